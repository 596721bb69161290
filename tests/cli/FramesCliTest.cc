// `vxf run --frames`: a shot frame by frame, as a user runs it on an animated scene.
#include "TestSupport.h"

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <filesystem>
#include <regex>

using vxf::test::binary;
using vxf::test::run;
using vxf::test::slurp;
using vxf::test::spit;
using vxf::test::TempDir;

namespace fs = std::filesystem;

namespace {

/// A sphere medium lit by a point light; @a light, @a camera and @a transform are JSON values
/// (keyframes or not), @a mesh the mesh path.
std::string sphereScene(const std::string& light, const std::string& camera, const std::string& transform = R"({"scale": 1})",
    const std::string& mesh = "builtin:sphere")
{
    return fmt::format(R"({{
  "objects": [{{"mesh": "{}", "transform": {}, "material": {{"albedo": 0.9, "mean_free_path": 0.2}}}}],
  "lights": [{{"type": "point", "position": {}, "intensity": 3}}],
  "camera": {{"position": {}, "look_at": [0, 0, 0], "fov": 40}},
  "voxelize": {{"dim": 16}},
  "scatter": {{"directions": 8, "kernel": "sweep"}},
  "render": {{"width": 32, "height": 24, "samples": 1}},
  "outputs": ["image"]
}})",
        mesh, transform, light, camera);
}

const char* kMoving = R"({"keyframes": [{"frame": 1, "value": [0, -4, 0]}, {"frame": 3, "value": [1, -4, 0.5]}]})";
const char* kStillCamera = "[0, -4, 0]";
const char* kStillLight = "[0, 0, 2]";

/// The stages' actions of each frame of a `vxf run --frames` output: "frame 2: voxelize reused, ...".
std::vector<std::string> frameActions(const std::string& out)
{
    std::vector<std::string> frames;
    const std::regex stage(R"(^  (\w+) +(ran|reused|skipped))");
    std::string line;
    std::istringstream in(out);
    while (std::getline(in, line)) {
        std::smatch m;
        if (line.rfind("frame ", 0) == 0) {
            frames.push_back(line + ":");
        } else if (std::regex_search(line, m, stage) && !frames.empty()) {
            frames.back() += " " + m[1].str() + " " + m[2].str();
        }
    }
    return frames;
}

vxf::test::RunResult runFrames(const TempDir& dir, const std::string& frames, const std::string& extra = "")
{
    return run(fmt::format("{} run {} --out {} --frames {} {}", binary("vxf"), dir.path("s.json"), dir.path("out"), frames, extra));
}

} // namespace

TEST_CASE("vxf run --frames renders NAME.0001.exr ..., a still scene's frames bit-identical", "[cli][run][frames]")
{
    TempDir dir;
    spit(dir.path("s.json"), sphereScene(kStillLight, kStillCamera));
    const auto result = runFrames(dir, "1-3:2");
    INFO(result.out << result.err);
    REQUIRE(result.status == 0);
    CHECK(fs::exists(dir.path("out/s.0001.exr")));
    CHECK(fs::exists(dir.path("out/s.0003.png")));
    CHECK_FALSE(fs::exists(dir.path("out/s.0002.exr")));
    CHECK_FALSE(fs::exists(dir.path("out/s.exr")));
    // No randomness by frame: per-voxel rotations and camera samples are seeded by position.
    CHECK(slurp(dir.path("out/s.0001.exr")) == slurp(dir.path("out/s.0003.exr")));
    const auto actions = frameActions(result.out);
    REQUIRE(actions.size() == 2);
    CHECK(actions[0] == "frame 1: voxelize ran light ran scatter ran render ran");
    CHECK(actions[1] == "frame 3: voxelize reused light reused scatter reused render ran");
}

TEST_CASE("each frame re-runs only the stages whose inputs its animation changed", "[cli][run][frames]")
{
    TempDir dir;
    SECTION("a moving camera: voxelize, light and scatter once")
    {
        spit(dir.path("s.json"), sphereScene(kStillLight, kMoving));
        const auto result = runFrames(dir, "1-3");
        INFO(result.out << result.err);
        REQUIRE(result.status == 0);
        const auto actions = frameActions(result.out);
        REQUIRE(actions.size() == 3);
        CHECK(actions[1] == "frame 2: voxelize reused light reused scatter reused render ran");
        CHECK(slurp(dir.path("out/s.0001.exr")) != slurp(dir.path("out/s.0002.exr")));
    }
    SECTION("a moving light: lit and scattered again, not voxelized")
    {
        spit(dir.path("s.json"), sphereScene(kMoving, kStillCamera));
        const auto result = runFrames(dir, "1-3");
        INFO(result.out << result.err);
        REQUIRE(result.status == 0);
        const auto actions = frameActions(result.out);
        REQUIRE(actions.size() == 3);
        CHECK(actions[1] == "frame 2: voxelize reused light ran scatter ran render ran");
        CHECK(actions[2] == "frame 3: voxelize reused light ran scatter ran render ran");
        // The stage commands read an animated scene at --frame (and refuse it without one).
        const std::string vxf = binary("vxf");
        REQUIRE(run(fmt::format("{} voxelize builtin:sphere -o {} --dim 16", vxf, dir.path("v.vdb"))).status == 0);
        const auto lit =
            run(fmt::format("{} light {} --scene {} --frame 2 -o {}", vxf, dir.path("v.vdb"), dir.path("s.json"), dir.path("l.vdb")));
        INFO(lit.err);
        CHECK(lit.status == 0);
        const auto unframed =
            run(fmt::format("{} light {} --scene {} -o {}", vxf, dir.path("v.vdb"), dir.path("s.json"), dir.path("l2.vdb")));
        CHECK(unframed.status == 1);
        CHECK_THAT(unframed.err, Catch::Contains("the scene is animated (/lights/0/position)"));
        // --prune-cache: the shot's cache keeps one frame's entries (the shared voxel set, frame 3's light and scatter).
        const auto prunedRun =
            run(fmt::format("{} run {} --out {} --frames 1-3 --prune-cache", binary("vxf"), dir.path("s.json"), dir.path("pruned")));
        INFO(prunedRun.out);
        REQUIRE(prunedRun.status == 0);
        CHECK(prunedRun.out.find("pruned 2 cache entries of the frame before") != std::string::npos);
        int entries = 0;
        for (const auto& e : fs::directory_iterator(dir.path("pruned/cache"))) entries += e.path().extension() == ".vdb" ? 1 : 0;
        CHECK(entries == 3);
        // Past the last key the light holds still: frame 4 reuses frame 3's lighting.
        const auto held = runFrames(dir, "4");
        CHECK(frameActions(held.out).at(0) == "frame 4: voxelize reused light reused scatter reused render ran");
    }
    SECTION("a moving object: voxelized again")
    {
        spit(dir.path("s.json"),
            sphereScene(kStillLight, kStillCamera,
                R"({"translate": {"keyframes": [{"frame": 1, "value": [0, 0, 0]}, {"frame": 2, "value": [0.3, 0, 0]}]}})"));
        const auto result = runFrames(dir, "1-2");
        INFO(result.out << result.err);
        REQUIRE(result.status == 0);
        CHECK(frameActions(result.out).at(1) == "frame 2: voxelize ran light ran scatter ran render ran");
    }
    SECTION("warm starts: the solve starts from the frame before, in fewer sweeps")
    {
        spit(dir.path("s.json"),
            sphereScene(R"({"keyframes": [{"frame": 1, "value": [0, 0, 2]}, {"frame": 48, "value": [2, 0, 2]}]})", kStillCamera));
        const auto cold = runFrames(dir, "2");
        const auto warm =
            run(fmt::format("{} run {} --out {} --frames 1-2 --warm-start", binary("vxf"), dir.path("s.json"), dir.path("warm")));
        INFO(cold.out << warm.out << warm.err);
        REQUIRE(warm.status == 0);
        const std::regex sweeps(R"(converged in (\d+) sweeps)");
        std::smatch c, w;
        REQUIRE(std::regex_search(cold.out, c, sweeps));
        const std::string frame2 = warm.out.substr(warm.out.find("frame 2"));
        REQUIRE(std::regex_search(frame2, w, sweeps));
        CHECK(frame2.find("from the frame before") != std::string::npos);
        CHECK(std::stoi(w[1].str()) < std::stoi(c[1].str()));
        CHECK(run(fmt::format("{} run {} --out {} --warm-start", binary("vxf"), dir.path("s.json"), dir.path("o"))).status == 2);
        CHECK(run(fmt::format("{} run {} --out {} --prune-cache", binary("vxf"), dir.path("s.json"), dir.path("o"))).status == 2);
    }
}

TEST_CASE("a sequence's missing frame is named before any frame renders", "[cli][run][frames]")
{
    TempDir dir;
    // A tetrahedron per frame, as a simulation writes them: frames 1 and 2 exist, 3 does not.
    const std::string tetra = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    spit(dir.path("ball.0001.obj"), tetra);
    spit(dir.path("ball.0002.obj"), tetra);
    spit(dir.path("s.json"), sphereScene(kStillLight, kStillCamera, R"({"scale": 1})", "ball.$F4.obj"));
    const auto bad = runFrames(dir, "1-3");
    CHECK(bad.status == 1);
    CHECK_THAT(bad.err, Catch::Contains("at frame 3: object 'object0': ") && Catch::Contains("ball.0003.obj does not exist"));
    CHECK_FALSE(fs::exists(dir.path("out/s.0001.exr"))); // nothing rendered before the check
    const auto good = runFrames(dir, "1-2");
    INFO(good.err);
    CHECK(good.status == 0);
    CHECK(fs::exists(dir.path("out/s.0002.exr")));
    // A still run of the animated scene is refused, naming what is animated.
    const auto still = run(fmt::format("{} run {} --out {}", binary("vxf"), dir.path("s.json"), dir.path("out")));
    CHECK(still.status == 1);
    CHECK_THAT(still.err, Catch::Contains("the scene is animated (/objects/0/mesh)"));
    // Bad ranges are usage errors.
    const auto backwards = runFrames(dir, "3-1");
    CHECK(backwards.status == 2);
    CHECK_THAT(backwards.err, Catch::Contains("--frames: '3-1': the range runs backwards"));
}
