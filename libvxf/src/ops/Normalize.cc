#include <vxf/ops/Normalize.h>

#include "Dispatch.h"

#include <openvdb/tools/ValueTransformer.h>

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
        double lo = 0.0, hi = 0.0;
        bool any = false;
        for (auto it = g.cbeginValueOn(); it; ++it) {
            const ValueT v = *it;
            for (int c = 0; c < detail::channels(v); ++c) {
                double x = detail::get(v, c);
                if (options.clampNegatives) x = std::max(0.0, x);
                lo = any ? std::min(lo, x) : x;
                hi = any ? std::max(hi, x) : x;
                any = true;
            }
        }
        const double offset = lo < 0.0 ? lo : 0.0;
        double scale = hi - offset > 0.0 ? hi - offset : 1.0;
        if (options.exact) scale = std::exp2(std::ceil(std::log2(scale))); // division by 2^k is exact
        const bool clamp = options.clampNegatives;
        openvdb::tools::foreach(g.beginValueOn(), [=](const typename GridT::ValueOnIter& it) {
            ValueT v = *it;
            for (int c = 0; c < detail::channels(v); ++c) {
                float x = detail::get(v, c);
                if (clamp) x = std::max(0.0f, x);
                detail::ref(v, c) = forward(x, scale, offset);
            }
            it.setValue(v);
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
        openvdb::tools::foreach(g.beginValueOn(), [=](const typename GridT::ValueOnIter& it) {
            ValueT v = *it;
            for (int c = 0; c < detail::channels(v); ++c) detail::ref(v, c) = detail::finite(restore(detail::get(v, c), scale, offset));
            it.setValue(v);
        });
    });
    grid.removeMeta(kNormalizeOffsetKey);
    grid.removeMeta(kNormalizeScaleKey);
}

} // namespace vxf::ops
