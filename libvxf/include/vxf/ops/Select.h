// vxf — selections: which active voxels of a grid lie in a box, a sphere or a value range.
#pragma once

#include <openvdb/openvdb.h>

namespace vxf::ops {

/// The active voxels of @a grid (any type) whose centres lie in the world-space box, as a
/// bool `mask` grid on the grid's transform (active = selected). Active tiles are tested
/// voxel by voxel, and only their selected voxels enter the mask.
openvdb::BoolGrid::Ptr selectBox(const openvdb::GridBase& grid, const openvdb::BBoxd& worldBox);

/// Likewise for a world-space sphere.
openvdb::BoolGrid::Ptr selectSphere(const openvdb::GridBase& grid, const openvdb::Vec3d& centre, double radius);

/// The active voxels of a float or Vec3f grid whose every channel lies in [lo, hi].
openvdb::BoolGrid::Ptr selectRange(const openvdb::GridBase& grid, double lo, double hi);

/// Deactivate the voxels of @a a that are active in @a b (any types; values kept, inactive).
void removeActive(openvdb::GridBase& a, const openvdb::GridBase& b);

/// Activate the voxels of @a a that are inactive there and active in @a b; they keep the value
/// @a a held there (its background, for vxf's grids 0).
void includeActive(openvdb::GridBase& a, const openvdb::GridBase& b);

} // namespace vxf::ops
