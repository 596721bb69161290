// `quality`: an error asked for reads the scene with the accuracy bench's fastest setting for it.
#include <vxf/core/Quality.h>

#include <vxf/core/Error.h>
#include <vxf/pipeline/SceneFile.h>

#include "TestSupport.h"
#include "pipeline/QualityPreset.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <openvdb/io/File.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/LevelSetUtil.h>

#include <algorithm>
#include <optional>
#include <string>

namespace {

using nlohmann::json;

/// A builtin sphere (radius 1: 2 units across) of @a albedo and @a opticalSize mean free paths
/// across, with @a extra members (quality, blocks) merged in.
json sphereScene(double albedo, double opticalSize, const json& extra = json::object())
{
    json scene = {{"objects", {{{"mesh", "builtin:sphere"}, {"material", {{"albedo", albedo}, {"mean_free_path", 2.0 / opticalSize}}}}}},
        {"lights", {{{"type", "point"}, {"position", {0, 0, 3}}}, {{"type", "environment"}, {"intensity", 0.1}}}},
        {"camera", {{"position", {0, -5, 0}}, {"look_at", {0, 0, 0}}}}};
    scene.update(extra);
    return scene;
}

vxf::Scene parse(const json& scene, std::optional<vxf::QualityRequest> quality = std::nullopt)
{
    return vxf::parseScene(scene.dump(), "/scenes/q.json", std::nullopt, quality);
}

/// The bench's frontier of @a name: the fastest row within @a error (the last if none).
const json& expectedRow(const std::string& name, double error)
{
    const json& rows = vxf::detail::qualityTable().at("scenes").at(name).at("settings");
    for (const json& row : rows) {
        if (row.at("error").get<double>() <= error) return row;
    }
    return rows.back();
}

} // namespace

TEST_CASE("quality: the levels name errors, other names are refused", "[quality]")
{
    CHECK(vxf::qualityLevelError("draft") == 0.10);
    CHECK(vxf::qualityLevelError("final") == 0.05);
    CHECK(vxf::qualityLevelError("reference") == 0.02);
    CHECK_THROWS_WITH(vxf::qualityLevelError("best"), Catch::Contains("draft") && Catch::Contains("reference"));
    CHECK_THROWS_WITH(parse(sphereScene(0.99, 50, {{"quality", "best"}})), Catch::Contains("/quality"));
    CHECK_THROWS_WITH(parse(sphereScene(0.99, 50, {{"quality", {{"error", 0}}}})), Catch::Contains("/quality"));
}

TEST_CASE("quality: the bench's table is whole (every scene a frontier of time against error)", "[quality]")
{
    const json& scenes = vxf::detail::qualityTable().at("scenes");
    for (const char* name : {"thick", "translucent", "smoke", "smoke_isotropic", "fog"}) {
        INFO(name);
        const json& rows = scenes.at(name).at("settings");
        REQUIRE(!rows.empty());
        for (std::size_t i = 1; i < rows.size(); ++i) {
            CHECK(rows[i].at("seconds").get<double>() >= rows[i - 1].at("seconds").get<double>());
            CHECK(rows[i].at("error").get<double>() < rows[i - 1].at("error").get<double>());
        }
    }
}

TEST_CASE("quality: a scene like the bench's thick bunny gets the fastest setting that reached the error", "[quality]")
{
    const vxf::Scene scene = parse(sphereScene(0.99, 50, {{"quality", {{"error", 0.05}}}}));
    REQUIRE(scene.settings.quality);
    const vxf::QualityChoice& choice = *scene.settings.quality;
    CHECK(choice.benchScene == "thick");
    CHECK(choice.reached);
    const json& row = expectedRow("thick", 0.05);
    CHECK(choice.error == row.at("error").get<double>());
    CHECK(choice.error <= 0.05);
    const json& knobs = row.at("knobs");
    const vxf::SceneSettings& s = scene.settings;
    CHECK(s.dim == knobs.at("dim").get<int>()); // the bench's optical size: its dim as it is
    CHECK(s.directions == knobs.at("directions").get<int>());
    CHECK(s.kernel == knobs.at("kernel").get<std::string>());
    CHECK(s.finePasses == knobs.at("fine_passes").get<int>());
    CHECK(s.cutoff == knobs.at("cutoff").get<double>());
    CHECK(s.samples == knobs.at("samples").get<int>());
    CHECK(s.directFromLights == (knobs.at("direct").get<std::string>() == "lights"));
    // The environment light takes the setting's samples; the summary says what and why.
    CHECK(scene.lights[1].samples == knobs.at("env_samples").get<int>());
    CHECK_THAT(choice.summary(), Catch::Contains("'thick'") && Catch::Contains(choice.setting));
}

TEST_CASE("quality: the scene's own knobs win, and are named", "[quality]")
{
    const json blocks = {
        {"quality", "draft"}, {"scatter", {{"directions", 24}}}, {"render", {{"samples", 2}}}, {"voxelize", {{"voxel_size", 0.05}}}};
    json scene = sphereScene(0.99, 50, blocks);
    scene["lights"][1]["samples"] = 7;
    const vxf::Scene read = parse(scene);
    REQUIRE(read.settings.quality);
    CHECK(read.settings.directions == 24);
    CHECK(read.settings.samples == 2);
    CHECK(read.settings.voxelSize == 0.05);
    CHECK(read.lights[1].samples == 7);
    const auto& kept = read.settings.quality->kept;
    for (const char* knob : {"/scatter/directions", "/render/samples", "/voxelize/voxel_size"}) {
        CHECK(std::find(kept.begin(), kept.end(), knob) != kept.end());
    }
    CHECK(read.settings.finePasses == expectedRow("thick", 0.10).at("knobs").at("fine_passes").get<int>());
}

TEST_CASE("quality: the closest bench scene by medium, and the voxels per mean free path kept", "[quality]")
{
    CHECK(parse(sphereScene(0.8, 20, {{"quality", "final"}})).settings.quality->benchScene == "translucent");
    CHECK(parse(sphereScene(0.99, 50, {{"quality", "final"}})).settings.quality->benchScene == "thick");
    // Ten times the bench's optical size: ten times its dim, so each voxel is as many mean free paths.
    const vxf::Scene thick = parse(sphereScene(0.99, 500, {{"quality", "final"}}));
    CHECK(thick.settings.dim == 10 * expectedRow("thick", 0.05).at("knobs").at("dim").get<int>());
    CHECK_THAT(thick.settings.quality->setting, Catch::Contains("voxels per mean free path"));
    // Optically smaller: never fewer voxels than the bench's.
    CHECK(parse(sphereScene(0.99, 5, {{"quality", "final"}})).settings.dim == expectedRow("thick", 0.05).at("knobs").at("dim").get<int>());
    // A volume object scattering forward: the smoke's table, and its phase's kernel kept.
    const json smoke = {
        {"objects", {{{"volume", "smoke.vdb"}, {"material", {{"albedo", 0.9}, {"mean_free_path", 0.1}, {"phase", {{"g", 0.5}}}}}}}},
        {"lights", {{{"type", "directional"}, {"direction", {0, 0, -1}}}}}, {"camera", {{"position", {0, -5, 0}}, {"look_at", {0, 0, 0}}}},
        {"quality", {{"error", 0.1}}}};
    const vxf::Scene volume = parse(smoke);
    CHECK(volume.settings.quality->benchScene == "smoke");
    CHECK(volume.settings.kernel == "sweep");
}

TEST_CASE("quality: an error no setting reached takes the most accurate and says so, and a request overrides the scene's", "[quality]")
{
    const vxf::Scene scene = parse(sphereScene(0.99, 50, {{"quality", {{"error", 0.001}}}}));
    REQUIRE(scene.settings.quality);
    CHECK(!scene.settings.quality->reached);
    CHECK(scene.settings.quality->error == expectedRow("thick", 0.0).at("error").get<double>());
    CHECK_THAT(scene.settings.quality->summary(), Catch::Contains("No setting the bench measured reaches it"));

    const vxf::Scene overridden = parse(sphereScene(0.99, 50, {{"quality", "reference"}}), vxf::QualityRequest{0.10, ""});
    CHECK(overridden.settings.quality->asked.error == 0.10);
    CHECK(overridden.settings.quality->error == expectedRow("thick", 0.10).at("error").get<double>());
    // No quality asked: the defaults, nothing chosen.
    CHECK(!parse(sphereScene(0.99, 50)).settings.quality);
}

TEST_CASE("quality: a volume object takes the bench volume's coarsening, scaled by its optical size", "[quality][volume]")
{
    // A fog sphere 2 across on voxels of 0.02 (100 across), albedo 0.9, isotropic: the fog's table.
    vxf::test::TempDir dir;
    auto fog = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(1.0f, openvdb::Vec3f(0.0f), 0.02f);
    openvdb::tools::sdfToFogVolume(*fog);
    fog->setName("density");
    openvdb::io::File(dir.path("fog.vdb")).write({fog});
    const auto volumeScene = [&](double opticalSize, double error) {
        const json scene = {{"objects", {{{"volume", "fog.vdb"}, {"material", {{"albedo", 0.9}, {"mean_free_path", 2.0 / opticalSize}}}}}},
            {"lights", {{{"type", "directional"}, {"direction", {0, 0, -1}}}}},
            {"camera", {{"position", {0, -5, 0}}, {"look_at", {0, 0, 0}}}}, {"quality", {{"error", error}}}};
        return vxf::parseScene(scene.dump(), dir.path("fog.json"));
    };
    for (const double error : {0.10, 0.05, 0.02}) {
        INFO("error " << error);
        const int asked = expectedRow("fog", error).at("knobs").value("volume_dim", 0);
        // Optically smaller than the bench's fog (40 mean free paths against 50): its volume_dim as
        // it is (0: its own voxels).
        const vxf::Scene scene = volumeScene(40.0, error);
        CHECK(scene.settings.quality->benchScene == "fog");
        CHECK(scene.settings.dim == asked);
        // Ten times the bench's optical size: ten times the voxels, so each is as many mean free paths.
        if (asked > 0) CHECK(volumeScene(500.0, error).settings.dim == Approx(std::min(10 * asked, 1024)).epsilon(0.03));
    }
}
