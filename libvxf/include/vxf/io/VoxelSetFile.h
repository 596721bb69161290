// vxf — reading and writing voxel sets as multi-grid OpenVDB files.
#pragma once

#include <vxf/core/VoxelSet.h>

#include <string>

namespace vxf {

struct VoxelSetWriteOptions
{
    bool half = false;     ///< store float and Vec3f grids as 16-bit halves (lossy)
    bool compress = true;  ///< Blosc compression (+ active-mask compression, always on)
};

/// Read every grid and the file metadata of the .vdb at @a path. The set's transform is
/// that of the first grid with a vxf role (else the first grid); grids of other types or
/// transforms are kept as they are. Throws vxf::Error naming the file when it is missing,
/// not an OpenVDB file, or damaged.
VoxelSet readVoxelSet(const std::string& path);

/// Write @a set to @a path atomically (temporary file + rename): the grids in order, with
/// "vxf:units" grid metadata filled in from their roles and the file metadata of the set,
/// stamped with this vxf version. The caller's grids are not modified.
void writeVoxelSet(const std::string& path, const VoxelSet& set, const VoxelSetWriteOptions& options = {});

} // namespace vxf
