#include <vxf/pipeline/Bake.h>

#include "SceneJson.h"

#include <vxf/core/GridRoles.h>
#include <vxf/io/VoxelSetFile.h>
#include <vxf/light/VolumeEmission.h>
#include <vxf/pipeline/RunPipeline.h>
#include <vxf/pipeline/SceneMedium.h>
#include <vxf/transport/Medium.h>

#include <openvdb/tree/LeafManager.h>
#include <tbb/enumerable_thread_specific.h>

#include <cmath>

namespace vxf {

namespace {

using nlohmann::json;

using detail::matrixJson;
using detail::vecJson;

json bakedLight(const Light& l)
{
    static const char* types[] = {"point", "spot", "directional", "area", "volume", "environment"};
    static const char* shapes[] = {"rectangle", "disk", "sphere"};
    return {{"type", types[int(l.type)]}, {"name", l.name}, {"color", vecJson(l.color)}, {"intensity", l.intensity},
        {"position", vecJson(l.position)}, {"direction", vecJson(l.direction)}, {"cone_angle", l.coneAngleDegrees},
        {"cone_softness", l.coneSoftnessDegrees}, {"shape", shapes[int(l.shape)]}, {"size", {l.width, l.height}}, {"radius", l.radius},
        {"baked", l.type == Light::Type::Volume}};
}

/// The scene a renderer needs around the baked volume: lights, camera, render settings, opaque objects.
json manifestOf(const Scene& scene, const Material& material, double actualG)
{
    json lights = json::array();
    for (const Light& l : scene.lights) lights.push_back(bakedLight(l));
    json objects = json::array();
    for (const SceneObject& o : scene.objects) {
        const char* role = o.role == SceneObject::Role::Medium ? "medium" : o.role == SceneObject::Role::Occluder ? "occluder" : "emitter";
        objects.push_back({{"name", o.name}, {"role", role}, {"mesh", o.mesh}, {"volume", o.volume},
            {"object_to_world", matrixJson(o.objectToWorld)}, {"diffuse", vecJson(o.surface.diffuse)},
            {"specular", vecJson(o.surface.specular)}, {"shininess", o.surface.shininess}, {"emission", vecJson(o.surface.emission)}});
    }
    const Camera& c = scene.camera;
    const SceneSettings& s = scene.settings;
    return {{"grids", {{"density", grids::kDensity}, {"emission", "emission"}}},
        {"medium",
            {{"sigma_a", vecJson(material.sigmaA)}, {"sigma_s", vecJson(material.sigmaS)}, {"phase_g", actualG},
                {"note",
                    actualG == 0.0 ? "isotropic: the renderer's single scattering plus the baked emission is vxf's image"
                                   : "anisotropic: the baked emission is the isotropic part of the multiple scattering vxf "
                                     "solved in the reduced medium (an approximation)"}}},
        {"lights", lights}, {"objects", objects},
        {"camera",
            {{"type", c.orthographic ? "orthographic" : "perspective"}, {"position", vecJson(c.position)}, {"look_at", vecJson(c.lookAt)},
                {"up", vecJson(c.up)}, {"fov", c.fovDegrees}, {"width", c.width}}},
        {"render", {{"width", s.width}, {"height", s.height}, {"background", vecJson(s.background)}}}};
}

} // namespace

BakedVolume bakeScene(const Scene& scene, const std::string& outDir, BakedScattering scattering, Interrupter* interrupter)
{
    Scene solved = scene;
    solved.settings.outputs = {"scatter"}; // the chain up to the scattered light, no image
    const PipelineReport report = runPipeline(solved, outDir, interrupter);
    const VoxelSet set = readVoxelSet(report.volume);
    const Material material = sceneMaterial(scene);
    const Medium medium(set, material);
    auto density = openvdb::gridPtrCast<openvdb::FloatGrid>(set.find(grids::kDensity)->deepCopyGrid());
    const auto scatter = scattering != BakedScattering::None && set.find(grids::kScatter) ? set.get<openvdb::Vec3SGrid>(grids::kScatter)
                                                                                          : openvdb::Vec3SGrid::Ptr();
    const auto direct = scattering == BakedScattering::All && set.find(grids::kDirect) ? set.get<openvdb::Vec3SGrid>(grids::kDirect)
                                                                                       : openvdb::Vec3SGrid::Ptr();

    // Emission on the medium's voxels: σs·φ/4π of the scattered light, plus the volume lights'.
    auto emission = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    emission->setTransform(density->transformPtr());
    emission->topologyUnion(*density);
    std::vector<VolumeEmission> emitters;
    for (const Light& l : scene.lights) {
        if (l.type == Light::Type::Volume && l.power() != openvdb::Vec3d(0.0)) emitters.emplace_back(l);
    }
    struct PerThread
    {
        Medium::Sampler medium;
        std::vector<VolumeEmission::Sampler> emitters;
        std::optional<openvdb::Vec3SGrid::ConstAccessor> scatter, direct;
    };
    tbb::enumerable_thread_specific<PerThread> local([&] {
        PerThread t{Medium::Sampler(medium), {}, std::nullopt, std::nullopt};
        for (const VolumeEmission& e : emitters) t.emitters.emplace_back(e);
        if (scatter) t.scatter.emplace(scatter->getConstAccessor());
        if (direct) t.direct.emplace(direct->getConstAccessor());
        return t;
    });
    openvdb::tree::LeafManager<openvdb::Vec3STree> leaves(emission->tree());
    leaves.foreach ([&](openvdb::Vec3STree::LeafNodeType& leaf, std::size_t) {
        PerThread& t = local.local();
        for (auto it = leaf.beginValueOn(); it; ++it) {
            const openvdb::Coord ijk = it.getCoord();
            openvdb::Vec3d phi(0.0); // the fluence the emission scatters
            if (t.scatter) phi += openvdb::Vec3d(t.scatter->getValue(ijk));
            if (t.direct) phi += openvdb::Vec3d(t.direct->getValue(ijk));
            openvdb::Vec3d e = t.medium.sigmaS(ijk) * phi / (4.0 * M_PI);
            const openvdb::Vec3d world = emission->transform().indexToWorld(ijk);
            for (VolumeEmission::Sampler& s : t.emitters) e += s.at(world);
            it.setValue(openvdb::Vec3f(e));
        }
    });
    emission->setName("emission");
    emission->setGridClass(openvdb::GRID_FOG_VOLUME);
    density->setName(grids::kDensity);

    BakedVolume baked{VoxelSet(density->transformPtr()), manifestOf(scene, material, material.phaseG)};
    baked.manifest["scattering"] = scattering == BakedScattering::All ? "all"
        : scattering == BakedScattering::Multiple                     ? "multiple"
                                                                      : "none";
    // The grids keep OpenVDB's placement (voxel centres on the transform's points: Houdini, Karma,
    // Arnold); a renderer that spreads voxel i over [i, i+1] (Blender's Cycles) moves the volume
    // back by this half voxel (io/VoxelPlacement.h).
    const openvdb::Vec3d half =
        density->transform().indexToWorld(openvdb::Vec3d(0.5)) - density->transform().indexToWorld(openvdb::Vec3d(0.0));
    baked.manifest["half_voxel"] = vecJson(half);
    baked.set.put(density);
    baked.set.put(emission);
    baked.set.setProvenance("bake", baked.manifest.dump());
    return baked;
}

} // namespace vxf
