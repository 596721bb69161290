#include <vxf/ops/Blend.h>

#include "Dispatch.h"

#include <openvdb/tools/GridTransformer.h>

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
        throw UsageError(fmt::format("blend: grids '{}' ({}) and '{}' ({}) hold different value types", a.getName(),
            a.valueType(), b.getName(), b.valueType()));
    }
    if (a.transform() != b.transform()) {
        throw UsageError(fmt::format("blend: grids '{}' and '{}' have different transforms; resample B onto A (resample=true)",
            a.getName(), b.getName()));
    }
    const double scaleB = options.normalizeB && maxMagnitude(b) > 0.0 ? 1.0 / maxMagnitude(b) : 1.0;
    detail::dispatch(a, "blend", [&](auto& ga) {
        using GridT = std::decay_t<decltype(ga)>;
        using ValueT = typename GridT::ValueType;
        auto other = static_cast<const GridT&>(b).deepCopy();
        const BlendMode mode = options.mode;
        const double w = options.weight;
        const bool clamp = options.clampNegatives;
        ga.tree().combineExtended(other->tree(), [&](openvdb::CombineArgs<ValueT>& args) {
            ValueT r = args.a();
            const ValueT bv = args.b();
            for (int c = 0; c < detail::channels(r); ++c) {
                double x = detail::get(args.a(), c), y = detail::get(bv, c) * scaleB;
                if (clamp) {
                    x = std::max(0.0, x);
                    y = std::max(0.0, y);
                }
                double v = x;
                switch (mode) {
                case BlendMode::Add: v = x + y; break;
                case BlendMode::Subtract: v = x - y; break;
                case BlendMode::Multiply: v = x * y; break;
                case BlendMode::Darker: v = std::min(x, y); break;
                case BlendMode::Lighter: v = std::max(x, y); break;
                case BlendMode::Mix: v = x * (1.0 - w) + y * w; break;
                }
                detail::ref(r, c) = detail::finite(v);
            }
            args.setResult(r);
            args.setResultIsActive(args.aIsActive() || args.bIsActive());
        });
    });
}

} // namespace vxf::ops
