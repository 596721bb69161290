// vxf — the Henyey-Greenstein phase function and the scalings the transport takes it by.
#pragma once

#include <openvdb/math/Vec3.h>

#include <cmath>
#include <vector>

namespace vxf {

/// The largest |g| a material may ask for: at |g| → 1 the phase is a delta, and the reduced
/// coefficients below carry the whole medium as transmitted light.
inline constexpr double kMaxPhaseG = 0.95;

/// Henyey-Greenstein phase function times 4π, at the cosine @a cosTheta between the light's
/// direction of travel before and after scattering (1: straight on):
/// 4π·p(θ) = (1 − g²) / (1 + g² − 2g·cosθ)^{3/2}. 1 for every θ at g = 0 (isotropic), so it
/// scales the isotropic σs·φ/4π; its mean over the sphere is 1 and its mean cosine g.
inline double henyeyGreenstein4Pi(double g, double cosTheta)
{
    if (g == 0.0) return 1.0;
    const double denominator = 1.0 + g * g - 2.0 * g * cosTheta; // ≥ (1 − |g|)² > 0
    return (1.0 - g * g) / (denominator * std::sqrt(denominator));
}

/// The share of σs that scatters light out of its direction under the similarity relation of
/// a phase of mean cosine @a g (the transport approximation, a delta-Eddington phase with an
/// isotropic rest): the forward part g·δ keeps light on its way, so transport with an isotropic
/// phase carries the same diffuse light in a medium of reduced coefficients σs' = (1 − g)·σs,
/// σt' = σa + σs' = σt − g·σs, σa unchanged (in an infinite medium the fluence σa alone sets is
/// the same; the diffusion coefficient 1/(3σt') is the transport-corrected one). Medium holds
/// Medium::isotropic() holds these, for the transport that carries no angular moment (the
/// gather kernel, passes kept per order; a backward phase throughout); the camera's march takes
/// single scattering with the phase itself.
inline double reducedScatteringFactor(double g) { return 1.0 - g; }

/// How many Legendre moments of the phase the transport carries (delta-M of this order).
inline constexpr int kRestOrders = 3;

/// How the transport takes a phase of mean cosine g: the share f of σs it keeps in the beam
/// (σs* = (1 − f)·σs, σt* = σt − f·σs) and the Legendre moments χ*_l (l = 1…kRestOrders) of the
/// rest, whose scattering the sweep solve and the camera's read take by RestPhase.
struct PhaseScaling
{
    double forward = 0.0; ///< f
    double rest[kRestOrders] = {0, 0, 0}; ///< χ*_1…χ*_3
    /// g* = χ*_1, the rest's mean cosine.
    double restG() const { return rest[0]; }
};

/// The transport's scaling (Medium::material()). A forward phase (g > 0) by delta-M of order 3
/// (Wiscombe 1977): f = g⁴, the Henyey-Greenstein phase's fourth Legendre moment, kept in the
/// beam, and the rest's moments χ*_l = (g^l − f)/(1 − f), exact for l ≤ 3 (g* = χ*_1 ≤ 0.73 at
/// g = 0.95); σt* − g*σs* = σt − g·σs, so deep in a thick medium the diffuse light is the
/// similarity relation's. On the smoke puff of docs/accuracy-notes.md (p, q, y) Mitsuba put the
/// multiple scattering of such a cut phase 7% below the true phase's (back-lit), against 12%
/// for f = g³, 23% for delta-Eddington (f = g²) and 47% for the similarity relation. A backward
/// phase has no forward peak to cut, and its first moment, one sweep behind in the solve,
/// alternates in sign and slowed the accelerated sweeps to a rate of 0.69 (g = −0.3, albedo
/// 0.999): it keeps the similarity relation, f = g (< 0: σs' > σs), χ* = 0.
inline PhaseScaling transportScaling(double g)
{
    PhaseScaling s;
    if (g <= 0.0) {
        s.forward = g;
        return s;
    }
    const double g2 = g * g;
    s.forward = g2 * g2;
    double gl = 1.0;
    for (int l = 0; l < kRestOrders; ++l) {
        gl *= g;
        s.rest[l] = (gl - s.forward) / (1.0 - s.forward);
    }
    return s;
}

/// The rest of the phase (PhaseScaling::rest, in float) as the sweeps and the camera's read
/// take it: the angular factor of light scattered toward unit ω of light whose mean direction
/// of travel is a (|a| = k ≤ 1), that light's angular shape taken as a Henyey-Greenstein lobe of
/// parameter k about â (exact for a collimated beam, k = 1, and for isotropic light, k = 0; its
/// first moment k·â in every case), whose moments k^l the rest scatters by its χ*_l:
/// 1 + Σ_l (2l + 1)·χ*_l·k^l·P_l(â·ω) = 1 + 3χ*_1·c + (5/2)χ*_2·(3c² − k²) + (7/2)χ*_3·(5c³ −
/// 3c·k²), c = a·ω, clamped at 0 (a strongly forward rest of a near-collimated beam dips below
/// it backward). Its mean over the sphere is 1, and over the sweep's directions too (opposite
/// pairs, isotropic second moments: SweepPass.h), clamp aside; its first moment χ1·a there with
/// QuadratureCorrection.
struct RestPhase
{
    float chi[kRestOrders] = {0.0f, 0.0f, 0.0f};

    RestPhase() = default;
    explicit RestPhase(const PhaseScaling& s)
    {
        for (int l = 0; l < kRestOrders; ++l) chi[l] = float(s.rest[l]);
    }
    float operator()(const openvdb::Vec3f& a, const openvdb::Vec3f& omega) const { return clamped(unclamped(a[0], a[1], a[2], omega)); }
    /// The same less β·ω (@a beta: QuadratureCorrection for ω).
    float operator()(const openvdb::Vec3f& a, const openvdb::Vec3f& omega, float betaDotOmega) const
    {
        return clamped(unclamped(a[0], a[1], a[2], omega) - betaDotOmega);
    }
    /// Before the clamp, at a = (@a x, @a y, @a z) (a.dot(ω) and a.lengthSqr() in their order).
    float unclamped(float x, float y, float z, const openvdb::Vec3f& omega) const
    {
        const float c = x * omega[0] + y * omega[1] + z * omega[2], k2 = x * x + y * y + z * z;
        return 1.0f + c * (3.0f * chi[0] + 3.5f * chi[2] * (5.0f * c * c - 3.0f * k2)) + 2.5f * chi[1] * (3.0f * c * c - k2);
    }
    static float clamped(float f) { return f > 0.0f ? f : 0.0f; }
};

/// On N directions ω_i in opposite pairs with isotropic second moments (the sweep's), RestPhase's
/// mean is 1 and its first moment Σ R·ω_i/N is χ1·a as on the sphere but for the cubic term, of
/// degree 4 with ω, which N directions do not integrate: it adds (7/2)χ3·(5/N·Σ_i ω_i(a·ω_i)³ −
/// k²·a). The β that takes that off (Σ (β·ω_i)ω_i/N = β/3): β = (21/2)·χ3·(5/N·Σ_i ω_i(a·ω_i)³ −
/// k²·a), leaving the mean as it is (Σ ω_i = 0). A sweep needs only β·ω for its own direction ω:
/// (21/2)·χ3·(5/N·Σ_i (ω·ω_i)(a·ω_i)³ − k²·a·ω), whose sum is a cubic form in a with 10
/// coefficients fixed by ω and the set: made once a direction, β·ω is then a few multiplies a
/// voxel, with no β held per voxel (12 bytes a voxel).
class QuadratureCorrection
{
public:
    QuadratureCorrection() = default;
    /// For direction @a omega of a set whose opposite pairs are @a pairFirsts (one of each:
    /// ω(a·ω)³ is the same for both; N twice their count). None (0) where the rest has no cubic
    /// term or there are no pairs.
    QuadratureCorrection(const RestPhase& rest, const openvdb::Vec3d& omega, const std::vector<openvdb::Vec3d>& pairFirsts)
        : mOmega(omega)
    {
        if (rest.chi[2] == 0.0f || pairFirsts.empty()) return;
        mScale = 10.5 * double(rest.chi[2]);
        double c[10] = {};
        for (const openvdb::Vec3d& w : pairFirsts) {
            // 5/N·Σ over all N directions = 5/(N/2)·Σ over one of each pair.
            const double t = omega.dot(w) * 5.0 / double(pairFirsts.size());
            const double x = w[0], y = w[1], z = w[2];
            // (a·w)³ expanded: the multinomial coefficients 1, 3, 6.
            const double m[10] = {x * x * x, 3 * x * x * y, 3 * x * x * z, 3 * x * y * y, 6 * x * y * z, 3 * x * z * z, y * y * y,
                3 * y * y * z, 3 * y * z * z, z * z * z};
            for (int i = 0; i < 10; ++i) c[i] += t * m[i];
        }
        for (int i = 0; i < 10; ++i) mCubic[i] = float(mScale * c[i]);
    }
    /// β·ω at mean direction @a a.
    float betaDotOmega(const openvdb::Vec3f& a) const { return none() ? 0.0f : betaDotOmega(a[0], a[1], a[2]); }
    /// Whether β is 0 (no cubic term, or no pairs).
    bool none() const { return mScale == 0.0; }
    /// β·ω at a = (@a x, @a y, @a z), β not none() (a.lengthSqr() and a.dot(ω) in their order).
    float betaDotOmega(float x, float y, float z) const
    {
        const float cubic =
            x * (x * (mCubic[0] * x + mCubic[1] * y + mCubic[2] * z) + y * (mCubic[3] * y + mCubic[4] * z) + mCubic[5] * z * z) +
            y * y * (mCubic[6] * y + mCubic[7] * z) + z * z * (mCubic[8] * y + mCubic[9] * z);
        const openvdb::Vec3f omega(mOmega);
        return cubic - float(mScale) * (x * x + y * y + z * z) * (x * omega[0] + y * omega[1] + z * omega[2]);
    }

private:
    openvdb::Vec3d mOmega{0.0};
    double mScale = 0.0;
    float mCubic[10] = {}; ///< (21/2)χ3·5/N·Σ_i (ω·ω_i)·(the monomial's coefficient in (a·ω_i)³)
};

/// RestPhase toward @a omega less @a beta's β·ω (null: none) at @a n mean directions held by
/// component (@a x, @a y, @a z), into @a out: the same values to the bit as RestPhase's
/// operator() a voxel at a time, in a loop the compiler vectorizes (a sweep with a phase made
/// them a voxel at a time, a fifth of its time: docs/accuracy-notes.md (as)).
inline void restFactors(const RestPhase& rest, const openvdb::Vec3f& omega, const QuadratureCorrection* beta, const float* __restrict x,
    const float* __restrict y, const float* __restrict z, int n, float* __restrict out)
{
    if (beta && !beta->none()) {
        for (int i = 0; i < n; ++i)
            out[i] = RestPhase::clamped(rest.unclamped(x[i], y[i], z[i], omega) - beta->betaDotOmega(x[i], y[i], z[i]));
    } else {
        for (int i = 0; i < n; ++i) out[i] = RestPhase::clamped(rest.unclamped(x[i], y[i], z[i], omega));
    }
}

/// The mean of a colour's channels: what one anisotropy vector stands for.
inline double greyOf(const openvdb::Vec3d& c) { return (c[0] + c[1] + c[2]) / 3.0; }

/// @a a shortened to length 1 when longer (a mean direction of travel is never longer).
inline openvdb::Vec3d clampedToUnit(const openvdb::Vec3d& a)
{
    const double length = a.length();
    return length > 1.0 ? a / length : a;
}

} // namespace vxf
