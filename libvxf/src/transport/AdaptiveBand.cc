#include <vxf/transport/AdaptiveBand.h>

#include <openvdb/tools/Count.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/Prune.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace vxf {

namespace {

/// A band of @a band world units in @a density's voxels (at least one).
int bandInVoxels(const openvdb::FloatGrid& density, double band)
{
    return int(std::clamp(std::ceil(band / density.voxelSize()[0]), 1.0, 1e9)); // (any band deeper than a medium is as good)
}

} // namespace

openvdb::Vec3f leafMean(const openvdb::Vec3STree::LeafNodeType& leaf)
{
    openvdb::Vec3d sum(0.0);
    for (auto v = leaf.cbeginValueOn(); v; ++v) sum += openvdb::Vec3d(*v);
    return openvdb::Vec3f(sum / double(leaf.SIZE));
}

BandInterior::BandInterior(const openvdb::FloatGrid& density, double band)
{
    if (!(band > 0.0)) return;
    const int bandVoxels = bandInVoxels(density, band);
    constexpr int leafDim = openvdb::MaskTree::LeafNodeType::DIM;
    const int depth = std::max(bandVoxels, leafDim / 2);
    // A band as deep as half the medium's extent leaves no core; eroding that far would take
    // one pass a voxel (a band given in voxels where world units are asked took minutes).
    openvdb::CoordBBox bounds;
    density.tree().evalActiveVoxelBoundingBox(bounds);
    if (bounds.empty() || 2 * std::int64_t(depth) >= std::int64_t(std::min({bounds.dim().x(), bounds.dim().y(), bounds.dim().z()}))) return;
    mCore.topologyUnion(density.tree());
    // L∞ erosion of the medium's topology: never overstates the distance to the surface.
    openvdb::tools::erodeActiveValues(mCore, depth, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::PRESERVE_TILES);
}

bool BandInterior::holdsLeaf(const openvdb::Coord& origin) const
{
    const auto* leaf = mCore.probeConstLeaf(origin);
    return leaf ? leaf->isValueMaskOn() : mCore.isValueOn(origin);
}

namespace {

using MaskTree = openvdb::MaskTree;
using Internal1 = openvdb::Vec3STree::RootNodeType::ChildNodeType::ChildNodeType; // 128³
constexpr int kLeafDim = openvdb::Vec3STree::LeafNodeType::DIM, kInternalDim = Internal1::DIM;

/// The blocks of a tree coarsenBeyondBand makes tiles, each with its mean: 128³ blocks, then
/// 8³ leaves (none inside those blocks).
struct DeepBlocks
{
    std::vector<std::pair<openvdb::Coord, openvdb::Vec3f>> internal, leaves; ///< internal: sorted by origin
    /// Whether @a origin (of a leaf or tile) lies in one of the 128³ blocks.
    bool inInternal(const openvdb::Coord& origin) const
    {
        const openvdb::Coord block(origin.x() & ~(kInternalDim - 1), origin.y() & ~(kInternalDim - 1), origin.z() & ~(kInternalDim - 1));
        const auto at =
            std::lower_bound(internal.begin(), internal.end(), block, [](const auto& b, const openvdb::Coord& c) { return b.first < c; });
        return at != internal.end() && at->first == block;
    }
};

DeepBlocks deepBlocks(const openvdb::Vec3STree& tree, const openvdb::FloatGrid& density, double band)
{
    DeepBlocks deep;
    if (!(band > 0.0)) return deep;
    const int bandVoxels = bandInVoxels(density, band);
    MaskTree medium;
    medium.topologyUnion(density.tree());

    // 128³ first: whole blocks at least max(band, 64) voxels deep, i.e. the block grown by that
    // depth (L∞) lies entirely in the medium (only a medium at least 256 voxels across every
    // axis has any).
    const int deepVoxels = std::max(bandVoxels, kInternalDim / 2);
    openvdb::CoordBBox bounds;
    medium.evalActiveVoxelBoundingBox(bounds);
    if (!bounds.empty() && std::min({bounds.dim().x(), bounds.dim().y(), bounds.dim().z()}) >= kInternalDim + 2 * deepVoxels) {
        std::vector<const Internal1*> nodes;
        tree.getNodes(nodes);
        for (const Internal1* node : nodes) {
            const openvdb::CoordBBox box = node->getNodeBoundingBox();
            const openvdb::CoordBBox grown = openvdb::CoordBBox(box.min().offsetBy(-deepVoxels), box.max().offsetBy(deepVoxels));
            if (openvdb::tools::countActiveVoxels(medium, grown) != grown.volume()) continue;
            openvdb::Vec3d sum(0.0);
            for (auto leaf = node->cbeginChildOn(); leaf; ++leaf)
                for (auto v = leaf->cbeginValueOn(); v; ++v) sum += openvdb::Vec3d(*v);
            for (auto t = node->cbeginValueOn(); t; ++t) sum += openvdb::Vec3d(*t) * double(kLeafDim * kLeafDim * kLeafDim);
            deep.internal.emplace_back(box.min(), openvdb::Vec3f(sum / double(box.volume())));
        }
        std::sort(deep.internal.begin(), deep.internal.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    }

    // Then 8³ leaves at least max(band, 4) voxels deep.
    const BandInterior core(density, band);
    for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
        const openvdb::Coord origin = leaf->origin();
        if (!core.holdsLeaf(origin) || deep.inInternal(origin)) continue;
        deep.leaves.emplace_back(origin, leafMean(*leaf));
    }
    return deep;
}

/// What @a grid holds at full resolution and as tiles, and @a deep's counts.
AdaptiveBandReport reportOf(const openvdb::Vec3SGrid& grid, const DeepBlocks& deep)
{
    AdaptiveBandReport report;
    report.internalTiles = deep.internal.size();
    report.leafTiles = deep.leaves.size();
    for (auto it = grid.tree().cbeginValueOn(); it; ++it) {
        if (it.isVoxelValue()) {
            ++report.fineVoxels;
        } else {
            report.coarseVoxels += it.getVoxelCount();
        }
    }
    return report;
}

} // namespace

AdaptiveBandReport coarsenBeyondBand(openvdb::Vec3SGrid& grid, const openvdb::FloatGrid& density, double band)
{
    const DeepBlocks deep = deepBlocks(grid.tree(), density, band);
    for (const auto& [origin, mean] : deep.internal) grid.tree().addTile(2, origin, mean, true);
    for (const auto& [origin, mean] : deep.leaves) grid.tree().addTile(1, origin, mean, true);
    return reportOf(grid, deep);
}

openvdb::Vec3SGrid::Ptr coarsenedBeyondBand(
    const openvdb::Vec3SGrid& grid, const openvdb::FloatGrid& density, double band, AdaptiveBandReport& report)
{
    const DeepBlocks deep = deepBlocks(grid.tree(), density, band);
    if (deep.internal.empty() && deep.leaves.empty()) { // as coarse as the band makes it already
        report = reportOf(grid, deep);
        return nullptr;
    }
    openvdb::Vec3SGrid::Ptr copy = grid.copyWithNewTree(); // metadata and transform
    auto& tree = copy->tree();
    for (auto it = grid.tree().cbeginValueOn(); it; ++it) { // the grid's own tiles
        if (it.isVoxelValue()) continue;
        openvdb::CoordBBox box;
        it.getBoundingBox(box);
        if (!deep.inInternal(box.min())) tree.addTile(it.getLevel(), box.min(), *it, true);
    }
    for (const auto& [origin, mean] : deep.internal) tree.addTile(2, origin, mean, true);
    // The leaves: the deep ones as their means, the others copied (none made to be dropped).
    std::size_t next = 0; // deep.leaves are in the tree's leaf order
    for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf) {
        if (next < deep.leaves.size() && deep.leaves[next].first == leaf->origin()) {
            tree.addTile(1, leaf->origin(), deep.leaves[next++].second, true);
        } else if (!deep.inInternal(leaf->origin())) {
            tree.addLeaf(new openvdb::Vec3STree::LeafNodeType(*leaf));
        }
    }
    report = reportOf(*copy, deep);
    return copy;
}

} // namespace vxf
