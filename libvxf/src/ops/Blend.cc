#include <vxf/ops/Blend.h>

#include "Dispatch.h"

#include <openvdb/tools/GridTransformer.h>
#include <openvdb/tree/LeafManager.h>

namespace vxf::ops {

double maxMagnitude(const openvdb::GridBase& grid)
{
    return detail::dispatch(grid, "max", [](const auto& g) {
        double m = 0.0;
        for (auto it = g.cbeginValueOn(); it; ++it) {
            const auto v = *it;
            for (int c = 0; c < detail::channels(v); ++c) m = std::max(m, std::abs(double(detail::get(v, c))));
        }
        return m;
    });
}

openvdb::GridBase::Ptr resampleLike(const openvdb::GridBase& grid, const openvdb::GridBase& like)
{
    return detail::dispatch(grid, "resample", [&](const auto& g) -> openvdb::GridBase::Ptr {
        using GridT = std::decay_t<decltype(g)>;
        auto out = GridT::create(g.background());
        out->setName(g.getName());
        out->setTransform(like.transform().copy());
        out->setGridClass(g.getGridClass());
        openvdb::tools::resampleToMatch<openvdb::tools::BoxSampler>(g, *out);
        return out;
    });
}

void blend(openvdb::GridBase& a, const openvdb::GridBase& b, const BlendOptions& options)
{
    if (a.valueType() != b.valueType()) {
        throw UsageError(fmt::format(
            "blend: grids '{}' ({}) and '{}' ({}) hold different value types", a.getName(), a.valueType(), b.getName(), b.valueType()));
    }
    if (a.transform() != b.transform()) {
        throw UsageError(fmt::format(
            "blend: grids '{}' and '{}' have different transforms; resample B onto A (resample=true)", a.getName(), b.getName()));
    }
    const double scaleB = options.normalizeB && maxMagnitude(b) > 0.0 ? 1.0 / maxMagnitude(b) : 1.0;
    detail::dispatch(a, "blend", [&](auto& ga) {
        using GridT = std::decay_t<decltype(ga)>;
        using ValueT = typename GridT::ValueType;
        const GridT& gb = static_cast<const GridT&>(b);
        const BlendMode mode = options.mode;
        const double w = options.weight;
        const bool clamp = options.clampNegatives;
        const auto combine = [&](ValueT& x, const ValueT& y) {
            for (int c = 0; c < detail::channels(x); ++c) {
                double p = detail::get(x, c), q = detail::get(y, c) * scaleB;
                if (clamp) {
                    p = std::max(0.0, p);
                    q = std::max(0.0, q);
                }
                double v = p;
                switch (mode) {
                case BlendMode::Add: v = p + q; break;
                case BlendMode::Subtract: v = p - q; break;
                case BlendMode::Multiply: v = p * q; break;
                case BlendMode::Darker: v = std::min(p, q); break;
                case BlendMode::Lighter: v = std::max(p, q); break;
                case BlendMode::Mix: v = p * (1.0 - w) + q * w; break;
                }
                detail::ref(x, c) = detail::finite(v);
            }
        };
        // Active where either is: A's tiles become leaves where B has leaves, so every voxel
        // where B varies is a voxel of A; where one side was inactive its stored value (the
        // background) stands in.
        ga.tree().topologyUnion(gb.tree());
        using TreeT = typename GridT::TreeType;
        detail::splitTilesWhereVaries(ga.tree(), gb.tree());
        openvdb::tree::LeafManager<TreeT> leaves(ga.tree());
        leaves.foreach ([&](typename TreeT::LeafNodeType& leaf, std::size_t) {
            auto other = gb.getConstAccessor();
            auto* values = leaf.buffer().data();
            const typename TreeT::LeafNodeType* otherLeaf = other.probeConstLeaf(leaf.origin());
            for (auto on = leaf.getValueMask().beginOn(); on; ++on) {
                const ValueT y = otherLeaf ? otherLeaf->getValue(on.pos()) : other.getValue(leaf.offsetToGlobalCoord(on.pos()));
                combine(values[on.pos()], y);
            }
        });
        auto tiles = ga.tree().beginValueOn();
        tiles.setMaxDepth(TreeT::RootNodeType::LEVEL - 1);
        auto other = gb.getConstAccessor();
        for (; tiles; ++tiles) { // B is uniform over each (it has no leaves there)
            ValueT x = *tiles;
            combine(x, other.getValue(tiles.getCoord()));
            tiles.setValue(x);
        }
    });
}

} // namespace vxf::ops
