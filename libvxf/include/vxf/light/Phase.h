// vxf — the Henyey-Greenstein phase function and the similarity relation the transport uses.
#pragma once

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
/// these; the camera's march takes single scattering with the phase itself.
inline double reducedScatteringFactor(double g) { return 1.0 - g; }

} // namespace vxf
