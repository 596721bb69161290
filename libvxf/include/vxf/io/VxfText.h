// vxf — the text VXF format of the thesis (specified in schemas/vxf-text.md).
#pragma once

#include <vxf/core/Interrupter.h>
#include <vxf/core/VoxelSet.h>

#include <string>
#include <vector>

namespace vxf {

/// File metadata recording the header of the text file a voxel set came from, so that
/// writing it back as text reproduces the same size, min and max exactly.
inline constexpr const char* kTextSizeMetaKey = "vxf:text_size";
inline constexpr const char* kTextMinMetaKey = "vxf:text_min";
inline constexpr const char* kTextMaxMetaKey = "vxf:text_max";

/// Read a text VXF file, streaming: memory grows with the grids built, not with the text.
/// Each declared column group becomes a grid (default: `color`, Vec3f); the voxel's active
/// flag sets its active state in every grid; level-set grids get their inside sign back by
/// signed flood fill, and uniform leaves are pruned to tiles. Voxel (i, j, k) of the text
/// has its centre at min + voxelsize·(i + ½, j + ½, k + ½). Where min lies on the voxel corners
/// of a transform that only scales (min/voxelsize + ½ integral to within 1e-6, within 2¹⁶
/// voxels of the origin, as vdb2vxf writes vxf's grids), that is the grids' transform and text
/// voxel (i, j, k) is VDB voxel (i, j, k) + round(min/voxelsize + ½): a grid comes back at its
/// own index coordinates. Otherwise the transform is translated to put voxel (0, 0, 0) there.
/// Throws vxf::InputError "path:line:column: what was expected" on any malformed input.
VoxelSet readVxfText(const std::string& path, Interrupter* interrupter = nullptr);

struct VxfWriteOptions
{
    /// Grids to write, as columns in this order; empty: every float, Vec3f and bool grid
    /// sharing the set's transform, in file order.
    std::vector<std::string> grids;
};

/// Write @a set as text VXF to @a path, atomically, streaming. Writes every voxel active in
/// any chosen grid (active tiles expanded) and every inactive voxel stored in a leaf whose
/// value differs from the background; inactive tiles are not written (they are restored on
/// reading: background, or the inside sign of a level set). Floats are printed in their
/// shortest round-trip form, so text → vdb → text → vdb is lossless. Returns warnings
/// (e.g. grids skipped or with different topologies). Throws vxf::Error on a NaN or
/// infinite value, a non-cubic-voxel transform or a grid that cannot be a column.
std::vector<std::string> writeVxfText(
    const std::string& path, const VoxelSet& set, const VxfWriteOptions& options = {}, Interrupter* interrupter = nullptr);

} // namespace vxf
