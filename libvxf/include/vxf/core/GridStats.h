// vxf — sparse-storage statistics of a grid (for summaries and `vxf info`).
#pragma once

#include <vxf/core/MemoryBudget.h>

#include <openvdb/Grid.h>

#include <cstdint>
#include <string>

namespace vxf {

struct GridStats
{
    openvdb::Index64 activeVoxels = 0; ///< active voxels, counting active tiles' voxels
    openvdb::Index64 leafNodes = 0; ///< allocated 8^3 leaf nodes
    openvdb::Index64 activeTiles = 0; ///< active tiles above the leaf level
    openvdb::Index64 memoryBytes = 0; ///< in-core size of the tree
    openvdb::CoordBBox activeBBox; ///< index-space bounds of the active values (may be empty)
};

/// Statistics of @a grid's tree; reads only, O(nodes).
GridStats gridStats(const openvdb::GridBase& grid);

/// The bytes a value of OpenVDB's type @a valueType ("float", "vec3s", …) takes (4 where unknown).
std::size_t valueBytes(const std::string& valueType);
/// A grid's footprint (MemoryBudget.h) from its tree's @a bytes, its active @a box and its
/// values' size: what a file's metadata declares, or (the second) a grid in memory holds.
GridFootprint footprintOf(const std::string& name, double bytes, const openvdb::CoordBBox& box, std::size_t valueBytes);
GridFootprint footprintOf(const openvdb::GridBase& grid);

/// The range of a grid's active values (an active tile counting once per voxel it covers).
struct ValueRange
{
    int channels = 0; ///< 1 (float, double, int), 3 (vec3), 0: not a numeric grid, or no active value
    openvdb::Vec3d min{0.0}, max{0.0}, mean{0.0}; ///< per channel (only [0] for one channel)
    openvdb::Index64 nonFinite = 0; ///< active values that are NaN or infinite (left out of the range)
};

/// The range of @a grid's active values: float, double, int32, int64 and their vec3 grids;
/// other types (bool, points) have none. Reads only, O(active values).
ValueRange valueRange(const openvdb::GridBase& grid);

/// A grid's active values that are NaN or infinite (tiles counted once each, as OpenVDB's
/// tools::Diagnose counts them): how many, and the first of them in the tree's order.
struct NonFiniteValues
{
    openvdb::Index64 count = 0;
    openvdb::Coord first; ///< (a tile's first voxel)
};

/// @a grid's NaN or infinite active values (tools::Diagnose with tools::CheckFinite, in
/// parallel): float and double grids and their vec3 grids; other types have none.
NonFiniteValues nonFiniteValues(const openvdb::GridBase& grid);

/// "12.3 MiB"-style byte count.
std::string formatBytes(std::uint64_t bytes);

} // namespace vxf
