#include <vxf/pipeline/Bake.h>

#include "SceneJson.h"

#include <vxf/core/Error.h>
#include <vxf/core/GridLookup.h>
#include <vxf/core/GridRoles.h>
#include <vxf/io/VoxelSetFile.h>
#include <vxf/light/InteriorField.h>
#include <vxf/light/VolumeEmission.h>
#include <vxf/pipeline/RunPipeline.h>
#include <vxf/pipeline/SceneMedium.h>
#include <vxf/scatter/SourceField.h>
#include <vxf/transport/Medium.h>

#include <openvdb/tree/LeafManager.h>
#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <cmath>
#include <optional>

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

/// What a renderer does with the bake, as the manifest says it.
const char* bakeNote(BakedScattering scattering, double g)
{
    switch (scattering) {
    case BakedScattering::All:
        return "the emission is all of vxf's scattered light: render it over a medium that only absorbs (sigma_a + sigma_s)";
    case BakedScattering::Multiple:
        return g == 0.0 ? "the emission is vxf's multiple scattering: the renderer's single scattering plus it is vxf's image"
                        : "the emission is the isotropic part of the multiple scattering vxf solved in the reduced medium (an "
                          "approximation): add the renderer's single scattering";
    case BakedScattering::None: return "the emission is the volumes' own: the renderer scatters all the light";
    }
    return "";
}

/// The scene a renderer needs around the baked volume: lights, camera, render settings, opaque objects.
json manifestOf(const Scene& scene, const Material& material, double actualG, BakedScattering scattering)
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
                {"note", bakeNote(scattering, actualG)}}},
        {"lights", lights}, {"objects", objects},
        {"camera",
            {{"type", c.orthographic ? "orthographic" : "perspective"}, {"position", vecJson(c.position)}, {"look_at", vecJson(c.lookAt)},
                {"up", vecJson(c.up)}, {"fov", c.fovDegrees}, {"width", c.width}}},
        {"render", {{"width", s.width}, {"height", s.height}, {"background", vecJson(s.background)}}}};
}

/// The lattice a bake is written on: @a factor voxels a side to each of the medium's, their
/// centres spread evenly over its cube (fine voxel k lies at coarse index (k + ½)/factor − ½).
openvdb::math::Transform::Ptr bakeTransform(const openvdb::math::Transform& medium, int factor)
{
    openvdb::math::Transform::Ptr xform = medium.copy();
    if (factor > 1) {
        xform->preTranslate(openvdb::Vec3d(0.5 / factor - 0.5));
        xform->preScale(1.0 / factor);
    }
    return xform;
}

/// The baked density's topology: every fine voxel of the medium's active voxels and tiles.
openvdb::FloatGrid::Ptr bakeTopology(const openvdb::FloatGrid& density, int factor)
{
    auto fine = openvdb::FloatGrid::create(0.0f);
    fine->setTransform(bakeTransform(density.transform(), factor));
    if (factor == 1) {
        fine->topologyUnion(density);
    } else {
        // Each active voxel or tile [lo, hi] covers the fine voxels [lo·factor, (hi + 1)·factor − 1].
        const auto scaled = [factor](const openvdb::Coord& c) { return openvdb::Coord(c.x() * factor, c.y() * factor, c.z() * factor); };
        for (auto it = density.cbeginValueOn(); it; ++it) {
            const openvdb::CoordBBox box = it.getBoundingBox();
            fine->tree().sparseFill(openvdb::CoordBBox(scaled(box.min()), scaled(box.max().offsetBy(1)).offsetBy(-1)), 0.0f, true);
        }
    }
    // Each voxel gets its own values: a mesh medium's interior is tiles, and the light varies there.
    fine->tree().voxelizeActiveTiles();
    return fine;
}

} // namespace

int bakeSupersampling(const VoxelSet& set, int requested)
{
    if (requested > 0) return requested;
    return set.find(grids::kSurface) ? kBakeSurfaceSupersampling : 1;
}

BakedVolume bakeScene(const Scene& scene, const std::string& outDir, const BakeOptions& options, Interrupter* interrupter)
{
    if (options.supersample < 0 || options.supersample > kBakeMaxSupersampling) {
        throw Error(fmt::format(
            "bake: supersample is {}, out of range (expected 0 for automatic, or 1 to {})", options.supersample, kBakeMaxSupersampling));
    }
    Scene solved = scene;
    solved.settings.outputs = {"scatter"}; // the chain up to the scattered light, no image
    const PipelineReport report = runPipeline(solved, outDir, interrupter);
    const VoxelSet set = readVoxelSet(report.volume);
    const Material material = sceneMaterial(scene);
    const Medium medium(set, material);
    // The grids' J as the render reads it (CameraTracer's RenderContext): in the transport's
    // medium where the solve carried the phase's first moment, its isotropic one otherwise.
    const bool firstMoment = material.phaseG != 0.0 && set.find(grids::kScatterAnisotropy);
    const Medium gridMedium = firstMoment ? medium : medium.isotropic();
    const auto& density = *set.get<openvdb::FloatGrid>(grids::kDensity);
    std::optional<InteriorField> directField;
    std::optional<SourceField> scatterField;
    if (options.scattering == BakedScattering::All && set.find(grids::kDirect)) {
        directField.emplace(gridMedium, *set.get<openvdb::Vec3SGrid>(grids::kDirect));
    }
    if (options.scattering != BakedScattering::None && set.find(grids::kScatter)) {
        scatterField.emplace(
            gridMedium, *sourceFromFluence(gridMedium, *set.get<openvdb::Vec3SGrid>(grids::kScatter)), SourceField::Near::Layers);
    }
    std::vector<VolumeEmission> emitters;
    for (const Light& l : scene.lights) {
        if (l.type == Light::Type::Volume && l.power() != openvdb::Vec3d(0.0)) emitters.emplace_back(l);
    }

    // Each baked voxel holds the medium and the light the render reads at its centre, inside
    // the surface; a mesh medium's are scaled by the part of the voxel inside (the volume
    // fraction of its centre's signed distance), so that a renderer's trilinear read of the
    // two grids holds the surface to a fraction of a voxel and never darkens J near it.
    const int factor = bakeSupersampling(set, options.supersample);
    const bool hasSurface = medium.surface() != nullptr;
    auto baked = bakeTopology(density, factor);
    auto emission = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    emission->setTransform(baked->transformPtr());
    emission->topologyUnion(*baked);
    struct PerThread
    {
        Medium::Sampler medium;
        GridLookup<openvdb::FloatGrid> density;
        std::optional<InteriorField::Sampler> direct;
        std::optional<SourceField::Sampler> scatter;
        std::vector<VolumeEmission::Sampler> emitters;
    };
    tbb::enumerable_thread_specific<PerThread> local([&] {
        PerThread t{Medium::Sampler(medium), GridLookup<openvdb::FloatGrid>(density, nullptr), std::nullopt, std::nullopt, {}};
        if (directField) t.direct.emplace(*directField);
        if (scatterField) t.scatter.emplace(*scatterField);
        for (const VolumeEmission& e : emitters) t.emitters.emplace_back(e);
        return t;
    });
    openvdb::tree::LeafManager<openvdb::FloatTree> leaves(baked->tree());
    leaves.foreach ([&](openvdb::FloatTree::LeafNodeType& leaf, std::size_t) {
        PerThread& t = local.local();
        auto* out = emission->tree().probeLeaf(leaf.origin());
        for (auto it = leaf.beginValueOn(); it; ++it) {
            const openvdb::Vec3d p = (openvdb::Vec3d(it.getCoord().asVec3d()) + 0.5) / factor - 0.5; // the medium's index space
            double fraction = 1.0, scale = 1.0;
            if (hasSurface) {
                fraction = std::clamp(0.5 - t.medium.signedDistance(p) * factor, 0.0, 1.0);
                scale = t.medium.interiorScale(p);
            }
            openvdb::Vec3d e(0.0);
            if (fraction > 0.0) {
                if (t.direct) e += t.direct->sample(p);
                if (t.scatter) e += t.scatter->sample(p);
            }
            if (!t.emitters.empty()) {
                const openvdb::Vec3d world = baked->transform().indexToWorld(it.getCoord());
                for (VolumeEmission::Sampler& s : t.emitters) e += s.at(world);
            }
            it.setValue(float(fraction * scale * t.density.sampleTrilinear(p)));
            out->setValueOnly(it.pos(), openvdb::Vec3f(e * fraction));
        }
    });
    emission->setName("emission");
    emission->setGridClass(openvdb::GRID_FOG_VOLUME);
    baked->setName(grids::kDensity);
    baked->setGridClass(openvdb::GRID_FOG_VOLUME);

    BakedVolume result{VoxelSet(baked->transformPtr()), manifestOf(scene, material, material.phaseG, options.scattering)};
    result.manifest["scattering"] = options.scattering == BakedScattering::All ? "all"
        : options.scattering == BakedScattering::Multiple                      ? "multiple"
                                                                               : "none";
    result.manifest["supersample"] = factor;
    // The grids keep OpenVDB's placement (voxel centres on the transform's points: Houdini, Karma,
    // Arnold); a renderer that spreads voxel i over [i, i+1] (Blender's Cycles) moves the volume
    // back by this half voxel (io/VoxelPlacement.h).
    const openvdb::Vec3d half = baked->transform().indexToWorld(openvdb::Vec3d(0.5)) - baked->transform().indexToWorld(openvdb::Vec3d(0.0));
    result.manifest["half_voxel"] = vecJson(half);
    result.set.put(baked);
    result.set.put(emission);
    result.set.setProvenance("bake", result.manifest.dump());
    return result;
}

} // namespace vxf
