#include <vxf/ops/Channels.h>

#include <vxf/core/Error.h>

#include <fmt/format.h>
#include <openvdb/tree/LeafManager.h>

namespace vxf::ops {

std::array<openvdb::FloatGrid::Ptr, 3> splitChannels(const openvdb::Vec3SGrid& grid)
{
    std::array<openvdb::FloatGrid::Ptr, 3> out;
    for (int c = 0; c < 3; ++c) {
        auto g = openvdb::FloatGrid::create(grid.background()[c]);
        g->setTransform(grid.transform().copy());
        for (auto meta = grid.beginMeta(); meta != grid.endMeta(); ++meta) g->insertMeta(meta->first, *meta->second);
        g->setName(grid.getName() + "." + "xyz"[c]);
        g->tree().topologyUnion(grid.tree());
        // Leaf by leaf, straight from the source leaf's buffer; tiles take the tile's channel.
        openvdb::tree::LeafManager<openvdb::FloatTree> leaves(g->tree());
        leaves.foreach ([&grid, c](openvdb::FloatTree::LeafNodeType& leaf, std::size_t) {
            const auto* source = grid.tree().probeConstLeaf(leaf.origin());
            auto* values = leaf.buffer().data();
            for (auto on = leaf.getValueMask().beginOn(); on; ++on) {
                values[on.pos()] = source ? source->getValue(on.pos())[c] : grid.tree().getValue(leaf.offsetToGlobalCoord(on.pos()))[c];
            }
        });
        auto tiles = g->tree().beginValueOn();
        tiles.setMaxDepth(openvdb::FloatTree::RootNodeType::LEVEL - 1);
        for (; tiles; ++tiles) tiles.setValue(grid.tree().getValue(tiles.getCoord())[c]);
        out[std::size_t(c)] = g;
    }
    return out;
}

openvdb::Vec3SGrid::Ptr mergeChannels(
    const openvdb::FloatGrid& x, const openvdb::FloatGrid& y, const openvdb::FloatGrid& z, const std::string& name)
{
    if (x.transform() != y.transform() || x.transform() != z.transform()) {
        throw UsageError(fmt::format("merge: '{}', '{}' and '{}' must share one transform", x.getName(), y.getName(), z.getName()));
    }
    auto out = openvdb::Vec3SGrid::create(openvdb::Vec3f(x.background(), y.background(), z.background()));
    out->setTransform(x.transform().copy());
    out->setName(name);
    for (const auto* g : {&x, &y, &z}) out->tree().topologyUnion(g->tree());
    auto ax = x.getConstAccessor(), ay = y.getConstAccessor(), az = z.getConstAccessor();
    for (auto it = out->beginValueOn(); it; ++it) {
        const openvdb::Coord c = it.getCoord();
        it.setValue(openvdb::Vec3f(ax.getValue(c), ay.getValue(c), az.getValue(c)));
    }
    return out;
}

} // namespace vxf::ops
