#include <vxf/ops/Normalize.h>

#include "Dispatch.h"

#include <tbb/parallel_reduce.h>

#include <cmath>

namespace vxf::ops {

namespace {

float restore(float y, double scale, double offset) { return float(double(y) * scale + offset); }

/// (x − offset)/scale as a float that restore() maps back to x whenever one of its
/// neighbours does.
float forward(float x, double scale, double offset)
{
    const float y = detail::finite((double(x) - offset) / scale);
    if (restore(y, scale, offset) == x) return y;
    for (const float candidate : {std::nextafter(y, -INFINITY), std::nextafter(y, INFINITY)}) {
        if (restore(candidate, scale, offset) == x) return candidate;
    }
    return y;
}

} // namespace

void normalize(openvdb::GridBase& grid, const NormalizeOptions& options)
{
    detail::dispatch(grid, "normalize", [&](auto& g) {
        using GridT = std::decay_t<decltype(g)>;
        using ValueT = typename GridT::ValueType;
        // Range of the active values (every channel), in parallel over leaves, then the tiles.
        struct Range
        {
            double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
            void add(double x)
            {
                lo = std::min(lo, x);
                hi = std::max(hi, x);
            }
        };
        const bool clampFirst = options.clampNegatives;
        const auto addValue = [clampFirst](Range& r, const ValueT& v) {
            for (int c = 0; c < detail::channels(v); ++c) r.add(clampFirst ? std::max(0.0f, detail::get(v, c)) : detail::get(v, c));
        };
        openvdb::tree::LeafManager<const typename GridT::TreeType> leaves(g.tree());
        Range range = tbb::parallel_reduce(
            leaves.leafRange(), Range(),
            [&](const auto& leafRange, Range r) {
                for (auto leaf = leafRange.begin(); leaf; ++leaf) {
                    const auto* values = leaf->buffer().data();
                    for (auto on = leaf->getValueMask().beginOn(); on; ++on) addValue(r, values[on.pos()]);
                }
                return r;
            },
            [](Range a, const Range& b) {
                a.lo = std::min(a.lo, b.lo);
                a.hi = std::max(a.hi, b.hi);
                return a;
            });
        auto tiles = g.tree().cbeginValueOn();
        tiles.setMaxDepth(GridT::TreeType::RootNodeType::LEVEL - 1);
        for (; tiles; ++tiles) addValue(range, *tiles);
        const bool any = range.lo <= range.hi;
        const double lo = any ? range.lo : 0.0, hi = any ? range.hi : 0.0;
        const double offset = lo < 0.0 ? lo : 0.0;
        double scale = hi - offset > 0.0 ? hi - offset : 1.0;
        if (options.exact) scale = std::exp2(std::ceil(std::log2(scale))); // division by 2^k is exact
        const bool clamp = options.clampNegatives;
        detail::forEachActiveValue(g, [=](ValueT& v) {
            for (int c = 0; c < detail::channels(v); ++c) {
                float x = detail::get(v, c);
                if (clamp) x = std::max(0.0f, x);
                detail::ref(v, c) = forward(x, scale, offset);
            }
        });
        g.insertMeta(kNormalizeOffsetKey, openvdb::DoubleMetadata(offset));
        g.insertMeta(kNormalizeScaleKey, openvdb::DoubleMetadata(scale));
    });
}

void denormalize(openvdb::GridBase& grid)
{
    const auto offsetMeta = grid.getMetadata<openvdb::DoubleMetadata>(kNormalizeOffsetKey);
    const auto scaleMeta = grid.getMetadata<openvdb::DoubleMetadata>(kNormalizeScaleKey);
    if (!offsetMeta || !scaleMeta) {
        throw UsageError(fmt::format("denormalize: grid '{}' carries no {} / {} metadata (normalize it first)", grid.getName(),
            kNormalizeOffsetKey, kNormalizeScaleKey));
    }
    const double offset = offsetMeta->value(), scale = scaleMeta->value();
    detail::dispatch(grid, "denormalize", [&](auto& g) {
        using GridT = std::decay_t<decltype(g)>;
        using ValueT = typename GridT::ValueType;
        detail::forEachActiveValue(g, [=](ValueT& v) {
            for (int c = 0; c < detail::channels(v); ++c) detail::ref(v, c) = detail::finite(restore(detail::get(v, c), scale, offset));
        });
    });
    grid.removeMeta(kNormalizeOffsetKey);
    grid.removeMeta(kNormalizeScaleKey);
}

} // namespace vxf::ops
