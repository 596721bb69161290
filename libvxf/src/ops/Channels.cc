#include <vxf/ops/Channels.h>

#include <vxf/core/Error.h>

#include <fmt/format.h>

namespace vxf::ops {

std::array<openvdb::FloatGrid::Ptr, 3> splitChannels(const openvdb::Vec3SGrid& grid)
{
    std::array<openvdb::FloatGrid::Ptr, 3> out;
    for (int c = 0; c < 3; ++c) {
        auto g = openvdb::FloatGrid::create(grid.background()[c]);
        g->setTransform(grid.transform().copy());
        g->setName(grid.getName() + "." + "xyz"[c]);
        for (auto meta = grid.beginMeta(); meta != grid.endMeta(); ++meta) g->insertMeta(meta->first, *meta->second);
        g->setName(grid.getName() + "." + "xyz"[c]);
        g->tree().topologyUnion(grid.tree());
        auto values = grid.getConstAccessor();
        for (auto it = g->beginValueOn(); it; ++it) it.setValue(values.getValue(it.getCoord())[c]);
        out[std::size_t(c)] = g;
    }
    return out;
}

openvdb::Vec3SGrid::Ptr mergeChannels(const openvdb::FloatGrid& x, const openvdb::FloatGrid& y, const openvdb::FloatGrid& z,
    const std::string& name)
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
