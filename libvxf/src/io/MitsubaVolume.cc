#include <vxf/io/MitsubaVolume.h>

#include <vxf/core/Error.h>
#include <vxf/io/AtomicFile.h>

#include <fmt/format.h>

#include <cstdint>
#include <fstream>
#include <vector>

namespace vxf {

namespace {

template <typename T>
void put(std::ofstream& out, T value)
{
    out.write(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <typename GridT>
MitsubaVolumeInfo write(const std::string& path, const GridT& grid, int pad)
{
    openvdb::CoordBBox box = grid.evalActiveVoxelBoundingBox();
    if (box.empty()) throw UsageError(fmt::format("grid '{}' has no active voxels to write", grid.getName()));
    box.expand(pad);
    MitsubaVolumeInfo info;
    info.resolution = box.dim();
    info.channels = std::is_same_v<typename GridT::ValueType, float> ? 1 : 3;
    const openvdb::math::Transform& xform = grid.transform();
    info.bounds = openvdb::BBoxd(
        xform.indexToWorld(box.min().asVec3d() - openvdb::Vec3d(0.5)), xform.indexToWorld(box.max().asVec3d() + openvdb::Vec3d(0.5)));
    writeAtomically(path, [&](const std::string& tmp) {
        std::ofstream out(tmp, std::ios::binary);
        out.write("VOL", 3);
        put<std::uint8_t>(out, 3);
        put<std::int32_t>(out, 1); // float32
        for (int a = 0; a < 3; ++a) put<std::int32_t>(out, info.resolution[a]);
        put<std::int32_t>(out, info.channels);
        for (int a = 0; a < 3; ++a) put<float>(out, float(info.bounds.min()[a]));
        for (int a = 0; a < 3; ++a) put<float>(out, float(info.bounds.max()[a]));
        auto values = grid.getConstAccessor();
        std::vector<float> row(std::size_t(info.resolution.x()) * std::size_t(info.channels));
        for (int z = box.min().z(); z <= box.max().z(); ++z) {
            for (int y = box.min().y(); y <= box.max().y(); ++y) {
                for (int x = box.min().x(); x <= box.max().x(); ++x) {
                    const auto v = values.getValue(openvdb::Coord(x, y, z));
                    const std::size_t at = std::size_t(x - box.min().x()) * std::size_t(info.channels);
                    if constexpr (std::is_same_v<typename GridT::ValueType, float>) {
                        row[at] = v;
                    } else {
                        for (int c = 0; c < 3; ++c) row[at + std::size_t(c)] = v[c];
                    }
                }
                out.write(reinterpret_cast<const char*>(row.data()), std::streamsize(row.size() * sizeof(float)));
            }
        }
        if (!out) throw Error(fmt::format("{}: write failed", path));
    });
    return info;
}

} // namespace

MitsubaVolumeInfo writeMitsubaVolume(const std::string& path, const openvdb::GridBase& grid, int pad)
{
    if (pad < 0) throw UsageError(fmt::format("pad must be >= 0, got {}", pad));
    if (const auto* f = dynamic_cast<const openvdb::FloatGrid*>(&grid)) return write(path, *f, pad);
    if (const auto* v = dynamic_cast<const openvdb::Vec3SGrid*>(&grid)) return write(path, *v, pad);
    throw UsageError(fmt::format("grid '{}' holds {} values; Mitsuba volumes take float or vec3s grids", grid.getName(), grid.valueType()));
}

} // namespace vxf
