#include <vxf/pipeline/LightScene.h>

#include <vxf/core/GridRoles.h>
#include <vxf/pipeline/SceneGeometry.h>
#include <vxf/pipeline/SceneMedium.h>

#include <fmt/format.h>

namespace vxf {

DirectLightReport lightScene(VoxelSet& set, const Scene& scene, DirectLightOptions options, Interrupter* interrupter)
{
    const Material material = sceneMaterial(scene);
    attachMaterialGrids(set, material);
    if (mediaCount(scene) > 1 && !(set.find(grids::kSigmaA) && set.find(grids::kSigmaS))) {
        throw UsageError(fmt::format("{}: the scene has {} media but the voxel set has no per-voxel sigma_a and sigma_s; "
                                     "voxelize them together (vxf run, or the graph's voxelize with this scene)",
            scene.path, mediaCount(scene)));
    }
    const Medium transport(set, material);
    const Medium medium = options.similarity ? transport.isotropic() : transport;
    const RayScene occluders = sceneGeometry(scene, SceneObject::Role::Occluder);
    options.occluders = occluders.empty() ? nullptr : &occluders;
    const RayScene boundary = sceneGeometry(scene, SceneObject::Role::Medium);
    options.boundary = boundary.empty() ? nullptr : &boundary;
    DirectLightReport report = computeDirectLight(set, medium, scene.lights, options, interrupter);
    recordMaterial(set, material);
    return report;
}

} // namespace vxf
