// vxf — reading and writing voxel sets as multi-grid OpenVDB files.
#pragma once

#include <vxf/core/MemoryBudget.h>
#include <vxf/core/VoxelSet.h>

#include <cstdint>
#include <functional>
#include <set>
#include <string>
#include <vector>

namespace vxf {

struct VoxelSetWriteOptions
{
    bool half = false; ///< store float and Vec3f grids as 16-bit halves (lossy)
    bool compress = true; ///< Blosc compression (+ active-mask compression, always on)
};

struct VoxelSetReadOptions
{
    /// Read grids whose data do not match the checksum vxf wrote with them (a file damaged on
    /// disk) instead of throwing; their names go to @a damaged when given.
    bool acceptDamaged = false;
    std::vector<std::string>* damaged = nullptr;
    /// Grids the file holds that are not voxel grids (point data, strings) are skipped; their
    /// "NAME (TYPE)" go here when given.
    std::vector<std::string>* skipped = nullptr;
    /// Only the grids whose names this accepts are read (empty: every grid); the others' data
    /// are skipped on disk, not read and dropped. A stage that needs a grid only when it
    /// writes reads it then (readGridsInto), and holds its memory for none of the work.
    std::function<bool(const std::string& name)> wanted;
    /// Grids whose names this accepts must hold finite values: one NaN or infinite value is
    /// refused, naming the file, the grid, how many there are and the first voxel. For the
    /// light a stage carries through its sums, where one such voxel spreads downwind to every
    /// voxel (a scatter_source with a few NaN made a scatter of zeros, written as if solved).
    std::function<bool(const std::string& name)> finite;
};

/// Read every voxel grid and the file metadata of the .vdb at @a path, every size the file
/// declares checked before it is used (io/src/VdbArchiveReader.h: no file makes the reader
/// write outside its buffers or allocate more than the file can describe). The set's transform is
/// that of the first grid with a vxf role (else the first grid); grids of other types or
/// transforms are kept as they are. Throws vxf::Error naming the file when it is missing,
/// not an OpenVDB file, or damaged: a grid vxf wrote carries a checksum of its data
/// ("vxf:checksum", io/GridChecksum.h) and one that no longer matches is named (files of other
/// tools carry none and read as they are).
VoxelSet readVoxelSet(const std::string& path);
VoxelSet readVoxelSet(const std::string& path, const VoxelSetReadOptions& options);

/// The grids named @a names of the .vdb at @a path (those it holds; read as readVoxelSet does,
/// with @a options but for `wanted`)
/// put into @a set, replacing grids of the same names.
void readGridsInto(VoxelSet& set, const std::string& path, const std::vector<std::string>& names, const VoxelSetReadOptions& options = {});

/// A set of the grids named @a names of the .vdb at @a path (those it holds) and its file
/// metadata; the others' data stay on disk (a DCC file's velocities beside the density a scene
/// object names); read with @a options but for `wanted`.
VoxelSet readGrids(const std::string& path, const std::vector<std::string>& names, const VoxelSetReadOptions& options = {});

/// The active voxels the .vdb at @a path declares for its grid @a grid (`file_voxel_count`, which
/// OpenVDB writes with every grid), its data not read: what a stage's memory estimate needs
/// before it reads the file. 0 where the file holds no such grid or declares no count.
std::uint64_t declaredVoxels(const std::string& path, const std::string& grid);

/// The footprints (MemoryBudget.h) the .vdb at @a path declares for those of its grids named in
/// @a names (`file_mem_bytes` and `file_bbox_min`/`max`, which OpenVDB writes with every grid),
/// their data not read: what the render's estimate counts before it reads them. A grid declaring
/// no size is left out.
std::vector<GridFootprint> declaredFootprints(const std::string& path, const std::set<std::string>& names);

/// The names of the voxel grids of the .vdb at @a path, in the file's order (no grid's data read):
/// for a message naming what a file holds when a grid asked for is not there.
std::vector<std::string> voxelGridNames(const std::string& path);

/// Write @a set to @a path atomically (temporary file + rename): the grids in order, with
/// "vxf:units" grid metadata filled in from their roles, "vxf:checksum" of each grid's data as
/// written (halves when @a options.half), and the file metadata of the set,
/// stamped with this vxf version. The caller's grids are not modified.
void writeVoxelSet(const std::string& path, const VoxelSet& set, const VoxelSetWriteOptions& options = {});

} // namespace vxf
