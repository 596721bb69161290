#include <vxf/ops/Diff.h>

#include <vxf/ops/Fill.h>

#include "Dispatch.h"
#include "Topology.h"

#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/Prune.h>
#include <openvdb/tree/LeafManager.h>

namespace vxf::ops {

openvdb::GridBase::Ptr difference(const openvdb::GridBase& a, const openvdb::GridBase& b, double tolerance)
{
    if (a.valueType() != b.valueType() || a.transform() != b.transform()) {
        throw UsageError(fmt::format("diff: grids '{}' and '{}' must hold the same value type on one transform", a.getName(), b.getName()));
    }
    return detail::dispatch(a, "diff", [&](const auto& ga) -> openvdb::GridBase::Ptr {
        using GridT = std::decay_t<decltype(ga)>;
        using ValueT = typename GridT::ValueType;
        const GridT& gb = static_cast<const GridT&>(b);
        auto d = GridT::create(openvdb::zeroVal<ValueT>());
        d->setTransform(ga.transform().copy());
        d->setName(ga.getName() + "_diff");
        // Candidates: where either is active, split so that A and B are uniform under each tile.
        auto& tree = d->tree();
        tree.topologyUnion(ga.tree());
        tree.topologyUnion(gb.tree());
        detail::splitTilesWhereVaries(tree, ga.tree());
        detail::splitTilesWhereVaries(tree, gb.tree());
        const auto compare = [tolerance](bool onA, const ValueT& x, bool onB, const ValueT& y, ValueT& delta) {
            delta = y - x;
            bool differs = onA != onB;
            for (int ch = 0; ch < detail::channels(delta); ++ch) differs = differs || std::abs(detail::get(delta, ch)) > tolerance;
            return differs;
        };
        openvdb::tree::LeafManager<typename GridT::TreeType> leaves(tree);
        leaves.foreach ([&](typename GridT::TreeType::LeafNodeType& leaf, std::size_t) {
            auto va = ga.getConstAccessor();
            auto vb = gb.getConstAccessor();
            for (auto on = leaf.beginValueOn(); on; ++on) {
                ValueT x, y, delta;
                const bool onA = va.probeValue(on.getCoord(), x), onB = vb.probeValue(on.getCoord(), y);
                if (compare(onA, x, onB, y, delta)) {
                    on.setValue(delta);
                } else {
                    on.setValueOff();
                }
            }
        });
        auto va = ga.getConstAccessor();
        auto vb = gb.getConstAccessor();
        auto tiles = tree.beginValueOn();
        tiles.setMaxDepth(GridT::TreeType::RootNodeType::LEVEL - 1);
        for (; tiles; ++tiles) {
            ValueT x, y, delta;
            const bool onA = va.probeValue(tiles.getCoord(), x), onB = vb.probeValue(tiles.getCoord(), y);
            if (compare(onA, x, onB, y, delta)) {
                tiles.setValue(delta);
            } else {
                tiles.setValueOff();
            }
        }
        openvdb::tools::pruneInactive(tree);
        return d;
    });
}

void applyDifference(openvdb::GridBase& a, const openvdb::GridBase& d)
{
    if (a.valueType() != d.valueType() || a.transform() != d.transform()) {
        throw UsageError(
            fmt::format("apply_diff: grids '{}' and '{}' must hold the same value type on one transform", a.getName(), d.getName()));
    }
    detail::dispatch(a, "apply_diff", [&](auto& ga) {
        using GridT = std::decay_t<decltype(ga)>;
        const GridT& gd = static_cast<const GridT&>(d);
        auto out = ga.getAccessor();
        for (auto it = gd.cbeginValueOn(); it; ++it) {
            openvdb::CoordBBox box;
            it.getBoundingBox(box);
            for (auto c = box.begin(); c; ++c) out.setValueOn(*c, out.getValue(*c) + *it);
        }
    });
}

void applyDifferenceSmoothed(openvdb::GridBase& a, const openvdb::GridBase& d, int radius, Interrupter* interrupter)
{
    applyDifference(a, d);
    if (radius < 1) return;
    auto edge = openvdb::BoolGrid::create(false);
    edge->setTransform(a.transform().copy());
    edge->tree().topologyUnion(*detail::activeTopology(d));
    openvdb::MaskTree edit;
    edit.topologyUnion(edge->tree());
    openvdb::tools::dilateActiveValues(edge->tree(), radius, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::EXPAND_TILES);
    edge->tree().topologyDifference(edit);
    // Recompute only the ring around the edit that A already has values for.
    edge->tree().topologyIntersection(*detail::activeTopology(a));
    FillOptions options;
    options.region = edge.get();
    options.selection = edge.get();
    fill(a, options, interrupter);
}

} // namespace vxf::ops
