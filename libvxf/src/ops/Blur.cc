#include <vxf/ops/Blur.h>

#include "Dispatch.h"

#include <openvdb/tools/Filter.h>

namespace vxf::ops {

openvdb::FloatGrid::Ptr weightsFromSelection(const openvdb::BoolGrid& selection)
{
    auto weights = openvdb::FloatGrid::create(0.0f);
    weights->setTransform(selection.transform().copy());
    weights->tree().topologyUnion(selection.tree());
    for (auto it = weights->beginValueOn(); it; ++it) it.setValue(1.0f);
    return weights;
}

void blur(openvdb::GridBase& grid, const BlurOptions& options, Interrupter* interrupter)
{
    if (options.radius < 1 || options.iterations < 1) {
        throw UsageError(fmt::format("blur: radius ({}) and iterations ({}) must be at least 1", options.radius, options.iterations));
    }
    if (options.mask && options.mask->transform() != grid.transform()) {
        throw UsageError(fmt::format("blur: the mask does not share grid '{}''s transform", grid.getName()));
    }
    InterruptStep step(interrupter, "blurring");
    detail::dispatch(grid, "blur", [&](auto& g) {
        using GridT = std::decay_t<decltype(g)>;
        openvdb::tools::Filter<GridT, openvdb::FloatGrid, openvdb::util::NullInterrupter> filter(g, interrupter);
        if (options.kind == BlurKind::Box) {
            filter.mean(options.radius, options.iterations, options.mask);
        } else {
            filter.gaussian(options.radius, options.iterations, options.mask);
        }
    });
    checkInterrupt(interrupter);
}

} // namespace vxf::ops
