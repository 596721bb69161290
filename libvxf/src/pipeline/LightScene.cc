#include <vxf/pipeline/LightScene.h>

#include <vxf/core/GridRoles.h>
#include <vxf/pipeline/SceneGeometry.h>
#include <vxf/pipeline/SceneMedium.h>
#include <vxf/scatter/Scatter.h>

#include <fmt/format.h>

#include <algorithm>
#include <tbb/task_group.h>

namespace vxf {

DirectLightOptions lightOptionsFrom(const SceneSettings& settings)
{
    DirectLightOptions o;
    o.march.step = settings.step;
    o.band = settings.scatterBand;
    o.similarity = !carriesFirstMoment(scatterOptionsFrom(settings));
    return o;
}

namespace {

/// A warning when the medium's mean free path at density 1 (its shortest channel's) is under
/// half a voxel: the light that leaves a surface comes from within about a mean free path of it,
/// which such voxels cannot hold, and the image comes out dark (measured: docs/accuracy-notes.md
/// (at)). "" when it is resolved, or its coefficients are per-voxel grids.
std::string unresolvedMedium(const Material& material, double voxelSize)
{
    const openvdb::Vec3d sigmaT = material.sigmaT();
    const double largest = std::max({sigmaT[0], sigmaT[1], sigmaT[2]});
    if (!material.gridsFile.empty() || !(largest * voxelSize > 2.0)) return {};
    const double mfp = 1.0 / largest;
    return fmt::format("the medium's mean free path ({:.3g} at density 1) is {:.2g} of a voxel ({:.3g}): the light that leaves "
                       "the medium comes from within a fraction of a voxel of its edge, which these voxels cannot resolve, so the image "
                       "comes out darker than the medium is; voxels of at most twice the mean free path (voxelize.voxel_size {:.3g}) "
                       "resolve it",
        mfp, mfp / voxelSize, voxelSize, 2.0 * mfp);
}

} // namespace

DirectLightReport lightScene(VoxelSet& set, const Scene& scene, DirectLightOptions options, Interrupter* interrupter)
{
    const Material material = sceneMaterial(scene);
    attachMaterialGrids(set, material);
    if (mediaCount(scene) > 1 && !(set.find(grids::kSigmaA) && set.find(grids::kSigmaS))) {
        throw UsageError(fmt::format("{}: the scene has {} media but the voxel set has no per-voxel sigma_a and sigma_s; "
                                     "voxelize them together (vxf run, or the graph's voxelize with this scene)",
            scene.path, mediaCount(scene)));
    }
    // The meshes are read and their ray scenes built (mostly on one thread) while the medium
    // makes its dense copies (in parallel): the thick bunny at dim 256, 0.12 and 0.07 s.
    RayScene occluders, boundary;
    tbb::task_group meshes;
    meshes.run([&] {
        occluders = sceneGeometry(scene, SceneObject::Role::Occluder);
        boundary = sceneGeometry(scene, SceneObject::Role::Medium);
    });
    const Medium transport(set, material);
    meshes.wait();
    const Medium medium = options.similarity ? transport.isotropic() : transport;
    options.occluders = occluders.empty() ? nullptr : &occluders;
    options.boundary = boundary.empty() ? nullptr : &boundary;
    DirectLightReport report = computeDirectLight(set, medium, scene.lights, options, interrupter);
    if (const std::string unresolved = unresolvedMedium(material, transport.voxelSize()); !unresolved.empty())
        report.warnings.push_back(unresolved);
    recordMaterial(set, material);
    return report;
}

} // namespace vxf
