#include <vxf/pipeline/SceneFile.h>

#include <vxf/core/Error.h>
#include <vxf/scatter/Scatter.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <filesystem>

namespace {

const char* kScene = R"({
  "objects": [
    {"name": "grape", "mesh": "meshes/grape.obj", "transform": {"scale": 2, "rotate": [0, 0, 90], "translate": [1, 0, 0]},
     "material": {"albedo": [0.8, 0.5, 0.0], "mean_free_path": 0.5}},
    {"mesh": "builtin:box", "role": "occluder"},
    {"mesh": "/abs/wax.ply", "material": {"sigma_a": [0.1, 0.2, 0.3], "sigma_s": 2,
                                          "grids": {"file": "coeffs.vdb", "sigma_s": "sigma_s"}}}
  ],
  "lights": [
    {"type": "point", "position": [0, 0, 3], "color": [1, 0.5, 0.25], "intensity": 4},
    {"type": "spot", "position": [0, 0, 3], "direction": [0, 0, -2], "cone_angle": 40, "cone_softness": 5, "falloff": "linear"},
    {"type": "directional", "direction": [1, 1, 0]},
    {"type": "area", "shape": "rectangle", "position": [0, 2, 2], "direction": [0, -1, 0], "size": [1, 0.5], "samples": 9},
    {"type": "volume", "file": "fire.vdb", "grid": "emission"},
    {"type": "environment", "color": 0.1}
  ],
  "camera": {"position": [0, -5, 1], "look_at": [0, 0, 1], "fov": 30},
  "voxelize": {"voxel_size": 0.01, "band": 4},
  "scatter": {"passes": 8, "directions": 32, "step": 0.5, "tolerance": 0.01, "band": 0.2, "cutoff": 0.01},
  "render": {"width": 320, "height": 200, "samples": 2, "mode": "gather", "background": [0.1, 0.2, 0.3]},
  "outputs": ["image", "direct"]
})";

vxf::Scene parse(const std::string& text) { return vxf::parseScene(text, "/scenes/test.json"); }

std::string errorOf(const std::string& text)
{
    try {
        parse(text);
    } catch (const vxf::InputError& e) {
        return e.what();
    }
    return "(no error)";
}

/// kScene with one replacement applied.
std::string edited(const std::string& from, const std::string& to)
{
    std::string text = kScene;
    const auto at = text.find(from);
    REQUIRE(at != std::string::npos);
    return text.replace(at, from.size(), to);
}

} // namespace

TEST_CASE("a scene file resolves materials, lights, camera and settings", "[pipeline][scene]")
{
    const vxf::Scene scene = parse(kScene);
    REQUIRE(scene.objects.size() == 3);
    const auto& grape = scene.objects[0];
    CHECK(grape.mesh == "/scenes/meshes/grape.obj"); // relative to the scene file
    // albedo + mean free path: sigma_t = 1/mfp = 2, sigma_s = albedo sigma_t, sigma_a = the rest.
    REQUIRE(grape.material);
    CHECK(grape.material->sigmaS.x() == Approx(1.6));
    CHECK(grape.material->sigmaA.x() == Approx(0.4));
    CHECK(grape.material->sigmaS.z() == 0.0);
    CHECK(grape.material->sigmaA.z() == Approx(2.0));
    CHECK(grape.material->albedo().y() == Approx(0.5));
    CHECK(grape.material->scatters());
    // scale 2, rotate 90 degrees about z, translate (1,0,0): (1,0,0) -> (1,2,0).
    const openvdb::Vec3d moved = grape.objectToWorld.transform(openvdb::Vec3d(1, 0, 0));
    CHECK(moved.x() == Approx(1.0));
    CHECK(moved.y() == Approx(2.0));
    CHECK(moved.z() == Approx(0.0).margin(1e-12));

    CHECK(scene.objects[1].role == vxf::SceneObject::Role::Occluder);
    CHECK(scene.objects[1].mesh == "builtin:box");
    CHECK_FALSE(scene.objects[1].material);
    CHECK(scene.objects[2].mesh == "/abs/wax.ply");
    CHECK(scene.objects[2].material->sigmaS == openvdb::Vec3d(2.0));
    CHECK(scene.objects[2].material->gridsFile == "/scenes/coeffs.vdb");
    CHECK(scene.objects[2].material->sigmaSGrid == "sigma_s");

    REQUIRE(scene.lights.size() == 6);
    CHECK(scene.lights[0].power() == openvdb::Vec3d(4, 2, 1));
    CHECK(scene.lights[0].falloff == vxf::Light::Falloff::InverseSquare);
    CHECK(scene.lights[1].type == vxf::Light::Type::Spot);
    CHECK(scene.lights[1].direction == openvdb::Vec3d(0, 0, -1)); // normalized
    CHECK(scene.lights[1].falloff == vxf::Light::Falloff::Linear);
    CHECK(scene.lights[2].direction.length() == Approx(1.0));
    CHECK(scene.lights[3].width == 1.0);
    CHECK(scene.lights[3].height == 0.5);
    CHECK(scene.lights[3].samples == 9);
    CHECK(scene.lights[4].file == "/scenes/fire.vdb");
    CHECK(scene.lights[5].color == openvdb::Vec3d(0.1));

    CHECK(scene.camera.fovDegrees == 30.0);
    CHECK(scene.settings.voxelSize == 0.01);
    CHECK(scene.settings.band == 4.0);
    CHECK(scene.settings.passes == 8);
    CHECK(scene.settings.scatterBand == 0.2);
    CHECK(scene.settings.cutoff == 0.01);
    CHECK(vxf::scatterOptionsFrom(scene.settings).pass.cutoff == 0.01);
    CHECK(scene.settings.gather);
    CHECK(scene.settings.background == openvdb::Vec3d(0.1, 0.2, 0.3));
    CHECK(scene.settings.outputs == std::vector<std::string>{"image", "direct"});
}

TEST_CASE("bad scenes are refused with the field at fault", "[pipeline][scene]")
{
    CHECK(errorOf("{\n  \"objects\": [\n    {\"mesh\": \"a.obj\",}\n  ]\n}") ==
        std::string(
            "/scenes/test.json:3:22: invalid JSON: syntax error while parsing object key - unexpected '}'; expected string literal"));
    // A number beyond a double is an error at the number, not nlohmann's out_of_range (found by fuzzing).
    CHECK(errorOf("{\n  \"objects\": [1e999]\n}") == std::string("/scenes/test.json:2:15: invalid JSON: number overflow parsing '1e999'"));
    CHECK_THAT(errorOf(edited(R"("intensity": 4)", R"("intensity": -4)")), Catch::StartsWith("/scenes/test.json: /lights/0/intensity: "));
    CHECK_THAT(errorOf(edited(R"("cone_angle": 40, )", "")), Catch::Contains("/lights/1"));
    CHECK_THAT(errorOf(edited(R"("fov": 30)", R"("fov": 30, "zoom": 2)")), Catch::Contains("/camera"));
    CHECK_THAT(errorOf(edited(R"("cutoff": 0.01)", R"("cutoff": 0)")), Catch::StartsWith("/scenes/test.json: /scatter/cutoff: "));
    CHECK_THAT(errorOf(edited(R"("cutoff": 0.01)", R"("cutoff": 0.9)")), Catch::StartsWith("/scenes/test.json: /scatter/cutoff: "));
    CHECK_THAT(
        errorOf(edited(R"("mean_free_path": 0.5)", R"("mean_free_path": 0.5, "sigma_a": 1)")), Catch::Contains("/objects/0/material"));
    CHECK_THAT(errorOf(edited(R"("voxel_size": 0.01)", R"("voxel_size": 0.01, "dim": 64)")), Catch::Contains("/voxelize"));
    CHECK_THAT(errorOf(edited(R"("type": "directional")", R"("type": "laser")")), Catch::Contains("/lights/2"));
    CHECK_THAT(errorOf(edited(R"("outputs": ["image", "direct"])", R"("outputs": ["picture"])")), Catch::Contains("/outputs/0"));
    CHECK(errorOf(edited(R"("direction": [1, 1, 0])", R"("direction": [0, 0, 0])")) ==
        "/scenes/test.json: /lights/2/direction: a direction must be a non-zero vector");
    CHECK(errorOf(edited(R"("look_at": [0, 0, 1])", R"("look_at": [0, -5, 1])")) ==
        "/scenes/test.json: /camera/look_at: must differ from /camera/position");
    CHECK(errorOf(edited(R"("look_at": [0, 0, 1], "fov": 30)", R"("look_at": [0, 0, 1], "up": [0, 3, 0], "fov": 30)")) ==
        "/scenes/test.json: /camera/up: must not point along the view direction");
    CHECK(errorOf(edited(R"({"mesh": "builtin:box", "role": "occluder"})", R"({"mesh": "builtin:box"})")) ==
        "/scenes/test.json: /objects/1: a medium object needs a material (or set \"role\": \"occluder\")");
    CHECK(errorOf(edited(R"({"mesh": "builtin:box", "role": "occluder"})", R"({"mesh": "builtin:flame", "role": "emitter"})")) ==
        "/scenes/test.json: /objects/1/surface/emission: an emitter needs a non-zero emission");
    CHECK(errorOf(edited(R"({"mesh": "builtin:box", "role": "occluder"})",
              R"({"mesh": "builtin:box", "material": {"albedo": 0.5, "mean_free_path": 1}, "surface": {"emission": 2}})")) ==
        "/scenes/test.json: /objects/1/surface/emission: only an occluder or an emitter emits (a medium's glow is a volume light)");
    CHECK(errorOf(edited(R"("cone_softness": 5)", R"("cone_softness": 25)")) ==
        "/scenes/test.json: /lights/1/cone_softness: the soft edge (25 degrees) must fit inside half the cone (20 degrees)");
    // A light beyond what float grids carry once multiplied by 1/r² and σs (it scattered to all
    // zeros before), and one just inside.
    CHECK(errorOf(edited(R"("color": [1, 0.5, 0.25], "intensity": 4)", R"("color": [1, 0.5, 0.25], "intensity": 1e37)")) ==
        "/scenes/test.json: /lights/0/intensity: intensity × colour is 1e+37, beyond the 1e+20 vxf carries (its grids hold 32-bit "
        "floats, up to 3.4e38, and the stages multiply a light by distances and densities); scale the scene's units instead");
    CHECK(errorOf(edited(R"("color": [1, 0.5, 0.25], "intensity": 4)", R"("color": [1, 0.5, 0.25], "intensity": 1e20)")) == "(no error)");
    // Volume objects (a .vdb's density grid): media only, without a surface; a mesh or a volume, not both.
    CHECK(errorOf(edited(R"({"mesh": "builtin:box", "role": "occluder"})", R"({"volume": "smoke.vdb", "role": "occluder"})")) ==
        "/scenes/test.json: /objects/1/role: a volume object is a medium (its grid is the medium's density); an opaque object needs a "
        "mesh");
    CHECK(errorOf(edited(R"({"mesh": "builtin:box", "role": "occluder"})",
              R"({"volume": "smoke.vdb", "material": {"albedo": 0.5, "mean_free_path": 1}, "surface": {"diffuse": 0.5}})")) ==
        "/scenes/test.json: /objects/1/surface: a volume object has no surface to shade (its look is the volume term)");
    CHECK(errorOf(edited(
              R"({"mesh": "builtin:box", "role": "occluder"})", R"({"mesh": "builtin:box", "role": "occluder", "grid": "density"})")) ==
        "/scenes/test.json: /objects/1/grid: names the grid of a volume object; this object has a mesh");
    CHECK_THAT(errorOf(edited(R"({"mesh": "builtin:box", "role": "occluder"})",
                   R"({"mesh": "builtin:box", "volume": "smoke.vdb", "role": "occluder"})")),
        Catch::StartsWith("/scenes/test.json: /objects/1"));
    CHECK_THAT(errorOf(edited(R"({"mesh": "builtin:box", "role": "occluder"})", R"({"role": "occluder"})")),
        Catch::StartsWith("/scenes/test.json: /objects/1"));
    // The phase: |g| ≤ 0.95, one g for every medium of the scene.
    CHECK_THAT(errorOf(edited(R"("mean_free_path": 0.5})", R"("mean_free_path": 0.5, "phase": {"g": 0.99}})")),
        Catch::StartsWith("/scenes/test.json: /objects/0/material/phase/g: "));
    CHECK(errorOf(edited(R"("mean_free_path": 0.5})", R"("mean_free_path": 0.5, "phase": {"g": 0.6}})")) ==
        "/scenes/test.json: /objects/2/material/phase/g: 0 differs from medium 'grape''s 0.6: every medium of a scene has the same phase");
    CHECK_THROWS_WITH(vxf::loadScene("/nonexistent/scene.json"), "/nonexistent/scene.json: no such file");
}

TEST_CASE("a material's phase: Henyey-Greenstein g, and single scattering marched to the lights unless the scene says",
    "[pipeline][scene][phase]")
{
    const std::string anisotropic = edited(R"("mean_free_path": 0.5})", R"("mean_free_path": 0.5, "phase": {"g": -0.3}})");
    std::string both = anisotropic;
    const std::string wax = R"("sigma_s": 2,)";
    both.replace(both.find(wax), wax.size(), R"("sigma_s": 2, "phase": {"g": -0.3},)");
    const vxf::Scene scene = parse(both);
    CHECK(scene.objects[0].material->phaseG == -0.3);
    CHECK(scene.objects[2].material->phaseG == -0.3);
    CHECK(scene.settings.directFromLights); // the phase shows in single scattering marched to the lights
    CHECK_FALSE(parse(kScene).settings.directFromLights); // isotropic: the direct grid, as before
    std::string asked = both;
    const std::string render = R"("mode": "gather",)";
    asked.replace(asked.find(render), render.size(), R"("mode": "gather", "direct": "grid",)");
    CHECK_FALSE(parse(asked).settings.directFromLights);
}

TEST_CASE("a volume object names a .vdb and its density grid, resolved against the scene", "[pipeline][scene][volume]")
{
    const vxf::Scene scene = vxf::parseScene(R"({
      "objects": [{"name": "smoke", "volume": "sim/smoke.vdb", "material": {"albedo": 0.9, "mean_free_path": 0.1}},
                  {"name": "ground", "mesh": "builtin:box", "role": "occluder"}],
      "lights": [], "camera": {"position": [0, -5, 0], "look_at": [0, 0, 0]}})",
        "/scenes/cloud.json");
    REQUIRE(scene.objects.size() == 2);
    CHECK(scene.objects[0].isVolume());
    CHECK(scene.objects[0].volume == "/scenes/sim/smoke.vdb");
    CHECK(scene.objects[0].grid == "density");
    CHECK(scene.objects[0].mesh.empty());
    CHECK_FALSE(scene.objects[1].isVolume());
    const vxf::Scene flame = vxf::parseScene(R"({
      "objects": [{"volume": "fire.vdb", "grid": "soot", "material": {"sigma_a": 1, "sigma_s": 1}}],
      "lights": [], "camera": {"position": [0, -5, 0], "look_at": [0, 0, 0]}})",
        "/scenes/fire.json");
    CHECK(flame.objects[0].grid == "soot");
}

TEST_CASE("every example scene is valid", "[pipeline][scene][examples]")
{
    int count = 0;
    for (const auto& entry : std::filesystem::directory_iterator(vxf::test::source("examples"))) {
        if (entry.path().extension() != ".json") continue;
        INFO(entry.path().string());
        CHECK_NOTHROW(vxf::loadScene(entry.path().string()));
        ++count;
    }
    CHECK(count >= 1);
}

TEST_CASE("the embedded scene schema is the committed one", "[pipeline][scene][schema]")
{
    CHECK(vxf::sceneSchemaText() == vxf::test::slurp(vxf::test::source("schemas/scene.schema.json")));
}

TEST_CASE("a volume object's emission is a volume light on its file that moves with it, a mesh has none", "[scene][emission]")
{
    const vxf::Scene scene = parse(R"({
      "objects": [{"name": "fire", "volume": "sim/fire.vdb", "transform": {"translate": [1, 2, 3]},
                   "emission": {"grid": "flame", "intensity": 4, "color": [1, 0.5, 0.2]},
                   "material": {"albedo": 0.9, "mean_free_path": 0.1}}],
      "lights": [{"type": "directional", "direction": [0, 0, -1]}],
      "camera": {"position": [0, -5, 1], "look_at": [0, 0, 1]}
    })");
    REQUIRE(scene.lights.size() == 2);
    CHECK(scene.lights[0].type == vxf::Light::Type::Directional); // the file's lights keep their indices
    const vxf::Light& e = scene.lights[1];
    CHECK(e.type == vxf::Light::Type::Volume);
    CHECK(e.name == "fire.emission");
    CHECK(e.file == "/scenes/sim/fire.vdb");
    CHECK(e.grid == "flame");
    CHECK(e.power() == openvdb::Vec3d(4.0, 2.0, 0.8));
    CHECK(e.gridToWorld == scene.objects[0].objectToWorld);
    CHECK(e.gridToWorld.getTranslation() == openvdb::Vec3d(1, 2, 3));

    CHECK(errorOf(edited(R"("mesh": "meshes/grape.obj", )", R"("mesh": "meshes/grape.obj", "emission": {"grid": "flame"}, )")) ==
        "/scenes/test.json: /objects/0/emission: names a grid of a volume object's file; a mesh medium's glow is a volume light");
}
