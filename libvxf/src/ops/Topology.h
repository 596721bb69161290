// Internal: the active topology of a grid of any (non-point) type, as a mask, and edits of a
// grid's topology by such a mask. Defined in one unit (Topology.cc): each of these instantiates
// OpenVDB's topology operations once per grid type, which cost seconds of compile time a call
// site; the operators include this header instead.
#pragma once

#include <openvdb/openvdb.h>

namespace vxf::ops::detail {

/// The active voxels and tiles of @a grid, any numeric, vector, bool or mask grid; empty for
/// other types (point grids).
openvdb::MaskTree::Ptr activeTopology(const openvdb::GridBase& grid);

/// @a grid's active set made its union with, or difference from, @a mask's; values keep
/// theirs, newly active ones take the background. Other types are left alone.
void unionTopology(openvdb::GridBase& grid, const openvdb::MaskTree& mask);
void subtractTopology(openvdb::GridBase& grid, const openvdb::MaskTree& mask);

} // namespace vxf::ops::detail
