// Animated scenes: keyframes interpolated, frame tokens expanded, the frame's scene checked
// (pipeline/SceneAnimation.h through vxf/pipeline/SceneFile.h).
#include "pipeline/SceneAnimation.h"

#include <vxf/core/Error.h>
#include <vxf/pipeline/SceneFile.h>

#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

using nlohmann::json;
using vxf::detail::evaluateKeyframes;

namespace {

double at(const json& curve, double frame) { return evaluateKeyframes(curve, frame, "s.json: /x").get<double>(); }

json curve(const std::string& interpolation)
{
    return json{{"keyframes",
                    {{{"frame", 1}, {"value", 0.0}}, {{"frame", 11}, {"value", 10.0}}, {{"frame", 21}, {"value", 10.0}},
                        {{"frame", 31}, {"value", 0.0}}}},
        {"interpolation", interpolation}};
}

std::string scene(const std::string& camera, const std::string& extra = "")
{
    return R"({"objects": [{"mesh": "smoke.$F4.obj", "material": {"albedo": 0.9, "mean_free_path": 0.5}}],
  "lights": [{"type": "point", "position": [0, 0, 3], "intensity": {"keyframes": [{"frame": 1, "value": 1}, {"frame": 5, "value": 5}]}}],
  "camera": )" +
        camera + extra + "}";
}

std::string errorOf(const std::string& text, std::optional<int> frame)
{
    try {
        vxf::parseScene(text, "s.json", frame);
    } catch (const vxf::Error& e) {
        return e.what();
    }
    return "";
}

} // namespace

TEST_CASE("keyframes interpolate as Blender's and Houdini's curves do", "[animation]")
{
    const json linear = curve("linear");
    CHECK(at(linear, -5) == 0.0); // held before the first key
    CHECK(at(linear, 6) == Approx(5.0));
    CHECK(at(linear, 16) == Approx(10.0));
    CHECK(at(linear, 26) == Approx(5.0));
    CHECK(at(linear, 100) == 0.0); // and after the last

    CHECK(at(curve("constant"), 10.99) == 0.0);
    CHECK(at(curve("constant"), 11) == 10.0);
    CHECK(at(curve("ease"), 6) == Approx(5.0)); // symmetric about the middle
    CHECK(at(curve("ease"), 3.5) == Approx(10.0 * 0.25 * 0.25 * (3 - 0.5)));

    // bezier: through the keys, flat at the ends and at the plateau, never past the keys' values.
    const json bezier = curve("bezier");
    CHECK(at(bezier, 11) == Approx(10.0));
    CHECK(at(bezier, 6) == Approx(5.0));
    CHECK(at(bezier, 1.01) < 0.01); // flat at the first key: slope ~0
    for (double f = 1; f <= 31; f += 0.25) {
        CHECK(at(bezier, f) >= -1e-12);
        CHECK(at(bezier, f) <= 10.0 + 1e-12);
    }
    CHECK(at(bezier, 16) == Approx(10.0)); // the plateau stays flat

    // A rising run stays smooth through a key: the slope at the middle key is the neighbours'.
    const json ramp = {{"keyframes", {{{"frame", 0}, {"value", 0.0}}, {{"frame", 10}, {"value", 10.0}}, {{"frame", 20}, {"value", 20.0}}}},
        {"interpolation", "bezier"}};
    CHECK((at(ramp, 10.01) - at(ramp, 9.99)) / 0.02 == Approx(1.0).epsilon(1e-3));

    // Triples component by component; a key's own interpolation wins over the curve's.
    const json triple = {
        {"keyframes", {{{"frame", 0}, {"value", {0, 10, 20}}, {"interpolation", "constant"}}, {{"frame", 10}, {"value", {10, 0, 20}}}}},
        {"interpolation", "linear"}};
    CHECK(evaluateKeyframes(triple, 5, "") == json::array({0.0, 10.0, 20.0}));
    json linearTriple = triple;
    linearTriple["keyframes"][0].erase("interpolation");
    CHECK(evaluateKeyframes(linearTriple, 5, "") == json::array({5.0, 5.0, 20.0}));
}

TEST_CASE("a curve's keys must run forward and be of one kind", "[animation]")
{
    const json backwards = {{"keyframes", {{{"frame", 5}, {"value", 1}}, {{"frame", 2}, {"value", 2}}}}};
    CHECK_THROWS_WITH(evaluateKeyframes(backwards, 3, "s.json: /lights/0/intensity"),
        Catch::Contains("s.json: /lights/0/intensity: the keys must run forward in frames (frame 2 follows frame 5)"));
    const json mixed = {{"keyframes", {{{"frame", 1}, {"value", 1}}, {{"frame", 2}, {"value", {1, 2, 3}}}}}};
    CHECK_THROWS_WITH(evaluateKeyframes(mixed, 1, "s.json: /camera/fov"), Catch::Contains("all numbers or all triples"));
}

TEST_CASE("an animated scene is read at a frame: values interpolated, paths expanded", "[animation][scene]")
{
    const std::string text = scene(
        R"({"position": {"keyframes": [{"frame": 1, "value": [0, -4, 0]}, {"frame": 3, "value": [2, -4, 0]}]}, "look_at": [0, 0, 0]})");
    const vxf::Scene s2 = vxf::parseScene(text, "dir/s.json", 2);
    CHECK(s2.frame == 2);
    CHECK(s2.camera.position == openvdb::Vec3d(1, -4, 0));
    CHECK(s2.lights[0].intensity == Approx(2.0));
    CHECK(s2.objects[0].mesh == "dir/smoke.0002.obj");
    CHECK(vxf::parseScene(text, "dir/s.json", 9).camera.position == openvdb::Vec3d(2, -4, 0));

    // Without a frame, an animated scene is refused naming what is animated.
    CHECK_THAT(errorOf(text, std::nullopt), Catch::Contains("s.json: the scene is animated (/camera/position and 2 more)"));
    CHECK_THAT(errorOf(text, std::nullopt), Catch::Contains("--frames"));

    // A still scene reads the same with or without a frame.
    const std::string still =
        R"({"objects": [{"mesh": "builtin:sphere", "material": {"albedo": 0.9, "mean_free_path": 0.5}}], "lights": [],
            "camera": {"position": [0, -4, 0], "look_at": [0, 0, 0]}})";
    CHECK(vxf::parseScene(still, "s.json", 7).camera.position == vxf::parseScene(still, "s.json").camera.position);
}

TEST_CASE("an animated value must be valid at every frame, and only values animate", "[animation][scene]")
{
    // fov runs out of (0, 180) past frame 2: the frame is named.
    const std::string wide = scene(R"({"position": [0, -4, 0], "look_at": [0, 0, 0],
        "fov": {"keyframes": [{"frame": 1, "value": 90}, {"frame": 3, "value": 270}]}})");
    CHECK(errorOf(wide, 1).empty());
    CHECK_THAT(errorOf(wide, 3), Catch::Contains("s.json: at frame 3: /camera/fov"));
    // Keyframes where a setting stands (voxelize dim) are a schema error, as any wrong type.
    const std::string dim =
        scene(R"({"position": [0, -4, 0], "look_at": [0, 0, 0]})", R"(, "voxelize": {"dim": {"keyframes": [{"frame": 1, "value": 32}]}})");
    CHECK_THAT(errorOf(dim, 1), Catch::Contains("/voxelize/dim"));
    // A key without a value, an unknown interpolation.
    const std::string noValue = scene(R"({"position": {"keyframes": [{"frame": 1}]}, "look_at": [0, 0, 0]})");
    CHECK_THAT(errorOf(noValue, 1), Catch::Contains("/camera/position"));
    const std::string cubic =
        scene(R"({"position": {"keyframes": [{"frame": 1, "value": [0, -4, 0]}], "interpolation": "cubic"}, "look_at": [0, 0, 0]})");
    CHECK_THAT(errorOf(cubic, 1), Catch::Contains("/camera/position"));
}
