#include <vxf/pipeline/SceneFile.h>

#include "QualityPreset.h"
#include "SceneAnimation.h"

#include <vxf/pipeline/Knobs.h>
#include <vxf/pipeline/SceneGeometry.h>
#include <vxf/pipeline/SceneMedium.h>

#include <vxf/io/InputFile.h>
#include <vxf/scatter/ScatterPass.h>

#include <vxf/core/Error.h>
#include <vxf/io/JsonDocument.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>

namespace vxf {

/// A scene is a page of JSON; a file past this is not one.
constexpr std::uintmax_t kMaxSceneBytes = std::uintmax_t(64) << 20;

namespace {

using nlohmann::json;

const JsonSchema& sceneSchema()
{
    static const JsonSchema schema(sceneSchemaDocument(), "schemas/scene.schema.json");
    return schema;
}

class SceneReader
{
public:
    SceneReader(std::string path)
        : mPath(std::move(path))
    {
    }

    [[noreturn]] void fail(const std::string& where, const std::string& what) const
    {
        throw InputError(mPath, 0, 0, fmt::format("{}: {}", where, what));
    }

    openvdb::Vec3d vec3(const json& j) const { return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()}; }

    openvdb::Vec3d rgb(const json& j) const
    {
        if (j.is_number()) return openvdb::Vec3d(j.get<double>());
        return vec3(j);
    }

    openvdb::Vec3d direction(const json& j, const std::string& where) const
    {
        const openvdb::Vec3d d = vec3(j);
        const double length = d.length();
        if (!(length > 1e-12) || !std::isfinite(length)) fail(where, "a direction must be a non-zero vector");
        return d / length;
    }

    std::string resolvePath(const std::string& relative) const
    {
        if (relative.rfind("builtin:", 0) == 0) return relative;
        const std::filesystem::path p(relative);
        if (p.is_absolute()) return relative;
        return (std::filesystem::path(mPath).parent_path() / p).lexically_normal().string();
    }

    openvdb::Mat4d transform(const json& j) const
    {
        openvdb::Mat4d m = openvdb::Mat4d::identity();
        if (j.contains("scale")) {
            const openvdb::Vec3d s = j["scale"].is_number() ? openvdb::Vec3d(j["scale"].get<double>()) : vec3(j["scale"]);
            m.postScale(s);
        }
        if (j.contains("rotate")) {
            const openvdb::Vec3d r = vec3(j["rotate"]) * (M_PI / 180.0);
            m.postRotate(openvdb::math::X_AXIS, r[0]);
            m.postRotate(openvdb::math::Y_AXIS, r[1]);
            m.postRotate(openvdb::math::Z_AXIS, r[2]);
        }
        if (j.contains("translate")) m.postTranslate(vec3(j["translate"]));
        return m;
    }

    Material material(const json& j, const std::string& where) const
    {
        Material m;
        if (j.contains("sigma_a")) {
            m.sigmaA = rgb(j["sigma_a"]);
            m.sigmaS = rgb(j["sigma_s"]);
        } else {
            // sigma_t = 1/mfp, sigma_s = albedo sigma_t, sigma_a = sigma_t - sigma_s (>= 0 as albedo <= 1).
            const openvdb::Vec3d albedo = rgb(j["albedo"]), mfp = rgb(j["mean_free_path"]);
            for (int c = 0; c < 3; ++c) {
                const double sigmaT = 1.0 / mfp[c];
                if (!std::isfinite(sigmaT)) fail(where + "/mean_free_path", "too small: sigma_t = 1/mean_free_path overflows");
                m.sigmaS[c] = albedo[c] * sigmaT;
                m.sigmaA[c] = std::max(0.0, sigmaT - m.sigmaS[c]);
            }
        }
        if (j.contains("phase")) m.phaseG = j["phase"].value("g", 0.0);
        if (j.contains("grids")) {
            const json& g = j["grids"];
            m.gridsFile = resolvePath(g["file"].get<std::string>());
            m.sigmaAGrid = g.value("sigma_a", std::string());
            m.sigmaSGrid = g.value("sigma_s", std::string());
            if (m.sigmaAGrid.empty() && m.sigmaSGrid.empty()) {
                fail(where + "/grids", "name at least one of sigma_a and sigma_s");
            }
        }
        return m;
    }

    /// The light's strength must leave room in 32-bit floats for what the stages multiply it
    /// by (1/r² near a point light, σs, the passes' sums): a light of 1e37 scattered to all
    /// zeros (overflowing to infinity, then dropped as non-finite) without a word.
    void checkPower(const Light& l, const std::string& where) const
    {
        const double power = std::abs(l.intensity) * std::max({l.color[0], l.color[1], l.color[2]});
        if (!(power <= kMaxLightPower)) {
            fail(where + "/intensity",
                fmt::format("intensity × colour is {:.3g}, beyond the {:.0e} vxf carries (its grids hold "
                            "32-bit floats, up to 3.4e38, and the stages multiply a light by distances and "
                            "densities); scale the scene's units instead",
                    power, kMaxLightPower));
        }
    }

    Light light(const json& j, const std::string& where) const
    {
        static const std::map<std::string, Light::Type> types = {{"point", Light::Type::Point}, {"spot", Light::Type::Spot},
            {"directional", Light::Type::Directional}, {"area", Light::Type::Area}, {"volume", Light::Type::Volume},
            {"environment", Light::Type::Environment}};
        Light l;
        l.type = types.at(j["type"].get<std::string>());
        l.name = j.value("name", fmt::format("{}{}", j["type"].get<std::string>(), where.substr(where.rfind('/') + 1)));
        if (j.contains("color")) l.color = rgb(j["color"]);
        l.intensity = j.value("intensity", 1.0);
        checkPower(l, where);
        const std::string falloff = j.value("falloff", std::string("inverse_square"));
        l.falloff = falloff == "linear" ? Light::Falloff::Linear : falloff == "none" ? Light::Falloff::None : Light::Falloff::InverseSquare;
        if (j.contains("position")) l.position = vec3(j["position"]);
        if (j.contains("direction")) l.direction = direction(j["direction"], where + "/direction");
        l.coneAngleDegrees = j.value("cone_angle", 0.0);
        l.coneSoftnessDegrees = j.value("cone_softness", 0.0);
        if (l.coneSoftnessDegrees > l.coneAngleDegrees * 0.5 && l.type == Light::Type::Spot) {
            fail(where + "/cone_softness",
                fmt::format("the soft edge ({} degrees) must fit inside half the cone ({} degrees)", l.coneSoftnessDegrees,
                    l.coneAngleDegrees * 0.5));
        }
        const std::string shape = j.value("shape", std::string("rectangle"));
        l.shape = shape == "disk" ? Light::Shape::Disk : shape == "sphere" ? Light::Shape::Sphere : Light::Shape::Rectangle;
        if (j.contains("size")) {
            l.width = j["size"][0].get<double>();
            l.height = j["size"][1].get<double>();
        }
        l.radius = j.value("radius", l.radius);
        l.samples = j.value("samples", l.type == Light::Type::Environment ? 64 : 16);
        if (j.contains("file")) l.file = resolvePath(j["file"].get<std::string>());
        l.grid = j.value("grid", std::string());
        l.placement = placement(j);
        blackbody(j, l);
        return l;
    }

    /// A volume object's "emission": a volume light on a grid of its own file, placed as the
    /// object is (Light::gridToWorld), named OBJECT.emission.
    Light objectEmission(const json& j, const SceneObject& object) const
    {
        Light l;
        l.type = Light::Type::Volume;
        l.name = object.name + ".emission";
        l.file = object.volume;
        l.grid = j["grid"].get<std::string>();
        if (j.contains("color")) l.color = rgb(j["color"]);
        l.intensity = j.value("intensity", 1.0);
        checkPower(l, "/objects/" + object.name + "/emission");
        l.gridToWorld = object.objectToWorld;
        l.placement = object.placement;
        blackbody(j, l);
        return l;
    }

    /// A `blackbody` block: the grid is a temperature of `temperature` Kelvin per unit, and the
    /// light's intensity takes the block's `intensity` (Blender's Principled Volume Temperature and
    /// Blackbody Intensity).
    static void blackbody(const json& j, Light& l)
    {
        if (!j.contains("blackbody")) return;
        l.blackbodyKelvin = j["blackbody"].value("temperature", 1.0);
        l.intensity *= j["blackbody"].value("intensity", 1.0);
    }

    /// `voxel_placement` of a volume object or light: auto (the default), centre or cell.
    static VoxelPlacement placement(const json& j)
    {
        const std::string p = j.value("voxel_placement", std::string("auto"));
        return p == "centre" ? VoxelPlacement::Centre : p == "cell" ? VoxelPlacement::Cell : VoxelPlacement::Auto;
    }

    Camera camera(const json& j) const
    {
        Camera c;
        c.orthographic = j.value("type", std::string("perspective")) == "orthographic";
        c.position = vec3(j["position"]);
        c.lookAt = vec3(j["look_at"]);
        if (j.contains("up")) c.up = vec3(j["up"]);
        c.fovDegrees = j.value("fov", c.fovDegrees);
        c.width = j.value("width", c.width);
        const openvdb::Vec3d view = c.lookAt - c.position;
        if (!(view.length() > 1e-12)) fail("/camera/look_at", "must differ from /camera/position");
        if (!(c.up.length() > 1e-12)) fail("/camera/up", "must be a non-zero vector");
        if (view.unit().cross(c.up.unit()).length() < 1e-6) fail("/camera/up", "must not point along the view direction");
        return c;
    }

    const std::string mPath;
};

/// The scene's settings (voxelize, scatter, render, outputs) over the defaults; a medium of an
/// anisotropic phase (@a medium's g ≠ 0) changes two of them, as schemas/scene.schema.json says.
/// An error asked for (@a quality, else the document's `quality`) puts the setting the accuracy
/// bench chose for it between the defaults and the scene's own blocks.
SceneSettings readSettings(const json& document, const detail::QualityMedium& medium, std::optional<QualityRequest> quality)
{
    SceneSettings s;
    // A volume object is solved on its own voxels unless the scene (or its quality) asks for a
    // voxel size or dim (then coarsened by halvings: SceneMedium.h): no default dim applies to it.
    if (medium.volume) s.dim = 0;
    const double phaseG = medium.phaseG;
    const bool anisotropic = phaseG != 0.0;
    // An anisotropic phase shows in single scattering marched to the lights; the direct grid's is isotropic.
    s.directFromLights = anisotropic;
    // A forward phase's anisotropy only the accelerated sweeps carry (Phase.h, Scatter.h).
    if (anisotropic) s.kernel = defaultScatterKernel(phaseG);
    if (!quality && document.contains("quality")) {
        const json& q = document["quality"];
        quality = q.is_string() ? qualityRequestForLevel(q.get<std::string>()) : QualityRequest{q["error"].get<double>(), ""};
    }
    if (quality) s.quality = detail::applyQuality(*quality, medium, document, s);
    readKnobs(document, s); // the scene's own blocks win over the quality's setting
    if (document.contains("outputs")) s.outputs = document["outputs"].get<std::vector<std::string>>();
    return s;
}

/// A medium's size in mean free paths (for `quality`): the longest side of its media's joint
/// bounds × σt (the mean of @a first's channels; a volume's at density 1). Reads the meshes
/// (objectMesh keeps them for the voxelize stage), or a volume object's grid (volumeBounds; 0
/// when it cannot be read).
double opticalSize(const Scene& scene, const SceneObject& first)
{
    openvdb::BBoxd bounds;
    for (const SceneObject& o : scene.objects) {
        if (o.role == SceneObject::Role::Medium && !o.isVolume()) bounds.expand(objectMesh(o).bounds());
    }
    if (first.isVolume()) {
        try {
            bounds = volumeBounds(first);
        } catch (const Error&) {
            return 0.0; // unknown: the voxelize stage reports the file's error when it reads it
        }
    }
    const openvdb::Vec3d sigmaT = first.material->sigmaT();
    const openvdb::Vec3d extent = bounds.extents();
    return bounds.isSorted() ? std::max({extent[0], extent[1], extent[2]}) * (sigmaT[0] + sigmaT[1] + sigmaT[2]) / 3.0 : 0.0;
}

} // namespace

namespace {

/// The scene document of @a text, checked, at @a frame when it is animated.
json sceneDocument(const std::string& text, const std::string& path, std::optional<int> frame)
{
    const json raw = parseJsonText(text, path);
    sceneSchema().check(raw, path);
    const std::vector<std::string> animated = detail::animatedValues(raw);
    if (animated.empty()) return raw;
    if (!frame) {
        throw InputError(path, 0, 0,
            fmt::format("the scene is animated ({}{}): render it frame by frame (vxf run SCENE --frames FIRST-LAST)", animated.front(),
                animated.size() > 1 ? fmt::format(" and {} more", animated.size() - 1) : std::string()));
    }
    json document = detail::sceneAtFrame(raw, *frame, path);
    try {
        sceneSchema().check(document, path);
    } catch (const InputError& e) {
        throw InputError(path, 0, 0, fmt::format("at frame {}: {}", *frame, std::string(e.what()).substr(path.size() + 2)));
    }
    return document;
}

} // namespace

Scene parseScene(const std::string& text, const std::string& path, std::optional<int> frame, const std::optional<QualityRequest>& quality)
{
    const json document = sceneDocument(text, path, frame);

    SceneReader reader(path);
    Scene scene;
    scene.path = path;
    scene.frame = frame;
    std::vector<Light> emitting; // the volume objects' emission, as volume lights that move with them
    for (std::size_t i = 0; i < document["objects"].size(); ++i) {
        const json& o = document["objects"][i];
        const std::string where = fmt::format("/objects/{}", i);
        SceneObject object;
        object.name = o.value("name", fmt::format("object{}", i));
        if (o.contains("mesh")) {
            object.mesh = reader.resolvePath(o["mesh"].get<std::string>());
        } else {
            object.volume = reader.resolvePath(o["volume"].get<std::string>());
            object.grid = o.value("grid", object.grid);
            object.placement = reader.placement(o);
        }
        object.objectToWorld = o.contains("transform") ? reader.transform(o["transform"]) : openvdb::Mat4d::identity();
        const std::string role = o.value("role", std::string("medium"));
        object.role = role == "occluder" ? SceneObject::Role::Occluder
            : role == "emitter"          ? SceneObject::Role::Emitter
                                         : SceneObject::Role::Medium;
        if (object.isVolume() && object.role != SceneObject::Role::Medium) {
            reader.fail(where + "/role", "a volume object is a medium (its grid is the medium's density); an opaque object needs a mesh");
        }
        if (!object.isVolume() && o.contains("voxel_placement")) {
            reader.fail(where + "/voxel_placement", "places a volume object's voxels; this object has a mesh");
        }
        if (!object.isVolume() && o.contains("grid")) {
            reader.fail(where + "/grid", "names the grid of a volume object; this object has a mesh");
        }
        if (object.isVolume() && o.contains("surface")) {
            reader.fail(where + "/surface", "a volume object has no surface to shade (its look is the volume term)");
        }
        if (o.contains("material")) object.material = reader.material(o["material"], where + "/material");
        if (object.role == SceneObject::Role::Medium && !object.material) {
            reader.fail(where, "a medium object needs a material (or set \"role\": \"occluder\")");
        }
        if (object.role == SceneObject::Role::Occluder) object.surface.diffuse = openvdb::Vec3d(0.5);
        if (o.contains("surface")) {
            const json& f = o["surface"];
            if (f.contains("diffuse")) object.surface.diffuse = reader.rgb(f["diffuse"]);
            if (f.contains("specular")) object.surface.specular = reader.rgb(f["specular"]);
            object.surface.shininess = f.value("shininess", object.surface.shininess);
            if (f.contains("emission")) object.surface.emission = reader.rgb(f["emission"]);
        }
        if (object.role == SceneObject::Role::Medium && object.surface.emission != openvdb::Vec3d(0.0)) {
            reader.fail(where + "/surface/emission", "only an occluder or an emitter emits (a medium's glow is a volume light)");
        }
        if (object.role == SceneObject::Role::Emitter && object.surface.emission == openvdb::Vec3d(0.0)) {
            reader.fail(where + "/surface/emission", "an emitter needs a non-zero emission");
        }
        if (o.contains("emission")) {
            if (!object.isVolume()) {
                reader.fail(where + "/emission", "names a grid of a volume object's file; a mesh medium's glow is a volume light");
            }
            emitting.push_back(reader.objectEmission(o["emission"], object));
        }
        scene.objects.push_back(std::move(object));
    }
    for (std::size_t i = 0; i < document["lights"].size(); ++i) {
        scene.lights.push_back(reader.light(document["lights"][i], fmt::format("/lights/{}", i)));
    }
    // Objects' emission after the scene's lights: a light's index in the scene stays its index in the file.
    for (Light& l : emitting) scene.lights.push_back(std::move(l));
    scene.camera = reader.camera(document["camera"]);

    // One phase for the scene's media: the voxel set's coefficient grids sum the objects'
    // σs, which a per-object g would have to weigh voxel by voxel.
    const SceneObject* firstMedium = nullptr;
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
        const SceneObject& o = scene.objects[i];
        if (o.role != SceneObject::Role::Medium) continue;
        if (!firstMedium) {
            firstMedium = &o;
        } else if (o.material->phaseG != firstMedium->material->phaseG) {
            reader.fail(fmt::format("/objects/{}/material/phase/g", i),
                fmt::format("{} differs from medium '{}''s {}: every medium of a scene has the same phase", o.material->phaseG,
                    firstMedium->name, firstMedium->material->phaseG));
        }
    }
    detail::QualityMedium medium;
    if (firstMedium) {
        const openvdb::Vec3d albedo = firstMedium->material->albedo();
        medium = {firstMedium->isVolume(), (albedo[0] + albedo[1] + albedo[2]) / 3.0, firstMedium->material->phaseG, 0.0};
        if (quality || document.contains("quality")) medium.opticalSize = opticalSize(scene, *firstMedium);
    }
    scene.settings = readSettings(document, medium, quality);
    // The environment lights' samples the quality's setting names, where a light sets none.
    if (scene.settings.quality && scene.settings.quality->environmentSamples > 0) {
        for (std::size_t i = 0; i < document["lights"].size(); ++i) {
            if (scene.lights[i].type == Light::Type::Environment && !document["lights"][i].contains("samples"))
                scene.lights[i].samples = scene.settings.quality->environmentSamples;
        }
    }
    return scene;
}

Scene loadScene(const std::string& path, std::optional<int> frame, const std::optional<QualityRequest>& quality)
{
    return parseScene(readBoundedFile(path, kMaxSceneBytes, "a scene file"), path, frame, quality);
}

} // namespace vxf
