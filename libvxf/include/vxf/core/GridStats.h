// vxf — sparse-storage statistics of a grid (for summaries and `vxf info`).
#pragma once

#include <openvdb/Grid.h>

#include <cstdint>
#include <string>

namespace vxf {

struct GridStats
{
    openvdb::Index64 activeVoxels = 0; ///< active voxels, counting active tiles' voxels
    openvdb::Index64 leafNodes = 0;    ///< allocated 8^3 leaf nodes
    openvdb::Index64 activeTiles = 0;  ///< active tiles above the leaf level
    openvdb::Index64 memoryBytes = 0;  ///< in-core size of the tree
    openvdb::CoordBBox activeBBox;     ///< index-space bounds of the active values (may be empty)
};

/// Statistics of @a grid's tree; reads only, O(nodes).
GridStats gridStats(const openvdb::GridBase& grid);

/// "12.3 MiB"-style byte count.
std::string formatBytes(std::uint64_t bytes);

} // namespace vxf
