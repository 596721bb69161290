// Internal: run a generic operation on a float or Vec3f grid.
#pragma once

#include <vxf/core/Error.h>

#include <openvdb/openvdb.h>
#include <openvdb/tree/LeafManager.h>

#include <fmt/format.h>

#include <vector>

namespace vxf::ops::detail {

/// Call @a f with @a grid as FloatGrid& or Vec3SGrid&; vxf::UsageError for other types.
template <typename GridBaseT, typename F>
decltype(auto) dispatch(GridBaseT& grid, const char* op, F&& f)
{
    using FloatT = std::conditional_t<std::is_const_v<GridBaseT>, const openvdb::FloatGrid, openvdb::FloatGrid>;
    using VecT = std::conditional_t<std::is_const_v<GridBaseT>, const openvdb::Vec3SGrid, openvdb::Vec3SGrid>;
    if (auto* g = dynamic_cast<FloatT*>(&grid)) return f(*g);
    if (auto* g = dynamic_cast<VecT*>(&grid)) return f(*g);
    throw UsageError(fmt::format("{}: grid '{}' holds {} values; it works on float and vec3s grids", op, grid.getName(), grid.valueType()));
}

/// Apply @a f (ValueT&) to every active value of @a grid in place: leaf voxels straight in
/// their buffers (parallel over leaves), then the active tiles (one value each). Topology
/// unchanged; deterministic (each value is changed alone).
template <typename GridT, typename F>
void forEachActiveValue(GridT& grid, const F& f)
{
    using TreeT = typename GridT::TreeType;
    openvdb::tree::LeafManager<TreeT> leaves(grid.tree());
    leaves.foreach ([&f](typename TreeT::LeafNodeType& leaf, std::size_t) {
        auto* values = leaf.buffer().data();
        for (auto on = leaf.getValueMask().beginOn(); on; ++on) f(values[on.pos()]);
    });
    auto tiles = grid.tree().beginValueOn();
    tiles.setMaxDepth(TreeT::RootNodeType::LEVEL - 1); // internal nodes' tiles, not leaf voxels
    for (; tiles; ++tiles) {
        auto v = *tiles;
        f(v);
        tiles.setValue(v);
    }
}

/// Apply @a f (const Coord&, ValueT&) to every active leaf voxel (parallel over leaves) and
/// to every active tile, given the coordinate of its first voxel and its bounding box in
/// @a tileBox (so a tile can be evaluated at its centre).
template <typename GridT, typename LeafF, typename TileF>
void forEachActiveVoxel(GridT& grid, const LeafF& leafF, const TileF& tileF)
{
    using TreeT = typename GridT::TreeType;
    openvdb::tree::LeafManager<TreeT> leaves(grid.tree());
    leaves.foreach ([&leafF](typename TreeT::LeafNodeType& leaf, std::size_t) {
        auto* values = leaf.buffer().data();
        for (auto on = leaf.getValueMask().beginOn(); on; ++on) leafF(leaf.offsetToGlobalCoord(on.pos()), values[on.pos()]);
    });
    auto tiles = grid.tree().beginValueOn();
    tiles.setMaxDepth(TreeT::RootNodeType::LEVEL - 1);
    for (; tiles; ++tiles) {
        openvdb::CoordBBox box;
        tiles.getBoundingBox(box);
        auto v = *tiles;
        tileF(box, v);
        tiles.setValue(v);
    }
}

/// Split the active tiles of @a target into leaves wherever @a reference's values vary under
/// them (a reference tile smaller than the target tile, or reference voxels), so a per-leaf
/// pass can read one reference value per target voxel or tile.
template <typename TreeT, typename OtherTreeT>
void splitTilesWhereVaries(TreeT& target, const OtherTreeT& reference)
{
    openvdb::tree::ValueAccessor<const OtherTreeT> other(reference);
    std::vector<openvdb::CoordBBox> split;
    auto tiles = target.cbeginValueOn();
    tiles.setMaxDepth(TreeT::RootNodeType::LEVEL - 1);
    for (; tiles; ++tiles) {
        openvdb::CoordBBox box;
        tiles.getBoundingBox(box);
        // Depth of the node holding the reference value there: −1 background, 0 a root tile
        // (4096³), 1 a 128³ tile, 2 an 8³ tile, 3 a voxel.
        const int depth = other.getValueDepth(box.min());
        const openvdb::Index64 held = depth <= 0 ? ~openvdb::Index64(0)
            : depth == 1                         ? openvdb::Index64(128 * 128 * 128)
            : depth == 2                         ? openvdb::Index64(512)
                                                 : 1;
        if (held < box.volume()) split.push_back(box);
    }
    constexpr int leafDim = TreeT::LeafNodeType::DIM;
    for (const auto& box : split) {
        for (int x = box.min().x(); x <= box.max().x(); x += leafDim)
            for (int y = box.min().y(); y <= box.max().y(); y += leafDim)
                for (int z = box.min().z(); z <= box.max().z(); z += leafDim) target.touchLeaf(openvdb::Coord(x, y, z));
    }
}

/// Per-channel access for float and Vec3f values.
inline int channels(float) { return 1; }
inline int channels(const openvdb::Vec3f&) { return 3; }
inline float get(float v, int) { return v; }
inline float get(const openvdb::Vec3f& v, int c) { return v[c]; }
inline float& ref(float& v, int) { return v; }
inline float& ref(openvdb::Vec3f& v, int c) { return v[c]; }

/// A value of the grid's type from an RGB colour (float grids take the first channel
/// when all three agree, else the mean).
template <typename T>
T fromColor(const openvdb::Vec3d& c)
{
    if constexpr (std::is_same_v<T, float>) {
        return (c[0] == c[1] && c[1] == c[2]) ? float(c[0]) : float((c[0] + c[1] + c[2]) / 3.0);
    } else {
        return openvdb::Vec3f(c);
    }
}

/// Clamp to the finite float range (NaN becomes 0): no operator may write NaN or Inf.
inline float finite(double v)
{
    if (std::isnan(v)) return 0.0f;
    constexpr double big = std::numeric_limits<float>::max();
    return float(std::clamp(v, -big, big));
}

} // namespace vxf::ops::detail
