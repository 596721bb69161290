#include <vxf/pipeline/LightScene.h>

#include <vxf/core/GridRoles.h>
#include <vxf/pipeline/SceneGeometry.h>
#include <vxf/pipeline/SceneMedium.h>
#include <vxf/scatter/Scatter.h>

#include <fmt/format.h>
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
    recordMaterial(set, material);
    return report;
}

} // namespace vxf
