#include <vxf/core/GridStats.h>

#include <vxf/core/GridLookup.h>

#include <openvdb/openvdb.h>
#include <openvdb/tools/Diagnostics.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

namespace vxf {

GridStats gridStats(const openvdb::GridBase& grid)
{
    GridStats stats;
    const openvdb::TreeBase& tree = grid.baseTree();
    stats.activeVoxels = tree.activeVoxelCount();
    stats.leafNodes = tree.leafCount();
    stats.activeTiles = tree.activeTileCount();
    stats.memoryBytes = tree.memUsage();
    stats.activeBBox = grid.evalActiveVoxelBoundingBox();
    return stats;
}

std::size_t valueBytes(const std::string& valueType)
{
    static const std::map<std::string, std::size_t> sizes = {{"bool", 1}, {"mask", 1}, {"float", 4}, {"double", 8}, {"half", 2},
        {"int32", 4}, {"int64", 8}, {"vec3s", 12}, {"vec3d", 24}, {"vec3i", 12}};
    const auto found = sizes.find(valueType);
    return found == sizes.end() ? 4 : found->second;
}

GridFootprint footprintOf(const std::string& name, double bytes, const openvdb::CoordBBox& box, std::size_t valueBytes)
{
    GridFootprint f{name, bytes, 0.0};
    if (!box.empty()) {
        openvdb::CoordBBox copied = box;
        copied.expand(kDenseCopyMargin);
        const double dense = double(copied.volume()) * double(valueBytes);
        if (dense <= double(kDenseCopyBytes)) f.denseBytes = dense; // (DenseCopy::create's test)
    }
    return f;
}

GridFootprint footprintOf(const openvdb::GridBase& grid)
{
    return footprintOf(grid.getName(), double(grid.baseTree().memUsage()), grid.evalActiveVoxelBoundingBox(), valueBytes(grid.valueType()));
}

namespace {

template <typename T>
openvdb::Vec3d asVec3(const T& v)
{
    return openvdb::Vec3d(double(v));
}
template <typename T>
openvdb::Vec3d asVec3(const openvdb::math::Vec3<T>& v)
{
    return openvdb::Vec3d(double(v[0]), double(v[1]), double(v[2]));
}

template <typename GridT>
ValueRange rangeOf(const GridT& grid, int channels)
{
    ValueRange r;
    openvdb::Vec3d sum(0.0);
    double count = 0.0;
    for (auto it = grid.cbeginValueOn(); it; ++it) {
        const openvdb::Vec3d v = asVec3(*it);
        if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) {
            r.nonFinite += it.getVoxelCount();
            continue;
        }
        const double n = double(it.getVoxelCount());
        if (count == 0.0) r.min = r.max = v;
        for (int c = 0; c < 3; ++c) {
            r.min[c] = std::min(r.min[c], v[c]);
            r.max[c] = std::max(r.max[c], v[c]);
        }
        sum += v * n;
        count += n;
    }
    if (count > 0.0) {
        r.channels = channels;
        r.mean = sum / count;
    }
    return r;
}

} // namespace

ValueRange valueRange(const openvdb::GridBase& grid)
{
    if (const auto* g = dynamic_cast<const openvdb::FloatGrid*>(&grid)) return rangeOf(*g, 1);
    if (const auto* g = dynamic_cast<const openvdb::DoubleGrid*>(&grid)) return rangeOf(*g, 1);
    if (const auto* g = dynamic_cast<const openvdb::Int32Grid*>(&grid)) return rangeOf(*g, 1);
    if (const auto* g = dynamic_cast<const openvdb::Int64Grid*>(&grid)) return rangeOf(*g, 1);
    if (const auto* g = dynamic_cast<const openvdb::Vec3SGrid*>(&grid)) return rangeOf(*g, 3);
    if (const auto* g = dynamic_cast<const openvdb::Vec3DGrid*>(&grid)) return rangeOf(*g, 3);
    if (const auto* g = dynamic_cast<const openvdb::Vec3IGrid*>(&grid)) return rangeOf(*g, 3);
    return {};
}

NonFiniteValues nonFiniteValues(const openvdb::GridBase& grid)
{
    NonFiniteValues found;
    grid.apply<openvdb::TypeList<openvdb::FloatGrid, openvdb::DoubleGrid, openvdb::Vec3SGrid, openvdb::Vec3DGrid>>([&found](const auto& g) {
        using GridT = std::decay_t<decltype(g)>;
        openvdb::tools::Diagnose<GridT> diagnose(g);
        diagnose.check(openvdb::tools::CheckFinite<GridT, typename GridT::ValueOnCIter>(), /*updateMask=*/true, /*checkVoxels=*/true,
            /*checkTiles=*/true, /*checkBackground=*/false);
        found.count = diagnose.failureCount();
        if (found.count > 0) {
            openvdb::CoordBBox box;
            auto first = diagnose.mask()->cbeginValueOn();
            first.getBoundingBox(box);
            found.first = box.min();
        }
    });
    return found;
}

std::string formatBytes(std::uint64_t bytes)
{
    const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
    double value = double(bytes);
    int unit = 0;
    while (value >= 1024.0 && unit < 4) {
        value /= 1024.0;
        ++unit;
    }
    return unit == 0 ? fmt::format("{} B", bytes) : fmt::format("{:.1f} {}", value, units[unit]);
}

} // namespace vxf
