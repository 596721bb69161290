// vxf — blur_special: fill unset voxels from their neighbours, never touching the artist's.
#pragma once

#include <vxf/core/Interrupter.h>

#include <openvdb/openvdb.h>

namespace vxf::ops {

struct FillOptions
{
    /// Where values are wanted (its active voxels and tiles; e.g. `density`, the medium).
    const openvdb::GridBase* region = nullptr;
    /// Voxels to recompute even though they are set (null: only the unset ones).
    const openvdb::BoolGrid* selection = nullptr;
    int smoothing = 4; ///< Jacobi smoothing passes over the filled voxels after the flood
};

/// The thesis's blur_special. Fixed voxels: the active voxels of @a grid outside the
/// selection; they keep their values bit for bit. Free voxels: the region's voxels that are
/// not fixed. The free voxels are reached layer by layer from the fixed ones (6-neighbour
/// flood), each taking the mean of its already-known face neighbours, then smoothed by
/// @a smoothing passes of the same mean over known neighbours (fixed ones included, never
/// changed). Free voxels no fixed voxel reaches stay as they were. The filled voxels become
/// active; nothing outside the region is touched. Float and Vec3f grids on the region's
/// transform. Returns the number of voxels filled.
openvdb::Index64 fill(openvdb::GridBase& grid, const FillOptions& options, Interrupter* interrupter = nullptr);

} // namespace vxf::ops
