// Every stage and every operator gives the same output with 1 and with 2 threads.
#include <vxf/pipeline/Operators.h>

#include <vxf/io/ImageFile.h>
#include <vxf/io/VoxelSetFile.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>
#include <tbb/global_control.h>

#include <set>

using nlohmann::json;

namespace {

/// A chain through every operator of the registry, in an order where each finds what it reads:
/// the stages on a small lit sphere, then the artist operators on their grids.
std::vector<std::pair<std::string, json>> everyOperator(const std::string& scene, const std::string& image, const std::string& other)
{
    return {
        {"voxelize", {{"mesh", "builtin:sphere"}, {"dim", 24}}},
        {"light", {{"scene", scene}}},
        {"scatter", {{"passes", 3}, {"directions", 8}, {"fine_passes", 1}, {"coarse_factor", 2}, {"tolerance", 0.0}}},
        {"scatter", {{"directions", 8}, {"kernel", "sweep"}, {"tolerance", 1e-3}}},
        {"scatter", {{"directions", 8}, {"kernel", "gather"}, {"fine_passes", 0}, {"tolerance", 1e-3}}}, // corrected by sweeps
        {"render", {{"scene", scene}, {"image", image}, {"width", 24}, {"height", 16}, {"samples", 2}, {"max_samples", 8}}},
        {"gradient",
            {{"kind", "surface_distance"}, {"distance", 0.3}, {"colors", json::array({json::array({1, 0, 0}), json::array({0, 0, 1})})}}},
        {"add", {{"grid", "density"}, {"value", 0.25}, {"out", "d1"}}},
        {"sub", {{"grid", "d1"}, {"value", 0.5}}},
        {"mul", {{"grid", "scatter"}, {"value", json::array({2, 1, 0.5})}, {"out", "s1"}}},
        {"div", {{"grid", "s1"}, {"value", 3}}},
        {"pow", {{"grid", "d1"}, {"value", 0.5}}},
        {"blend", {{"grid", "s1"}, {"with", "gradient"}, {"mode", "mix"}, {"weight", 0.3}}},
        {"blur", {{"grid", "s1"}, {"radius", 2}, {"iterations", 2}, {"out", "s2"}}},
        {"select", {{"grid", "density"}, {"shape", "sphere"}, {"radius", 0.6}, {"out", "core"}}},
        {"blur_special", {{"grid", "s1"}, {"selection", "core"}, {"smoothing", 3}, {"out", "s3"}}},
        {"normalize", {{"grid", "s2"}}},
        {"denormalize", {{"grid", "s2"}, {"out", "s4"}}},
        {"edit", {{"grid", "s4"}, {"selection", "core"}, {"hue_shift", 40}, {"saturation", 0.5}}},
        {"diff", {{"grid", "s1"}, {"with", "s4"}, {"out", "d"}}},
        {"apply_diff", {{"grid", "s3"}, {"with", "d"}, {"smooth", 2}}},
        {"remove", {{"grid", "s3"}, {"with", "core"}}},
        {"include", {{"grid", "s3"}, {"with", "s2"}}},
        {"split", {{"grid", "s3"}}},
        {"merge", {{"x", "s3.z"}, {"y", "s3.x"}, {"z", "s3.y"}, {"out", "s5"}}},
        {"rename", {{"grid", "s5"}, {"to", "s6"}}},
        {"copy", {{"grid", "density"}, {"from_file", other}, {"to", "copied"}, {"resample", true}}},
        {"noise", {{"grid", "s6"}, {"selection", "core"}, {"frequency", 3.0}, {"per_channel", true}, {"out", "s7"}}},
        {"noise", {{"grid", "d1"}, {"mode", "multiply"}, {"offset", 1.0}, {"amplitude", 0.3}}},
        {"paint", {{"grid", "s7"}, {"points", json::array({json::array({0, 0, 0}), json::array({0.3, 0.1, 0})})}, {"radius", 0.3}}},
        {"delete", {{"grid", "s6"}}},
    };
}

} // namespace

TEST_CASE("every stage and every operator gives the same output with 1 and 2 threads", "[ops][threads]")
{
    vxf::test::TempDir dir;
    const std::string scene = dir.path("scene.json");
    vxf::test::spit(scene, R"({
      "objects": [{"mesh": "builtin:sphere", "material": {"albedo": [0.95, 0.9, 0.8], "mean_free_path": 0.1}}],
      "lights": [{"type": "point", "position": [2, -2, 2], "intensity": 8},
                 {"type": "directional", "direction": [-1, 0.5, -1], "intensity": 1},
                 {"type": "environment", "color": 0.2, "samples": 16}],
      "camera": {"position": [0, -4, 0.5], "look_at": [0, 0, 0], "fov": 40}
    })");
    // A file for `copy` to read, on another lattice (resampled).
    {
        vxf::VoxelSet other;
        const auto& voxelize = vxf::findOperator("voxelize");
        const auto args = vxf::ops::checkArgs(voxelize, {{"mesh", "builtin:box"}, {"dim", 20}});
        vxf::ops::OpContext context{other, args, nullptr};
        voxelize.run(context);
        vxf::writeVoxelSet(dir.path("other.vdb"), other);
    }

    const auto chain = everyOperator(scene, dir.path("image.exr"), dir.path("other.vdb"));
    std::set<std::string> covered;
    for (const auto& [name, params] : chain) covered.insert(name);
    for (const auto& op : vxf::operators()) {
        INFO("operator missing from the chain: " << op.name);
        CHECK(covered.count(op.name));
    }

    vxf::VoxelSet one, two;
    for (const auto& [name, params] : chain) {
        INFO(name << " " << params.dump());
        const auto& op = vxf::findOperator(name);
        const auto args = vxf::ops::checkArgs(op, params);
        std::vector<openvdb::Vec3f> image;
        for (int threads : {1, 2}) {
            tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
            vxf::ops::OpContext context{threads == 1 ? one : two, args, nullptr};
            REQUIRE_NOTHROW(op.run(context));
            if (name == "render") {
                const vxf::RgbImage rendered = vxf::readExr(dir.path("image.exr"));
                if (threads == 1) {
                    image = rendered.pixels;
                } else {
                    CHECK(rendered.pixels == image);
                }
            }
        }
        REQUIRE(one.grids().size() == two.grids().size());
        for (std::size_t g = 0; g < one.grids().size(); ++g) {
            std::string why;
            const bool same = vxf::test::identicalGrids(*one.grids()[g], *two.grids()[g], &why);
            INFO(one.grids()[g]->getName() << ": " << why);
            CHECK(same);
        }
    }
}
