// vxf — Mitsuba's binary grid volume (.vol), so a path tracer sees the same medium.
#pragma once

#include <openvdb/openvdb.h>

#include <string>

namespace vxf {

struct MitsubaVolumeInfo
{
    openvdb::Coord resolution; ///< voxels along x, y, z
    int channels = 1; ///< 1 (float grid) or 3 (Vec3f grid)
    openvdb::BBoxd bounds; ///< world-space box the data spans (voxel cells, not centres)
};

/// Write a float or Vec3f grid as Mitsuba's .vol: 'VOL', version 3, encoding 1 (float32),
/// resolution x y z (int32), channels (int32), the bounding box (6 float32: min xyz, max xyz),
/// then the values, x fastest, then y, then z. The dense block covers the grid's active
/// bounding box grown by @a pad voxels each side (inactive voxels hold their value there, the
/// background for vxf's grids); its box spans the voxel cells, so a trilinear lookup at a
/// voxel centre (Mitsuba's (i + 0.5)/res convention) returns that voxel's value. The format
/// is dense by nature: the file holds resolution.x·y·z·channels floats, written slice by
/// slice (no dense copy in memory). Atomic. Throws vxf::UsageError for other grid types or an
/// empty grid.
MitsubaVolumeInfo writeMitsubaVolume(const std::string& path, const openvdb::GridBase& grid, int pad = 1);

} // namespace vxf
