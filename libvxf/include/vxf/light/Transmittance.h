// vxf — Beer-Lambert transmittance through the medium.
#pragma once

#include <vxf/light/Medium.h>

#include <algorithm>
#include <cmath>

namespace vxf {

struct MarchOptions
{
    double step = 0.5;    ///< march step in voxels (σt is taken constant over each step)
    double cutoff = 1e-4; ///< below this transmittance (every channel) a march stops and returns 0
};

/// Index-space box every march is clipped to: the medium's active bounds plus one voxel
/// (trilinear lookups reach that far). Empty when there is no medium.
openvdb::BBoxd marchBounds(const Medium& medium);

/// Clip the ray origin + t·direction to @a box, narrowing [t0, t1] (slab method);
/// false when nothing of the interval is inside.
bool clipRay(const openvdb::BBoxd& box, const openvdb::Vec3d& origin, const openvdb::Vec3d& direction, double& t0, double& t1);

/// ∫_0^h e^{−σt s} ds = (1 − e^{−σt h})/σt for one march step of world length @a h, exact for
/// any σt ≥ 0 (series form as σt·h → 0; never divides by zero). Negative σt counts as 0.
inline double stepIntegral(double sigmaT, double h)
{
    const double s = sigmaT > 0.0 ? sigmaT : 0.0;
    const double od = s * h;
    return od > 1e-8 ? -std::expm1(-od) / s : h * (1.0 - 0.5 * od);
}

/// The part [@a lo, @a hi] of the march step [@a ta, @a tb] inside the medium's surface, from
/// the signed distances @a sa, @a sb at its ends (linear between them, so a step of at most a
/// voxel meets the zero crossing of the trilinear level set to second order); false when the
/// step lies outside. Without a surface (distances −1) the whole step is inside.
inline bool insidePart(double ta, double sa, double tb, double sb, double& lo, double& hi)
{
    lo = ta;
    hi = tb;
    if (sa >= 0.0 && sb >= 0.0) return false;
    if (sa > 0.0) lo = ta + (tb - ta) * sa / (sa - sb);
    else if (sb > 0.0) hi = ta + (tb - ta) * sa / (sa - sb);
    return hi > lo;
}

/// One march step's part inside the medium's surface: its midpoint (index space), its length
/// (voxels) and Medium::Sampler::interiorScale there.
struct InsideStep
{
    openvdb::Vec3d midpoint{0.0};
    double length = 0.0;
    double interior = 1.0;
};

/// The equal steps of @a h voxels along origin + t·direction from t = @a t0, each clipped to the
/// surface by insidePart (one signed-distance lookup per step end; interiorScale skipped deep
/// inside). Without a surface every step is whole, with interior scale 1.
class InsideSteps
{
public:
    InsideSteps(Medium::Sampler& sampler, const openvdb::Vec3d& origin, const openvdb::Vec3d& direction, double t0, double h)
        : mSampler(sampler), mOrigin(origin), mDirection(direction), mT(t0), mH(h)
        , mDistance(sampler.signedDistance(origin + direction * t0))
    {
    }

    /// Advance one step; false when it lies outside the surface (@a step is then unchanged).
    bool next(InsideStep& step)
    {
        const double ta = mT, sa = mDistance;
        mT += mH;
        mDistance = mSampler.signedDistance(mOrigin + mDirection * mT);
        double lo, hi;
        if (!insidePart(ta, sa, mT, mDistance, lo, hi)) return false;
        step.midpoint = mOrigin + mDirection * (0.5 * (lo + hi));
        step.length = hi - lo;
        // The midpoint lies within h/2 of a step end, and signed distances are 1-Lipschitz.
        step.interior = mSampler.interiorScale(step.midpoint, std::max(sa, mDistance) + 0.5 * mH);
        return true;
    }

private:
    Medium::Sampler& mSampler;
    openvdb::Vec3d mOrigin, mDirection;
    double mT, mH, mDistance;
};

/// T(a, b) = exp(−∫ σt ds) on the segment from @a fromIjk to @a toIjk (index space),
/// per channel. Only the medium counts: σt is 0 outside it, so a segment may leave and
/// re-enter a concave mesh. Midpoint rule over equal steps of at most options.step voxels;
/// negative σt (artist grids) counts as 0, so 0 ≤ T ≤ 1 always. The segment is clipped to
/// the medium's bounds first, so empty space costs nothing.
openvdb::Vec3d transmittance(Medium::Sampler& sampler, const Medium& medium, const openvdb::Vec3d& fromIjk,
    const openvdb::Vec3d& toIjk, const MarchOptions& options);

/// T from @a fromIjk along the index-space direction @a direction (any length > 0) until the
/// ray leaves the medium's bounds (light arriving from outside, e.g. directional or sky).
openvdb::Vec3d transmittanceToBoundary(Medium::Sampler& sampler, const Medium& medium, const openvdb::Vec3d& fromIjk,
    const openvdb::Vec3d& direction, const MarchOptions& options);

} // namespace vxf
