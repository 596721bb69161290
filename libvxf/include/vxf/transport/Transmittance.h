// vxf — Beer-Lambert transmittance through the medium.
#pragma once

#include <vxf/transport/Medium.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>

namespace vxf {

struct MarchOptions
{
    double step = 0.5; ///< march step in voxels (σt is taken constant over each step)
    double cutoff = 1e-4; ///< below this transmittance (every channel) a march stops and returns 0
};

/// Index-space box every march is clipped to: the medium's active bounds plus one voxel
/// (trilinear lookups reach that far). Empty when there is no medium.
openvdb::BBoxd marchBounds(const Medium& medium);

/// Clip the ray origin + t·direction to @a box, narrowing [t0, t1] (slab method);
/// false when nothing of the interval is inside.
bool clipRay(const openvdb::BBoxd& box, const openvdb::Vec3d& origin, const openvdb::Vec3d& direction, double& t0, double& t1);

/// Weights of the emission J at a step's start, middle and end in ∫_0^h J(s)·e^{−σt s} ds: the
/// quadratic through the three values integrated exactly against the exponential (product
/// integration; Simpson's rule as σt·h → 0). Exact for J quadratic along the step; for light
/// falling off over a mean free path (J ∝ e^{−σt s}, h = 0.77 of it) it errs by 0.06% where J
/// at the midpoint alone errs by −7%. @a total is ∫_0^h e^{−σt s} ds, @a transmittance e^{−σt h}.
/// Negative σt counts as 0; finite for any σt ≥ 0 including +∞.
struct EmissionWeights
{
    double start = 0.0, middle = 0.0, end = 0.0, total = 0.0, transmittance = 1.0;
};

inline EmissionWeights emissionWeights(double sigmaT, double h)
{
    // m_n = ∫_0^1 u^n e^{−k u} du; the quadratic's Lagrange basis in u = s/h gives the weights.
    const double k = sigmaT > 0.0 ? sigmaT * h : 0.0;
    const double e = std::exp(-k);
    double m0 = 0.0, m1 = 0.0, m2 = 0.0;
    if (k < 0.5) { // series Σ_j (−k)^j / (j! (n + j + 1)): no cancellation near 0; 0.5^13/13! < 2e-14
        double term = 1.0;
        for (int j = 0; j < 13; ++j) {
            m0 += term / (j + 1);
            m1 += term / (j + 2);
            m2 += term / (j + 3);
            term *= -k / (j + 1);
        }
    } else {
        const double ek = e > 0.0 ? e * k : 0.0, ekk = e > 0.0 ? ek * k : 0.0;
        m0 = (1.0 - e) / k;
        m1 = (1.0 - e - ek) / (k * k);
        m2 = (2.0 - 2.0 * e - 2.0 * ek - ekk) / (k * k * k);
    }
    return {h * (m0 - 3.0 * m1 + 2.0 * m2), h * (4.0 * m1 - 4.0 * m2), h * (2.0 * m2 - m1), h * m0, e};
}

/// emissionWeights per channel of @a sigmaT, computed once where the channels are equal (grey media).
inline std::array<EmissionWeights, 3> emissionWeights(const openvdb::Vec3d& sigmaT, double h)
{
    std::array<EmissionWeights, 3> w;
    w[0] = emissionWeights(sigmaT[0], h);
    w[1] = sigmaT[1] == sigmaT[0] ? w[0] : emissionWeights(sigmaT[1], h);
    w[2] = sigmaT[2] == sigmaT[1] ? w[1] : emissionWeights(sigmaT[2], h);
    return w;
}

/// ∫_0^h J(s)·e^{−σt s} ds from J at the step's start, middle and end (emissionWeights), kept
/// between the smallest and largest of them times ∫ e^{−σt s} ds: where the quadratic
/// overshoots (J jumping within an optically thick step) the integral stays bounded and of J's sign.
inline double emissionIntegral(const EmissionWeights& w, double jStart, double jMiddle, double jEnd)
{
    const double v = w.start * jStart + w.middle * jMiddle + w.end * jEnd;
    const double lo = std::min({jStart, jMiddle, jEnd}) * w.total, hi = std::max({jStart, jMiddle, jEnd}) * w.total;
    return std::clamp(v, lo, hi);
}

/// One march step's part inside the medium's surface (index space): its ends and midpoint,
/// its length (voxels), Medium::Sampler::interiorScale at the midpoint, and an upper bound of
/// the signed distance over it (for interiorScale elsewhere on the step).
struct InsideStep
{
    openvdb::Vec3d start{0.0}, midpoint{0.0}, end{0.0};
    double length = 0.0;
    double interior = 1.0;
    double distanceBound = 0.0;
    bool joined = false; ///< it starts where the previous inside step ended (values there can be reused)
};

/// The equal steps of @a h voxels along origin + t·direction (unit, index space) from t = @a t0,
/// each clipped to the part inside the surface. Both ends of a step are looked up (the end
/// once, shared with the next step); where the surface may cut the step, the cut is found on
/// the level set itself (Medium::Sampler::signedDistance), not on the line between the ends:
/// a grazing ray's signed distance is a parabola whose chord the line shortens (0.1 voxel
/// under the silhouette of a sphere of 10 voxels, by 4 to 6% at 1-voxel steps, where the
/// crossings found on it give 0.1%), and a chord shorter than a step, between two ends
/// outside, was lost altogether. Signed distances are 1-Lipschitz, so a step whose
/// ends lie outside by sa + sb ≥ its length cannot dip inside and costs nothing more. Each
/// step keeps one contiguous inside part (a gap narrower than the step, between two parts
/// inside, counts as medium). Without a surface every step is whole, with interior scale 1.
class InsideSteps
{
public:
    InsideSteps(Medium::Sampler& sampler, const openvdb::Vec3d& origin, const openvdb::Vec3d& direction, double t0, double h)
        : mSampler(sampler)
        , mOrigin(origin)
        , mDirection(direction)
        , mT(t0)
        , mH(h)
        , mDistance(distanceAt(t0))
    {
    }

    /// Advance one step; false when it lies outside the surface (@a step is then unchanged).
    bool next(InsideStep& step)
    {
        const double ta = mT, sa = mDistance;
        const bool previousReachedEnd = mReachedEnd;
        mReachedEnd = false;
        mT += mH;
        mDistance = distanceAt(mT);
        double lo, hi;
        if (!insidePart(ta, sa, mT, mDistance, lo, hi)) return false;
        step.start = mOrigin + mDirection * lo;
        step.end = mOrigin + mDirection * hi;
        step.midpoint = 0.5 * (step.start + step.end);
        step.length = hi - lo;
        step.joined = previousReachedEnd && lo == ta;
        mReachedEnd = hi == mT;
        // Every point lies within h/2 of a step end, and signed distances are 1-Lipschitz.
        step.distanceBound = std::max(sa, mDistance) + 0.5 * mH;
        step.interior = mSampler.interiorScale(step.midpoint, step.distanceBound);
        return true;
    }

    /// Where the next step starts (the ray's parameter).
    double t() const { return mT; }
    /// The signed distance there (voxels; without a surface, as Medium::Sampler gives it).
    double distance() const { return mDistance; }

    /// Advance @a count whole steps without looking at them: for a caller that knows them all
    /// alike (UniformBricks: uniform inside the surface, or wholly outside) and has counted them.
    /// The ray's parameter moves as the steps would have moved it, a step at a time (the same
    /// sums to the bit: a march that skips reads the same points after as one that stepped).
    void skip(int count)
    {
        for (int k = 0; k < count; ++k) mT += mH;
        mDistance = distanceAt(mT);
        mReachedEnd = true;
    }

private:
    double distanceAt(double t) { return mSampler.signedDistance(mOrigin + mDirection * t); }

    /// The part [@a lo, @a hi] of the step [@a ta, @a tb] inside the surface, from the signed
    /// distances @a sa, @a sb at its ends; false when it lies outside.
    bool insidePart(double ta, double sa, double tb, double sb, double& lo, double& hi)
    {
        lo = ta;
        hi = tb;
        if (sa >= 0.0 && sb >= 0.0) {
            double tm, sm;
            if (!dipInside(ta, sa, tb, sb, kDipDepth, tm, sm)) return false;
            lo = crossing(ta, sa, tm, sm);
            hi = crossing(tm, sm, tb, sb);
        } else if (sa > 0.0) {
            lo = crossing(ta, sa, tb, sb);
        } else if (sb > 0.0) {
            hi = crossing(ta, sa, tb, sb);
        }
        // With boundary meshes: an end the level set holds inside but near the surface may lie
        // outside the meshes (a short chord under a silhouette, a grazing ray's crossing a step
        // away from the level set's): the part before their entry, or after their exit, is outside.
        // One ray serves both ends unless its first hit moved the start (then the end asks again past it).
        double t = 0.0;
        bool entering = false, hit = false, asked = false;
        if (lo == ta && sa > -Medium::kSnapWindow) {
            hit = mSampler.boundaryHit(mOrigin, mDirection, lo, hi, t, entering);
            asked = true;
            if (hit && entering) {
                lo = t;
                asked = false;
            }
        }
        if (hi == tb && sb > -Medium::kSnapWindow) {
            if (!asked) hit = mSampler.boundaryHit(mOrigin, mDirection, lo, hi, t, entering);
            if (hit && !entering) hi = t;
        }
        return hi > lo;
    }

    /// A point @a tm inside (@a sm < 0) of [@a ta, @a tb] whose ends lie outside: looked up
    /// where the two ends' Lipschitz cones meet (the deepest the surface can reach), then in the
    /// halves, @a depth levels down; false when none is found or none can exist.
    bool dipInside(double ta, double sa, double tb, double sb, int depth, double& tm, double& sm)
    {
        if (depth == 0 || sa + sb >= tb - ta) return false;
        tm = std::clamp(0.5 * (ta + tb + sa - sb), ta, tb);
        sm = distanceAt(tm);
        if (sm < 0.0) return true;
        const double tMiddle = tm, sMiddle = sm;
        return dipInside(ta, sa, tMiddle, sMiddle, depth - 1, tm, sm) || dipInside(tMiddle, sMiddle, tb, sb, depth - 1, tm, sm);
    }

    /// The zero of the signed distance between @a ta and @a tb, where it changes sign
    /// (@a sa, @a sb): regula falsi with the Illinois rule, from the secant's estimate.
    double crossing(double ta, double sa, double tb, double sb)
    {
        // Where the crossing may be placed on the meshes: within the step, or the step beyond
        // it on the outside (a grazing ray crosses the mesh up to ~1/cos further along than
        // the level set says; the neighbouring step there lies outside and counts nothing).
        const double lo = sa > 0.0 ? ta - mH : ta, hi = sb > 0.0 ? tb + mH : tb;
        double t = ta + (tb - ta) * sa / (sa - sb);
        int kept = 0; // the end kept by the last two iterations: −1 a, +1 b
        for (int k = 0; k < kCrossingIterations && tb - ta > kCrossingTolerance; ++k) {
            const double s = distanceAt(t);
            if (std::abs(s) < kCrossingTolerance) break;
            if ((s > 0.0) == (sa > 0.0)) {
                ta = t;
                sa = s;
                if (kept == +1) sb *= 0.5;
                kept = +1;
            } else {
                tb = t;
                sb = s;
                if (kept == -1) sa *= 0.5;
                kept = -1;
            }
            t = ta + (tb - ta) * sa / (sa - sb);
        }
        return mSampler.snapCrossing(mOrigin, mDirection, t, lo, hi, sa > 0.0);
    }

    static constexpr int kDipDepth = 3; ///< a chord down to an eighth of a step is found
    static constexpr int kCrossingIterations = 4;
    static constexpr double kCrossingTolerance = 1e-3; ///< voxels

    Medium::Sampler& mSampler;
    openvdb::Vec3d mOrigin, mDirection;
    double mT, mH, mDistance;
    bool mReachedEnd = false;
};

/// T(a, b) = exp(−∫ σt ds) on the segment from @a fromIjk to @a toIjk (index space),
/// per channel. Only the medium counts: σt is 0 outside it, so a segment may leave and
/// re-enter a concave mesh. Midpoint rule over equal steps of at most options.step voxels;
/// negative σt (artist grids) counts as 0, so 0 ≤ T ≤ 1 always. The segment is clipped to
/// the medium's bounds first, so empty space costs nothing.
openvdb::Vec3d transmittance(Medium::Sampler& sampler, const Medium& medium, const openvdb::Vec3d& fromIjk, const openvdb::Vec3d& toIjk,
    const MarchOptions& options);

/// T from @a fromIjk along the index-space direction @a direction (any length > 0) until the
/// ray leaves the medium's bounds (light arriving from outside, e.g. directional or sky).
openvdb::Vec3d transmittanceToBoundary(Medium::Sampler& sampler, const Medium& medium, const openvdb::Vec3d& fromIjk,
    const openvdb::Vec3d& direction, const MarchOptions& options);

/// Where a march may stop and take the optical depth of the rest of its way from elsewhere (a
/// sweep's, say): asked with the point reached (index space) and the signed distance there
/// (voxels) a voxel along the march and then at least a voxel apart (once after a uniform
/// region crossed at once); true with @a depth, the optical depth from there on.
using MarchHandOff = std::function<bool(const openvdb::Vec3d& pointIjk, double signedDistance, openvdb::Vec3f& depth)>;

/// transmittance from @a fromIjk to @a toIjk, handing the rest of the way to @a handOff where it takes it.
openvdb::Vec3d transmittance(Medium::Sampler& sampler, const Medium& medium, const openvdb::Vec3d& fromIjk, const openvdb::Vec3d& toIjk,
    const MarchOptions& options, const MarchHandOff& handOff);

/// transmittanceToBoundary, handing the rest of the way to @a handOff where it takes it.
openvdb::Vec3d transmittanceToBoundary(Medium::Sampler& sampler, const Medium& medium, const openvdb::Vec3d& fromIjk,
    const openvdb::Vec3d& direction, const MarchOptions& options, const MarchHandOff& handOff);

/// Voxels a march keeps before the medium's meshes where it skips the vacuum up to them
/// (vacuumAhead): the level set's surface lies within a few thousandths of a voxel of the
/// meshes', and the march then crosses it as it would have.
inline constexpr double kVacuumMargin = 2.0;

/// The vacuum a ray may skip before it meets the medium: from world point @a xWorld along the
/// unit world @a direction, up to @a far (world units), the first hit of @a media (the medium's
/// meshes; no medium lies outside them). +∞ when the ray meets none (it crosses no medium,
/// T = 1); the way to @a margin (world units) before a hit met from the front; 0 where that is
/// no way at all, or the hit is met from behind (the ray starts inside the meshes: all marched).
/// The light stage's grazing rim and the renderer's surface shadow rays leave the medium mostly
/// for good: the candle demo's render 6.6 → 5.0 s (12.8M of 14.8M shadow rays meet no wax), the
/// sky's rim at dim 256 0.25 s of 4.85 (docs/accuracy-notes.md (w)).
double vacuumAhead(const RayScene& media, const openvdb::Vec3d& xWorld, const openvdb::Vec3d& direction, double margin,
    double far = std::numeric_limits<double>::infinity());

} // namespace vxf
