// vxf — blend grid B into grid A.
#pragma once

#include <openvdb/openvdb.h>

namespace vxf::ops {

enum class BlendMode { Add, Subtract, Multiply, Darker, Lighter, Mix };

struct BlendOptions
{
    BlendMode mode = BlendMode::Add;
    double weight = 0.5; ///< mix: A·(1−w) + B·w
    bool clampNegatives = false; ///< clamp A and B to ≥ 0 first
    bool normalizeB = false; ///< divide B by its largest |value| first (B in [−1, 1])
};

/// A ← A ∘ B per voxel and channel: add, subtract (A − B), multiply, darker (min), lighter
/// (max) or mix. Both float or both Vec3f, on the same transform (resampleLike() first
/// otherwise). Topology: A's active values afterwards are the union of A's and B's (A's
/// tiles become leaves where B has leaves; tiles stay tiles elsewhere); where one side is
/// inactive its stored inactive value (the background, 0 for vxf's grids) stands in, so
/// multiply gives 0 there. Inactive values and the background of A are unchanged. Results
/// are clamped to the finite float range. B is not modified. Parallel over A's leaves.
/// Throws vxf::UsageError naming the grids otherwise.
void blend(openvdb::GridBase& a, const openvdb::GridBase& b, const BlendOptions& options);

/// A copy of @a grid resampled (trilinear) onto @a like's transform, as Houdini's VDB Combine
/// does when asked; float and Vec3f grids.
openvdb::GridBase::Ptr resampleLike(const openvdb::GridBase& grid, const openvdb::GridBase& like);

/// The largest |value| (over channels) among @a grid's active values; 0 when none.
double maxMagnitude(const openvdb::GridBase& grid);

} // namespace vxf::ops
