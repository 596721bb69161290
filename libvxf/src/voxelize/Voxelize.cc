#include <vxf/voxelize/Voxelize.h>

#include <vxf/core/GridRoles.h>
#include <vxf/core/GridStats.h>
#include <vxf/core/MemoryBudget.h>

#include <openvdb/tools/LevelSetUtil.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/Prune.h>
#include <openvdb/tree/LeafManager.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace vxf {

double resolveVoxelSize(const openvdb::BBoxd& bounds, const VoxelizeOptions& options)
{
    if (options.voxelSize != 0.0 && options.dim != 0) {
        throw UsageError("give either voxel_size or dim, not both");
    }
    if (!(options.bandWidth >= 1.0f) || !std::isfinite(options.bandWidth)) {
        throw UsageError(fmt::format("band must be at least 1 voxel, got {}", options.bandWidth));
    }
    if (bounds.empty()) throw Error("the mesh has no triangles");
    const double extent = bounds.extents()[bounds.maxExtent()];
    if (options.voxelSize != 0.0) {
        if (!(options.voxelSize > 0.0) || !std::isfinite(options.voxelSize)) {
            throw UsageError(fmt::format("voxel_size must be a positive number, got {}", options.voxelSize));
        }
        if (extent / options.voxelSize > double(1 << 20)) {
            throw UsageError(fmt::format("voxel_size {} gives {:.0f} voxels along the mesh's longest side "
                                         "(more than 2^20); use a larger voxel size",
                options.voxelSize, extent / options.voxelSize));
        }
        if (options.voxelSize < kMinVoxelSize) {
            throw UsageError(fmt::format(
                "voxel_size {} is below {}, the smallest OpenVDB's transforms take; scale the mesh up", options.voxelSize, kMinVoxelSize));
        }
        return options.voxelSize;
    }
    if (options.dim <= 0) throw UsageError("give voxel_size or dim (a positive voxel count)");
    if (options.dim > (1 << 20)) throw UsageError(fmt::format("dim {} is above the limit 2^20", options.dim));
    if (!(extent > 0.0)) throw Error("the mesh is flat in every direction (zero extent); give voxel_size");
    const double voxelSize = extent / double(options.dim);
    if (voxelSize < kMinVoxelSize) {
        throw UsageError(fmt::format("dim {} makes voxels of {:.3g}, below {}, the smallest OpenVDB's transforms take; "
                                     "use a smaller dim or scale the mesh up",
            options.dim, voxelSize, kMinVoxelSize));
    }
    return voxelSize;
}

openvdb::math::Transform::Ptr voxelLattice(const openvdb::BBoxd& bounds, double voxelSize)
{
    // Far from the origin, shift the index origin by a whole number of voxels to the bounds.
    openvdb::Vec3d shift(0.0);
    const double farIndex = std::max(bounds.min().length(), bounds.max().length()) / voxelSize;
    if (farIndex > double(1 << 16)) {
        const openvdb::Vec3d centre = bounds.getCenter() / voxelSize;
        shift = openvdb::Vec3d(std::round(centre[0]), std::round(centre[1]), std::round(centre[2])) * voxelSize;
    }
    auto xform = openvdb::math::Transform::createLinearTransform(voxelSize);
    if (shift != openvdb::Vec3d(0.0)) xform->postTranslate(shift);
    return xform;
}

VoxelSet voxelize(const TriangleMesh& mesh, const VoxelizeOptions& options, Interrupter* interrupter)
{
    if (mesh.triangles.empty()) throw Error("the mesh has no triangles");
    openvdb::math::Transform::Ptr xform;
    if (options.lattice) {
        const auto map = options.lattice->baseMap();
        if (!map->isType<openvdb::math::UniformScaleMap>() && !map->isType<openvdb::math::UniformScaleTranslateMap>()) {
            throw UsageError(fmt::format("the voxel lattice must be a uniform scale and translation, not a {}", map->type()));
        }
        if (!(options.bandWidth >= 1.0f) || !std::isfinite(options.bandWidth)) {
            throw UsageError(fmt::format("band must be at least 1 voxel, got {}", options.bandWidth));
        }
        xform = options.lattice->copy();
    } else {
        xform = voxelLattice(mesh.bounds(), resolveVoxelSize(mesh.bounds(), options));
    }
    const double voxelSize = xform->voxelSize()[0];
    const openvdb::Vec3d shift = xform->indexToWorld(openvdb::Vec3d(0.0));
    double area = 0.0;
    for (const auto& t : mesh.triangles) {
        for (int c = 0; c < 3; ++c) {
            if (t[c] >= mesh.points.size()) throw Error(fmt::format("triangle refers to point {} of {}", t[c], mesh.points.size()));
        }
        area += 0.5 * (mesh.points[t[1]] - mesh.points[t[0]]).cross(mesh.points[t[2]] - mesh.points[t[0]]).length();
    }
    // What meshToVolume will allocate, before it does: the surface in voxels times the band's
    // width, each voxel about kVoxelizeBytesPerBandVoxel at its peak.
    const double bandVoxels = area / (voxelSize * voxelSize) * 2.0 * double(options.bandWidth);
    MemoryEstimate estimate = stageMemory(kStageFixedBytes, bandVoxels, kVoxelizeBytesPerBandVoxel);
    estimate.how = fmt::format("the mesh's area {:.4g} is {:.3g} voxels of size {:.4g}, times a band of 2 × {} voxels: {:.3g} "
                               "narrow-band voxels × {:.0f} bytes + {}",
        area, area / (voxelSize * voxelSize), voxelSize, options.bandWidth, bandVoxels, kVoxelizeBytesPerBandVoxel,
        formatBytes(std::uint64_t(kStageFixedBytes)));
    requireMemory("voxelize", estimate);

    // Points relative to the shifted origin, rounded to float and mapped to index space as
    // tools::meshToLevelSet does (so a mesh near the origin gives exactly its voxels).
    const auto unshifted = openvdb::math::Transform::createLinearTransform(voxelSize);
    std::vector<openvdb::Vec3s> indexPoints(mesh.points.size());
    for (size_t i = 0; i < mesh.points.size(); ++i) {
        const openvdb::Vec3s local(mesh.points[i] - shift);
        indexPoints[i] = openvdb::Vec3s(unshifted->worldToIndex(openvdb::Vec3d(local)));
    }

    openvdb::FloatGrid::Ptr surface;
    {
        InterruptStep step(interrupter, "voxelizing");
        openvdb::util::NullInterrupter none;
        openvdb::util::NullInterrupter& progress = interrupter ? *interrupter : none;
        const openvdb::tools::QuadAndTriangleDataAdapter<openvdb::Vec3s, openvdb::Vec3I> adapter(indexPoints, mesh.triangles);
        surface = openvdb::tools::meshToVolume<openvdb::FloatGrid>(progress, adapter, *xform, options.bandWidth, options.bandWidth);
        checkInterrupt(interrupter);
    }
    if (!surface) throw Interrupted();
    surface->setName(grids::kSurface);
    surface->setGridClass(openvdb::GRID_LEVEL_SET);

    openvdb::FloatGrid::Ptr density;
    {
        InterruptStep step(interrupter, "making density");
        density = surface->deepCopy();
        // Fog volume with active tiles of 1 inside (OpenVDB fills the interior) ...
        openvdb::tools::sdfToFogVolume(*density);
        // ... and, in the band, each voxel's volume fraction clamp(½ − φ/dx, 0, 1) instead of
        // sdfToFogVolume's ramp −φ/(band·dx), which thinned the medium by band/2 voxels each
        // side. Trilinear lookups of the fraction cross ½ at the surface, so a ray's optical
        // depth is its chord through the mesh at any voxel size.
        density->tree().topologyUnion(surface->tree());
        const float dx = float(surface->voxelSize()[0]);
        openvdb::tree::LeafManager<openvdb::FloatTree> leaves(density->tree());
        leaves.foreach ([&](openvdb::FloatTree::LeafNodeType& leaf, std::size_t) {
            auto phi = surface->getConstAccessor();
            for (auto it = leaf.beginValueOn(); it; ++it) {
                const float fraction = std::clamp(0.5f - phi.getValue(it.getCoord()) / dx, 0.0f, 1.0f);
                it.setValue(fraction);
                if (fraction == 0.0f) it.setValueOff();
            }
        });
        openvdb::tools::pruneInactive(density->tree());
        openvdb::tools::prune(density->tree()); // leaves of 1 become tiles
        density->setName(grids::kDensity);
        density->setGridClass(openvdb::GRID_FOG_VOLUME);
    }

    VoxelSet set(xform);
    set.put(surface);
    set.put(density);
    return set;
}

} // namespace vxf
