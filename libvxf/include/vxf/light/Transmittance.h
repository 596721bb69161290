// vxf — Beer-Lambert transmittance through the medium.
#pragma once

#include <vxf/light/Medium.h>

namespace vxf {

struct MarchOptions
{
    double step = 0.5;    ///< march step in voxels (σt is taken constant over each step)
    double cutoff = 1e-4; ///< below this transmittance (every channel) a march stops and returns 0
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
