#include <vxf/core/GridStats.h>

#include <fmt/format.h>

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
