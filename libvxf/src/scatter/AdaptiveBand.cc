#include <vxf/scatter/AdaptiveBand.h>

#include <openvdb/tools/Count.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/Prune.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace vxf {

namespace {

using MaskTree = openvdb::MaskTree;

/// The medium's voxels at least @a depth voxels inside it (L∞ erosion of its topology).
MaskTree interior(const MaskTree& medium, int depth)
{
    MaskTree core(medium);
    openvdb::tools::erodeActiveValues(core, depth, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::PRESERVE_TILES);
    return core;
}

} // namespace

AdaptiveBandReport coarsenBeyondBand(openvdb::Vec3SGrid& grid, const openvdb::FloatGrid& density, double band)
{
    AdaptiveBandReport report;
    auto& tree = grid.tree();
    if (band > 0.0) {
        const int bandVoxels = std::max(1, int(std::ceil(band / density.voxelSize()[0])));
        MaskTree medium;
        medium.topologyUnion(density.tree());
        using Internal1 = openvdb::Vec3STree::RootNodeType::ChildNodeType::ChildNodeType; // 128³
        constexpr int leafDim = openvdb::Vec3STree::LeafNodeType::DIM, internalDim = Internal1::DIM;

        // 128³ first: whole blocks at least max(band, 64) voxels deep, i.e. the block grown by
        // that depth (L∞) lies entirely in the medium (only a medium at least 256 voxels
        // across every axis has any).
        const int deepVoxels = std::max(bandVoxels, internalDim / 2);
        openvdb::CoordBBox bounds;
        medium.evalActiveVoxelBoundingBox(bounds);
        if (!bounds.empty() && std::min({bounds.dim().x(), bounds.dim().y(), bounds.dim().z()}) >= internalDim + 2 * deepVoxels) {
            std::vector<const Internal1*> nodes;
            tree.getNodes(nodes);
            std::vector<std::pair<openvdb::Coord, openvdb::Vec3f>> blocks;
            for (const Internal1* node : nodes) {
                const openvdb::CoordBBox box = node->getNodeBoundingBox();
                const openvdb::CoordBBox grown = openvdb::CoordBBox(box.min().offsetBy(-deepVoxels), box.max().offsetBy(deepVoxels));
                if (openvdb::tools::countActiveVoxels(medium, grown) != grown.volume()) continue;
                openvdb::Vec3d sum(0.0);
                for (auto leaf = node->cbeginChildOn(); leaf; ++leaf)
                    for (auto v = leaf->cbeginValueOn(); v; ++v) sum += openvdb::Vec3d(*v);
                for (auto t = node->cbeginValueOn(); t; ++t) sum += openvdb::Vec3d(*t) * double(leafDim * leafDim * leafDim);
                blocks.emplace_back(box.min(), openvdb::Vec3f(sum / double(box.volume())));
            }
            for (const auto& [origin, mean] : blocks) tree.addTile(2, origin, mean, true);
            report.internalTiles = blocks.size();
        }

        // Then 8³ leaves at least max(band, 4) voxels deep.
        const MaskTree core = interior(medium, std::max(bandVoxels, leafDim / 2));
        openvdb::tree::ValueAccessor<const MaskTree> coreAccessor(core);
        std::vector<std::pair<openvdb::Coord, openvdb::Vec3f>> leaves;
        for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
            const openvdb::Coord origin = leaf->origin();
            const auto* coreLeaf = coreAccessor.probeConstLeaf(origin);
            const bool deepEnough = coreLeaf ? coreLeaf->isValueMaskOn() : coreAccessor.isValueOn(origin);
            if (!deepEnough) continue;
            openvdb::Vec3d sum(0.0);
            for (auto v = leaf->cbeginValueOn(); v; ++v) sum += openvdb::Vec3d(*v);
            leaves.emplace_back(origin, openvdb::Vec3f(sum / double(leaf->SIZE)));
        }
        for (const auto& [origin, mean] : leaves) tree.addTile(1, origin, mean, true);
        report.leafTiles = leaves.size();
    }
    for (auto it = tree.cbeginValueOn(); it; ++it) {
        if (it.isVoxelValue()) {
            ++report.fineVoxels;
        } else {
            report.coarseVoxels += it.getVoxelCount();
        }
    }
    return report;
}

} // namespace vxf
