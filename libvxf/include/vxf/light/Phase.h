// vxf — the Henyey-Greenstein phase function and the scalings the transport takes it by.
#pragma once

#include <openvdb/math/Vec3.h>

#include <cmath>

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

/// How the transport takes a phase of mean cosine g: the share f of σs it keeps in the beam
/// (σs* = (1 − f)·σs, σt* = σt − f·σs) and the mean cosine g* of the rest, which the sweep
/// solve carries as a first angular moment, the source (σs*/4π)(φ + 3g*·F·ω).
struct PhaseScaling
{
    double forward = 0.0; ///< f
    double restG = 0.0;   ///< g*
};

/// The transport's scaling (Medium::material()). A forward phase (g > 0) by delta-Eddington:
/// f = g², the Henyey-Greenstein phase's second Legendre moment, and g* = (g − f)/(1 − f) =
/// g/(1 + g) (≤ 0.49 at g = 0.95); σt* − g*σs* = σt − g·σs, so deep in a thick medium the
/// diffuse light is the similarity relation's. On the smoke puff of docs/accuracy-notes.md (p)
/// Mitsuba put this scaling's multiple scattering 23% (back-lit) and 10% (front-lit) below the
/// true phase's, against 47% and 30% for the similarity relation. A backward phase has no
/// forward peak to cut, and its first moment, one sweep behind in the solve, alternates in sign
/// and slowed the accelerated sweeps to a rate of 0.69 (g = −0.3, albedo 0.999): it keeps the
/// similarity relation, f = g (< 0: σs' > σs), g* = 0.
inline PhaseScaling transportScaling(double g)
{
    if (g > 0.0) return {g * g, g / (1.0 + g)};
    return {g, 0.0};
}

/// The first angular moment the transport keeps for the rest's g* (≠ 0 only), as the mean
/// direction of travel a = F/φ of the light (world space, |a| ≤ 1, one vector for the three
/// channels: F and φ their means), so that a source emits J(ω) = J·(1 + 3g*·a·ω) toward ω:
/// the light stage's source J0 (its scattered share; a volume light's emission has none) and
/// the scattered fluence the solve writes, which the camera reads toward itself. Scaling a
/// fluence grid leaves its anisotropy as it is; a set with g = 0 has neither grid.
inline constexpr const char* kSourceAnisotropyGrid = "scatter_source_anisotropy";
inline constexpr const char* kScatterAnisotropyGrid = "scatter_anisotropy";

/// The mean of a colour's channels: what one anisotropy vector stands for.
inline double greyOf(const openvdb::Vec3d& c) { return (c[0] + c[1] + c[2]) / 3.0; }

/// @a a shortened to length 1 when longer (a mean direction of travel is never longer).
inline openvdb::Vec3d clampedToUnit(const openvdb::Vec3d& a)
{
    const double length = a.length();
    return length > 1.0 ? a / length : a;
}

} // namespace vxf
