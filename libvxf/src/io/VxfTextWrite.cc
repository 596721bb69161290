#include <vxf/io/VxfText.h>

#include "VxfTextColumns.h"

#include <vxf/io/AtomicFile.h>
#include <vxf/io/InputFile.h>

#include <openvdb/tools/SignedFloodFill.h>

#include <fmt/format.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string_view>

namespace vxf {

namespace {

using namespace detail;

/// Buffered output with shortest round-trip number formatting into @a file; errors name
/// @a target, the file the user asked for (@a file is its temporary sibling).
class TextSink
{
public:
    TextSink(const std::string& file, const std::string& target)
        : mFile(std::fopen(file.c_str(), "wb"))
        , mPath(target)
    {
        if (!mFile) throw Error(fmt::format("{}: cannot write: {}", target, std::strerror(errno)));
        mBuffer.reserve(1 << 20);
    }
    ~TextSink()
    {
        if (mFile) std::fclose(mFile);
    }
    template <typename T>
    void number(T value)
    {
        char buf[64];
        const auto result = std::to_chars(buf, buf + sizeof(buf), value);
        mBuffer.append(buf, result.ptr);
    }
    void text(std::string_view s) { mBuffer.append(s); }
    void put(char c) { mBuffer.push_back(c); }
    void flushIfFull()
    {
        if (mBuffer.size() > (1u << 20) - 4096) flush();
    }
    void flush()
    {
        if (!mBuffer.empty() && std::fwrite(mBuffer.data(), 1, mBuffer.size(), mFile) != mBuffer.size()) {
            throw Error(fmt::format("{}: cannot write: {}", mPath, std::strerror(errno)));
        }
        mBuffer.clear();
    }
    void close()
    {
        flush();
        const int rc = std::fclose(mFile);
        mFile = nullptr;
        if (rc != 0) throw Error(fmt::format("{}: cannot write: {}", mPath, std::strerror(errno)));
    }

private:
    std::FILE* mFile;
    std::string mPath;
    std::string mBuffer;
};

struct ColumnReader
{
    GridColumn column;
    openvdb::GridBase::ConstPtr grid;
    std::unique_ptr<openvdb::BoolGrid::ConstAccessor> boolAcc;
    std::unique_ptr<openvdb::FloatGrid::ConstAccessor> floatAcc;
    std::unique_ptr<openvdb::Vec3SGrid::ConstAccessor> vecAcc;
};

/// Add to @a mask every voxel of @a grid that the text must carry: active voxels and tiles,
/// and inactive leaf voxels whose value differs from the background.
template <typename GridT>
void collectVoxels(const GridT& grid, openvdb::MaskTree& mask)
{
    mask.topologyUnion(grid.tree());
    const auto background = grid.background();
    openvdb::tree::ValueAccessor<openvdb::MaskTree> acc(mask);
    for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf) {
        for (auto it = leaf->cbeginValueOff(); it; ++it) {
            if (!openvdb::math::isExactlyEqual(*it, background)) acc.setValueOn(it.getCoord());
        }
    }
}

template <typename T>
void requireFinite(const T& value, const std::string& grid, const openvdb::Coord& ijk)
{
    bool finite;
    if constexpr (std::is_same_v<T, openvdb::Vec3f>)
        finite = std::isfinite(value[0]) && std::isfinite(value[1]) && std::isfinite(value[2]);
    else
        finite = std::isfinite(value);
    if (!finite) {
        throw Error(fmt::format(
            "grid '{}' holds a non-finite value at voxel ({}, {}, {}); text VXF allows finite numbers only", grid, ijk[0], ijk[1], ijk[2]));
    }
}

} // namespace

namespace {

/// The grids to write: @a options.grids, or every grid a text column can hold (the others
/// named in @a warnings); their names must be column names.
std::vector<openvdb::GridBase::Ptr> chooseGrids(const VoxelSet& set, const VxfWriteOptions& options, std::vector<std::string>& warnings)
{
    const auto supported = [](const openvdb::GridBase& g) {
        return g.isType<openvdb::FloatGrid>() || g.isType<openvdb::Vec3SGrid>() || g.isType<openvdb::BoolGrid>();
    };
    std::vector<openvdb::GridBase::Ptr> chosen;
    if (options.grids.empty()) {
        for (const auto& g : set.grids()) {
            if (!supported(*g)) {
                warnings.push_back(fmt::format("skipped grid '{}': {} grids cannot be text columns", g->getName(), g->valueType()));
            } else if (g->transform() != set.transform()) {
                warnings.push_back(fmt::format("skipped grid '{}': its transform differs from the other grids'", g->getName()));
            } else {
                chosen.push_back(g);
            }
        }
    } else {
        for (const auto& name : options.grids) {
            auto g = set.find(name);
            // A usage error, as vdb2vol's: the argument names no grid of the input.
            if (!g) throw UsageError(fmt::format("{}no grid named '{}' to write", set.path().empty() ? "" : set.path() + ": ", name));
            if (!supported(*g))
                throw Error(fmt::format("grid '{}' holds {} values; text VXF columns are bool, float or vec3", name, g->valueType()));
            for (const auto& other : chosen) {
                if (other->getName() == name) throw Error(fmt::format("grid '{}' requested twice", name));
            }
            if (!chosen.empty() && g->transform() != chosen.front()->transform()) {
                throw Error(fmt::format("grid '{}' does not share the transform of grid '{}'", name, chosen.front()->getName()));
            }
            chosen.push_back(g);
        }
    }
    if (chosen.empty()) throw Error("no grid to write (text VXF holds bool, float and vec3 grids)");
    for (const auto& g : chosen) {
        if (g->getName() == "active" || g->getName().empty() || g->getName().find_first_of(" \t#") != std::string::npos) {
            throw Error(fmt::format("grid name '{}' cannot be a text column name (rename it)", g->getName()));
        }
    }
    return chosen;
}

/// The text header's extent: voxel (0, 0, 0)'s index, the size and the corners.
struct TextExtent
{
    openvdb::Coord origin;
    openvdb::Vec3i size;
    openvdb::Vec3d minCorner, maxCorner;
};

/// The extent of @a bbox (the written voxels' bounds, @a count of them) on @a xform, or the text
/// header @a set came from when it still describes it.
TextExtent textExtent(
    const VoxelSet& set, const openvdb::math::Transform& xform, double voxelSize, const openvdb::CoordBBox& bbox, openvdb::Index64 count)
{
    TextExtent e;
    e.origin = bbox.min();
    e.size = openvdb::Vec3i(bbox.dim().x(), bbox.dim().y(), bbox.dim().z());
    e.minCorner = xform.indexToWorld(openvdb::Vec3d(e.origin.asVec3d()) - openvdb::Vec3d(0.5));
    e.maxCorner = e.minCorner + openvdb::Vec3d(e.size) * voxelSize;
    const auto& meta = set.metadata();
    auto textSize = meta.getMetadata<openvdb::Vec3IMetadata>(kTextSizeMetaKey);
    auto textMin = meta.getMetadata<openvdb::Vec3DMetadata>(kTextMinMetaKey);
    auto textMax = meta.getMetadata<openvdb::Vec3DMetadata>(kTextMaxMetaKey);
    if (textSize && textMin && textMax) {
        openvdb::Coord textOrigin;
        const auto textXform = textTransform(textMin->value(), voxelSize, textOrigin);
        const openvdb::CoordBBox textBox(textOrigin, textOrigin + openvdb::Coord(textSize->value()) - openvdb::Coord(1));
        if (*textXform == xform && (count == 0 || textBox.isInside(bbox))) {
            e.origin = textOrigin;
            e.size = textSize->value();
            e.minCorner = textMin->value();
            e.maxCorner = textMax->value();
        }
    }
    return e;
}

/// One reader per grid, with its text column.
std::vector<ColumnReader> columnReaders(const std::vector<openvdb::GridBase::Ptr>& chosen)
{
    std::vector<ColumnReader> readers;
    for (const auto& g : chosen) {
        ColumnReader r;
        r.grid = g;
        r.column.name = g->getName();
        r.column.gridClass = g->getGridClass();
        if (auto f = openvdb::gridConstPtrCast<openvdb::FloatGrid>(g)) {
            r.column.type = ColumnType::Float;
            r.column.background = openvdb::Vec3f(f->background());
            r.floatAcc = std::make_unique<openvdb::FloatGrid::ConstAccessor>(f->getConstAccessor());
        } else if (auto v = openvdb::gridConstPtrCast<openvdb::Vec3SGrid>(g)) {
            r.column.type = ColumnType::Vec3;
            r.column.background = v->background();
            r.vecAcc = std::make_unique<openvdb::Vec3SGrid::ConstAccessor>(v->getConstAccessor());
        } else if (auto b = openvdb::gridConstPtrCast<openvdb::BoolGrid>(g)) {
            r.column.type = ColumnType::Bool;
            r.column.background = openvdb::Vec3f(b->background() ? 1.0f : 0.0f);
            r.boolAcc = std::make_unique<openvdb::BoolGrid::ConstAccessor>(b->getConstAccessor());
        }
        if (r.column.type != ColumnType::Float && r.column.gridClass == openvdb::GRID_LEVEL_SET) {
            r.column.gridClass = openvdb::GRID_UNKNOWN;
        }
        readers.push_back(std::move(r));
    }
    return readers;
}

/// The header lines: vxf, size, min, max, a grid line per column and count.
void writeHeader(
    TextSink& out, const TextExtent& extent, double voxelSize, const std::vector<ColumnReader>& readers, openvdb::Index64 count)
{
    out.text(fmt::format("# text VXF voxel file written by vxf {} (spec: schemas/vxf-text.md)\nvxf 1\n", versionString()));
    out.text("size ");
    for (int a = 0; a < 3; ++a) {
        out.number(extent.size[a]);
        out.put(' ');
    }
    out.number(voxelSize);
    for (int c = 0; c < 2; ++c) {
        const openvdb::Vec3d& corner = c == 0 ? extent.minCorner : extent.maxCorner;
        out.text(c == 0 ? "\nmin" : "\nmax");
        for (int a = 0; a < 3; ++a) {
            out.put(' ');
            out.number(corner[a]);
        }
    }
    out.put('\n');
    for (const ColumnReader& r : readers) {
        out.text(fmt::format("grid {} {}", r.column.name, columnTypeName(r.column.type)));
        if (r.column.gridClass == openvdb::GRID_LEVEL_SET) out.text(" class=level_set");
        if (r.column.gridClass == openvdb::GRID_FOG_VOLUME) out.text(" class=fog_volume");
        if (r.column.background != openvdb::Vec3f(0.0f)) {
            out.text(" background=");
            for (int a = 0; a < columnWidth(r.column.type); ++a) {
                if (a) out.put(',');
                out.number(r.column.background[a]);
            }
        }
        out.put('\n');
    }
    out.text("count ");
    out.number(count);
    out.put('\n');
}

/// The voxel line of @a ijk: its index from @a origin, the active flag, the columns' values.
void writeVoxelLine(TextSink& out, const std::vector<ColumnReader>& readers, const openvdb::Coord& ijk, const openvdb::Coord& origin)
{
    bool active = false;
    for (const ColumnReader& r : readers) {
        active = active || (r.floatAcc ? r.floatAcc->isValueOn(ijk) : r.vecAcc ? r.vecAcc->isValueOn(ijk) : r.boolAcc->isValueOn(ijk));
    }
    const openvdb::Coord index = ijk - origin;
    out.number(index.x());
    out.put(' ');
    out.number(index.y());
    out.put(' ');
    out.number(index.z());
    out.text(active ? " 1" : " 0");
    for (const ColumnReader& r : readers) {
        if (r.floatAcc) {
            const float v = r.floatAcc->getValue(ijk);
            requireFinite(v, r.column.name, ijk);
            out.put(' ');
            out.number(v);
        } else if (r.vecAcc) {
            const openvdb::Vec3f v = r.vecAcc->getValue(ijk);
            requireFinite(v, r.column.name, ijk);
            for (int a = 0; a < 3; ++a) {
                out.put(' ');
                out.number(v[a]);
            }
        } else {
            out.text(r.boolAcc->getValue(ijk) ? " 1" : " 0");
        }
    }
    out.put('\n');
    out.flushIfFull();
}

} // namespace

std::vector<std::string> writeVxfText(
    const std::string& path, const VoxelSet& set, const VxfWriteOptions& options, Interrupter* interrupter)
{
    InterruptStep step(interrupter, "writing text VXF");
    std::vector<std::string> warnings;

    // Choose the grids.
    const std::vector<openvdb::GridBase::Ptr> chosen = chooseGrids(set, options, warnings);
    const openvdb::math::Transform& xform = chosen.front()->transform();
    const auto map = xform.baseMap();
    const bool axisAligned = map->isType<openvdb::math::UniformScaleMap>() || map->isType<openvdb::math::UniformScaleTranslateMap>() ||
        map->isType<openvdb::math::ScaleMap>() || map->isType<openvdb::math::ScaleTranslateMap>();
    if (!axisAligned || !map->hasUniformScale()) {
        throw Error(fmt::format("grid '{}' has a {} transform; text VXF needs axis-aligned cubic voxels (resample first)",
            chosen.front()->getName(), map->type()));
    }
    const double voxelSize = xform.voxelSize()[0];

    // Which voxels: union over the grids.
    openvdb::MaskTree mask;
    openvdb::Index64 maxActive = 0;
    for (const auto& g : chosen) {
        maxActive = std::max(maxActive, g->activeVoxelCount());
        if (auto f = openvdb::gridConstPtrCast<openvdb::FloatGrid>(g))
            collectVoxels(*f, mask);
        else if (auto v = openvdb::gridConstPtrCast<openvdb::Vec3SGrid>(g))
            collectVoxels(*v, mask);
        else if (auto b = openvdb::gridConstPtrCast<openvdb::BoolGrid>(g))
            collectVoxels(*b, mask);
    }
    mask.voxelizeActiveTiles();
    const openvdb::Index64 count = mask.activeVoxelCount();
    if (chosen.size() > 1) {
        for (const auto& g : chosen) {
            if (g->activeVoxelCount() != maxActive) {
                warnings.push_back("the grids have different active voxels; text VXF has one active flag per voxel, so a "
                                   "voxel active in any grid is written active (and reads back active in all)");
                break;
            }
        }
    }

    // Header: reuse the text header the set came from when it still describes it.
    openvdb::CoordBBox bbox;
    mask.evalActiveVoxelBoundingBox(bbox);
    if (count == 0) bbox = openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(-1));
    const TextExtent extent = textExtent(set, xform, voxelSize, bbox, count);
    const std::vector<ColumnReader> readers = columnReaders(chosen);

    writeAtomically(path, [&](const std::string& tmpPath) {
        TextSink out(tmpPath, path);
        writeHeader(out, extent, voxelSize, readers, count);

        std::uint64_t written = 0;
        for (auto leaf = mask.cbeginLeaf(); leaf; ++leaf) {
            for (auto it = leaf->cbeginValueOn(); it; ++it) {
                writeVoxelLine(out, readers, it.getCoord(), extent.origin);
            }
            written += leaf->onVoxelCount();
            if (count > 0 && (written & 0xFFFF) < 512) checkInterrupt(interrupter, int(100.0 * double(written) / double(count)));
        }
        out.close();
    });
    return warnings;
}

} // namespace vxf
