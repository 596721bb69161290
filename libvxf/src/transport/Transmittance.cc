#include <vxf/transport/Transmittance.h>

#include <vxf/transport/UniformBricks.h>

#include <vxf/core/RayScene.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vxf {

openvdb::BBoxd marchBounds(const Medium& medium)
{
    const openvdb::CoordBBox& b = medium.activeBounds();
    if (b.empty()) return openvdb::BBoxd(); // empty
    return openvdb::BBoxd(b.min().asVec3d() - openvdb::Vec3d(1.0), b.max().asVec3d() + openvdb::Vec3d(1.0));
}

bool clipRay(const openvdb::BBoxd& box, const openvdb::Vec3d& origin, const openvdb::Vec3d& direction, double& t0, double& t1)
{
    for (int a = 0; a < 3; ++a) {
        if (direction[a] == 0.0) {
            if (origin[a] < box.min()[a] || origin[a] > box.max()[a]) return false;
            continue;
        }
        const double inv = 1.0 / direction[a];
        double near = (box.min()[a] - origin[a]) * inv, far = (box.max()[a] - origin[a]) * inv;
        if (near > far) std::swap(near, far);
        t0 = std::max(t0, near);
        t1 = std::min(t1, far);
    }
    return t0 < t1;
}

namespace {

/// The number of whole steps of @a h voxels from @a p along @a unit that lie in the uniform
/// region holding @a p (at most @a most; 0 for fewer than two, or no region), their optical
/// depth added to @a tau as the steps would add it one by one.
int uniformSteps(const UniformBricks& uniform, const openvdb::Vec3d& p, const openvdb::Vec3d& unit, double h, int most, openvdb::Vec3d& tau,
    const Medium& medium)
{
    float density = 0.0f;
    const int count = uniform.stepsWithin(p, unit, h, most, density);
    if (count == 0) return 0;
    const openvdb::Vec3d sigmaT = medium.material().sigmaT() * double(density);
    const double length = count * h * medium.voxelSize();
    for (int c = 0; c < 3; ++c) tau[c] += std::max(0.0, sigmaT[c]) * length;
    return count;
}

openvdb::Vec3d march(Medium::Sampler& sampler, const Medium& medium, const openvdb::Vec3d& origin, const openvdb::Vec3d& unit, double t0,
    double t1, const MarchOptions& options, const MarchHandOff* handOff = nullptr)
{
    if (medium.activeBounds().empty() || !clipRay(marchBounds(medium), origin, unit, t0, t1)) return openvdb::Vec3d(1.0);
    const double length = t1 - t0;
    const int steps = std::max(1, int(std::ceil(length / std::max(options.step, 1e-3))));
    const double h = length / steps;
    const double tauCutoff = -std::log(std::max(options.cutoff, std::numeric_limits<double>::min()));
    // Beer-Lambert with σt constant over each step: τ += σt·h, T = exp(−τ).
    // Only the part of each step inside the surface holds medium (sharp boundary).
    openvdb::Vec3d tau(0.0);
    InsideSteps inside(sampler, origin, unit, t0, h);
    InsideStep step;
    const UniformBricks* uniform = medium.uniformBricks();
    double nextHandOff = t0 + 1.0;
    for (int i = 0; i < steps; ++i) {
        if (handOff && inside.t() >= nextHandOff) {
            nextHandOff = inside.t() + 1.0;
            openvdb::Vec3f depth;
            if ((*handOff)(origin + unit * inside.t(), inside.distance(), depth)) {
                for (int c = 0; c < 3; ++c) tau[c] += std::max(0.0, double(depth[c]));
                break;
            }
        }
        // Through a uniform region all the steps that lie in it at once (the same sum).
        const int alike = uniform ? uniformSteps(*uniform, origin + unit * inside.t(), unit, h, steps - i, tau, medium) : 0;
        if (alike > 0) {
            inside.skip(alike);
            i += alike - 1;
            if (std::min({tau[0], tau[1], tau[2]}) > tauCutoff) return openvdb::Vec3d(0.0);
            continue;
        }
        if (!inside.next(step)) continue;
        const openvdb::Vec3d sigmaT = sampler.sigmaT(step.midpoint) * step.interior;
        const double hWorld = step.length * medium.voxelSize();
        for (int c = 0; c < 3; ++c) tau[c] += std::max(0.0, sigmaT[c]) * hWorld;
        if (std::min({tau[0], tau[1], tau[2]}) > tauCutoff) return openvdb::Vec3d(0.0);
    }
    return openvdb::Vec3d(std::exp(-tau[0]), std::exp(-tau[1]), std::exp(-tau[2]));
}

} // namespace

openvdb::Vec3d transmittance(
    Medium::Sampler& sampler, const Medium& medium, const openvdb::Vec3d& fromIjk, const openvdb::Vec3d& toIjk, const MarchOptions& options)
{
    return transmittance(sampler, medium, fromIjk, toIjk, options, MarchHandOff());
}

openvdb::Vec3d transmittance(Medium::Sampler& sampler, const Medium& medium, const openvdb::Vec3d& fromIjk, const openvdb::Vec3d& toIjk,
    const MarchOptions& options, const MarchHandOff& handOff)
{
    const openvdb::Vec3d d = toIjk - fromIjk;
    const double length = d.length();
    if (!(length > 0.0)) return openvdb::Vec3d(1.0);
    return march(sampler, medium, fromIjk, d / length, 0.0, length, options, handOff ? &handOff : nullptr);
}

openvdb::Vec3d transmittanceToBoundary(Medium::Sampler& sampler, const Medium& medium, const openvdb::Vec3d& fromIjk,
    const openvdb::Vec3d& direction, const MarchOptions& options)
{
    return transmittanceToBoundary(sampler, medium, fromIjk, direction, options, MarchHandOff());
}

openvdb::Vec3d transmittanceToBoundary(Medium::Sampler& sampler, const Medium& medium, const openvdb::Vec3d& fromIjk,
    const openvdb::Vec3d& direction, const MarchOptions& options, const MarchHandOff& handOff)
{
    const double length = direction.length();
    if (!(length > 0.0)) return openvdb::Vec3d(1.0);
    return march(
        sampler, medium, fromIjk, direction / length, 0.0, std::numeric_limits<double>::max(), options, handOff ? &handOff : nullptr);
}

double vacuumAhead(const RayScene& media, const openvdb::Vec3d& xWorld, const openvdb::Vec3d& direction, double margin, double far)
{
    const auto hit = media.intersect(xWorld, direction, 0.0, far);
    if (!hit) return std::numeric_limits<double>::infinity();
    return hit->backFace ? 0.0 : std::max(0.0, hit->distance - margin);
}

} // namespace vxf
