#include "Topology.h"

namespace vxf::ops::detail {
namespace {

/// Every grid type whose topology operators may read (not point grids).
using TopologyGridTypes = openvdb::NumericGridTypes::Append<openvdb::Vec3GridTypes>::Append<openvdb::BoolGrid, openvdb::MaskGrid>;

} // namespace

openvdb::MaskTree::Ptr activeTopology(const openvdb::GridBase& grid)
{
    auto mask = std::make_shared<openvdb::MaskTree>();
    grid.apply<TopologyGridTypes>([&](const auto& g) { mask->topologyUnion(g.tree()); });
    return mask;
}

void unionTopology(openvdb::GridBase& grid, const openvdb::MaskTree& mask)
{
    grid.apply<TopologyGridTypes>([&](auto& g) { g.tree().topologyUnion(mask); });
}

void subtractTopology(openvdb::GridBase& grid, const openvdb::MaskTree& mask)
{
    grid.apply<TopologyGridTypes>([&](auto& g) { g.tree().topologyDifference(mask); });
}

} // namespace vxf::ops::detail
