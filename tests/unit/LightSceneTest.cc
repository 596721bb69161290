// Lighting a voxel set by a scene (vxf/pipeline/LightScene.h): the scene's occluders shadow the
// medium, its material is recorded, and media the set cannot tell apart are refused.
#include <vxf/pipeline/LightScene.h>

#include <vxf/core/Error.h>
#include <vxf/pipeline/SceneFile.h>
#include <vxf/pipeline/SceneMedium.h>
#include <vxf/transport/Medium.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

namespace {
std::string sceneText(bool occluder, bool secondMedium = false)
{
    std::string objects = R"({"name": "ball", "mesh": "builtin:sphere", "material": {"sigma_a": 0.5, "sigma_s": 2.0}})";
    if (occluder) {
        objects += R"(, {"name": "roof", "mesh": "builtin:box", "role": "occluder",
            "transform": {"scale": [4, 4, 0.1], "translate": [0, 0, 3]}})";
    }
    if (secondMedium) {
        objects += R"(, {"name": "other", "mesh": "builtin:box", "material": {"sigma_a": 1.0, "sigma_s": 1.0},
            "transform": {"translate": [3, 0, 0]}})";
    }
    return R"({"objects": [)" + objects + R"(],
        "lights": [{"name": "sun", "type": "directional", "direction": [0, 0, -1], "intensity": 1.0}],
        "camera": {"position": [0, -5, 0], "look_at": [0, 0, 0]}, "voxelize": {"dim": 24}})";
}

/// The `direct` fluence at the top of the ball.
double topFluence(const vxf::Scene& scene)
{
    vxf::VoxelSet set = vxf::voxelizeMedia(scene, vxf::VoxelizeOptions{0.0, 24, 3.0f, nullptr});
    vxf::lightScene(set, scene);
    CHECK(set.metadata().getMetadata<openvdb::StringMetadata>(vxf::kMaterialMetaKey));
    const auto direct = set.get<openvdb::Vec3SGrid>("direct");
    const openvdb::Coord top = direct->transform().worldToIndexCellCentered(openvdb::Vec3d(0.0, 0.0, 0.85));
    return direct->tree().getValue(top)[0];
}
} // namespace

TEST_CASE("a scene's occluder shadows its medium, several media need their own coefficient grids", "[pipeline][light]")
{
    vxf::test::TempDir dir;
    vxf::test::spit(dir.path("open.json"), sceneText(false));
    vxf::test::spit(dir.path("roofed.json"), sceneText(true));
    const double open = topFluence(vxf::loadScene(dir.path("open.json")));
    const double roofed = topFluence(vxf::loadScene(dir.path("roofed.json")));
    CHECK(open > 0.3); // a little under the surface: e^{-2.5 x}
    CHECK(roofed < 1e-6 * open);

    vxf::test::spit(dir.path("two.json"), sceneText(false, true));
    const vxf::Scene two = vxf::loadScene(dir.path("two.json"));
    vxf::VoxelSet justOne = vxf::voxelizeMedia(vxf::loadScene(dir.path("open.json")), vxf::VoxelizeOptions{0.0, 24, 3.0f, nullptr});
    CHECK_THROWS_WITH(vxf::lightScene(justOne, two), Catch::Contains("two.json") && Catch::Contains("2 media"));
}

TEST_CASE("a medium whose mean free path is under half a voxel is said to be unresolved", "[pipeline][light]")
{
    // The ball at dim 24: a voxel 2/24. sigma_t 2.5 (a mean free path of 5 voxels) is resolved;
    // sigma_t 50 (0.24 of a voxel) is not, and the warning names both sizes and the cure.
    const auto warnings = [](const char* material) {
        const std::string text = R"({"objects": [{"name": "ball", "mesh": "builtin:sphere", "material": )" + std::string(material) +
            R"(}], "lights": [{"type": "directional", "direction": [0, 0, -1]}], "camera": {"position": [0, -5, 0], "look_at": [0, 0, 0]}})";
        const vxf::Scene scene = vxf::parseScene(text, "/scenes/ball.json");
        vxf::VoxelSet set = vxf::voxelizeMedia(scene, vxf::VoxelizeOptions{0.0, 24, 3.0f, nullptr});
        return vxf::lightScene(set, scene).warnings;
    };
    CHECK(warnings(R"({"sigma_a": 0.5, "sigma_s": 2.0})").empty());
    const auto dense = warnings(R"({"sigma_a": 10.0, "sigma_s": 40.0})");
    REQUIRE(dense.size() == 1);
    CHECK_THAT(dense[0],
        Catch::Contains("mean free path (0.02 at density 1) is 0.24 of a voxel (0.0833)") && Catch::Contains("voxelize.voxel_size 0.04"));
}
