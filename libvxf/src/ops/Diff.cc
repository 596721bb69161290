#include <vxf/ops/Diff.h>

#include <vxf/ops/Fill.h>

#include "Dispatch.h"

#include <openvdb/tools/Morphology.h>

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
        openvdb::MaskTree both;
        both.topologyUnion(ga.tree());
        both.topologyUnion(gb.tree());
        auto va = ga.getConstAccessor(), vb = gb.getConstAccessor();
        auto out = d->getAccessor();
        for (auto it = both.cbeginValueOn(); it; ++it) {
            openvdb::CoordBBox box;
            it.getBoundingBox(box);
            for (auto c = box.begin(); c; ++c) {
                ValueT x, y;
                const bool onA = va.probeValue(*c, x), onB = vb.probeValue(*c, y);
                bool differs = onA != onB;
                ValueT delta = y - x;
                for (int ch = 0; ch < detail::channels(delta); ++ch) differs = differs || std::abs(detail::get(delta, ch)) > tolerance;
                if (differs) out.setValueOn(*c, delta);
            }
        }
        return d;
    });
}

void applyDifference(openvdb::GridBase& a, const openvdb::GridBase& d)
{
    if (a.valueType() != d.valueType() || a.transform() != d.transform()) {
        throw UsageError(fmt::format("apply_diff: grids '{}' and '{}' must hold the same value type on one transform", a.getName(), d.getName()));
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
    d.apply<detail::TopologyGridTypes>([&](const auto& g) { edge->tree().topologyUnion(g.tree()); });
    openvdb::MaskTree edit;
    edit.topologyUnion(edge->tree());
    openvdb::tools::dilateActiveValues(edge->tree(), radius, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::EXPAND_TILES);
    edge->tree().topologyDifference(edit);
    // Recompute only the ring around the edit that A already has values for.
    a.apply<detail::TopologyGridTypes>([&](const auto& g) { edge->tree().topologyIntersection(g.tree()); });
    FillOptions options;
    options.region = edge.get();
    options.selection = edge.get();
    fill(a, options, interrupter);
}

} // namespace vxf::ops
