#include <vxf/pipeline/Graph.h>

#include <vxf/core/Error.h>
#include <vxf/io/ContentHash.h>
#include <vxf/io/VoxelSetFile.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <filesystem>

namespace {

void writeSource(const std::string& path)
{
    vxf::VoxelSet set;
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    for (int i = 0; i < 8; ++i) density->tree().setValueOn(openvdb::Coord(i, 0, 0), float(i));
    set.put(density);
    vxf::writeVoxelSet(path, set);
}

std::string graph(double value, int radius)
{
    return R"({
  "nodes": {
    "source": {"file": "in.vdb"},
    "scaled": {"op": "mul", "input": "source", "params": {"grid": "density", "value": )" +
        std::to_string(value) + R"(}},
    "soft": {"op": "blur", "input": "scaled", "params": {"grid": "density", "radius": )" +
        std::to_string(radius) + R"(}},
    "unused": {"op": "normalize", "input": "source", "params": {"grid": "density"}}
  },
  "outputs": {"soft": "out.vdb", "scaled": "scaled.vdb"}
})";
}

std::map<std::string, std::string> actions(const vxf::GraphReport& r)
{
    std::map<std::string, std::string> m;
    for (const auto& n : r.nodes) m[n.node] = n.action;
    return m;
}

} // namespace

TEST_CASE("the graph runs only what its outputs need and caches every node", "[graph]")
{
    vxf::test::TempDir dir;
    writeSource(dir.path("in.vdb"));
    vxf::test::spit(dir.path("p.json"), graph(2.0, 1));
    const auto first = vxf::runGraph(dir.path("p.json"), dir.path("cache"));
    CHECK(actions(first) == std::map<std::string, std::string>{{"source", "ran"}, {"scaled", "ran"}, {"soft", "ran"}});
    const auto scaled = vxf::readVoxelSet(dir.path("scaled.vdb"));
    CHECK(scaled.get<openvdb::FloatGrid>("density")->tree().getValue(openvdb::Coord(3, 0, 0)) == 6.0f);
    CHECK(scaled.stage() == "op");

    const auto second = vxf::runGraph(dir.path("p.json"), dir.path("cache"));
    CHECK(actions(second) == std::map<std::string, std::string>{{"soft", "reused"}, {"scaled", "reused"}});

    vxf::test::spit(dir.path("p.json"), graph(2.0, 2)); // only the blur changes
    const auto third = vxf::runGraph(dir.path("p.json"), dir.path("cache"));
    CHECK(actions(third) == std::map<std::string, std::string>{{"soft", "ran"}, {"scaled", "reused"}});

    // A newer file with the same bytes: nothing to do (the cache keys on bytes, not times).
    std::filesystem::last_write_time(dir.path("in.vdb"), std::filesystem::file_time_type::clock::now());
    CHECK(actions(vxf::runGraph(dir.path("p.json"), dir.path("cache")))["soft"] == "reused");
    writeSource(dir.path("in.vdb")); // rewritten: OpenVDB stamps each file with a new UUID, so it counts as new
    CHECK(actions(vxf::runGraph(dir.path("p.json"), dir.path("cache")))["source"] == "ran");
}

TEST_CASE("bad graphs name the file and the node", "[graph]")
{
    vxf::test::TempDir dir;
    writeSource(dir.path("in.vdb"));
    const auto fails = [&](const std::string& text, const std::string& message) {
        vxf::test::spit(dir.path("bad.json"), text);
        INFO(text);
        CHECK_THROWS_WITH(vxf::runGraph(dir.path("bad.json"), dir.path("cache")), Catch::Contains("bad.json") && Catch::Contains(message));
    };
    fails(R"({"nodes": {"a": {"file": "in.vdb"}}, "outputs": {"b": "x.vdb"}})", "no node named 'b'");
    fails(R"({"nodes": {"a": {"op": "blur", "input": "z", "params": {"grid": "density"}}}, "outputs": {"a": "x.vdb"}})",
        "/nodes/a: input 'z'");
    fails(
        R"({"nodes": {"a": {"op": "blur", "input": "b", "params": {"grid": "density"}}, "b": {"op": "blur", "input": "a", "params": {"grid": "density"}}}, "outputs": {"a": "x.vdb"}})",
        "cycle");
    fails(
        R"({"nodes": {"s": {"file": "in.vdb"}, "a": {"op": "blur", "input": "s", "params": {"grid": "density", "radius": 99}}}, "outputs": {"a": "x.vdb"}})",
        "radius");
    fails(R"({"nodes": {"a": {"op": "sharpen", "input": "a"}}, "outputs": {}})", "/nodes/a/op");
    fails(R"({"nodes": {"a": {"file": "in.vdb"}}, "outputs": {"a": "x.vdb"}, })", "invalid JSON");
}

TEST_CASE("recorded commands become a graph that replays them", "[graph]")
{
    vxf::test::TempDir dir;
    writeSource(dir.path("in.vdb"));
    vxf::recordStep(dir.path("p.json"), "mul", {{"grid", "density"}, {"value", 3}}, dir.path("in.vdb"), dir.path("a.vdb"));
    vxf::recordStep(dir.path("p.json"), "add", {{"grid", "density"}, {"value", 1}}, dir.path("a.vdb"), dir.path("b.vdb"));
    const auto g = nlohmann::json::parse(vxf::test::slurp(dir.path("p.json")));
    CHECK(g["nodes"]["add"]["input"] == "mul");
    CHECK(g["nodes"]["mul"]["input"] == "in");
    CHECK(g["nodes"]["in"]["file"] == "in.vdb"); // relative to the graph
    vxf::runGraph(dir.path("p.json"), dir.path("cache"));
    CHECK(vxf::readVoxelSet(dir.path("b.vdb")).get<openvdb::FloatGrid>("density")->tree().getValue(openvdb::Coord(2, 0, 0)) == 7.0f);
}

TEST_CASE("a graph runs the pipeline stages and combines nodes (with)", "[graph]")
{
    vxf::test::TempDir dir;
    vxf::test::spit(dir.path("s.json"), R"({
  "objects": [{"mesh": "builtin:sphere", "material": {"albedo": 0.8, "mean_free_path": 0.3}}],
  "lights": [{"type": "point", "position": [0, 0, 2], "intensity": 3}],
  "camera": {"position": [0, -4, 0], "look_at": [0, 0, 0]}
})");
    vxf::test::spit(dir.path("p.json"), R"({
  "nodes": {
    "vox": {"op": "voxelize", "params": {"mesh": "builtin:sphere", "dim": 16}},
    "lit": {"op": "light", "input": "vox", "params": {"scene": "s.json"}},
    "sc": {"op": "scatter", "input": "lit", "params": {"passes": 1, "directions": 4}},
    "glow": {"op": "mul", "input": "sc", "params": {"grid": "scatter", "value": 2}},
    "mixed": {"op": "blend", "input": "sc", "with": "glow", "params": {"grid": "scatter", "with": "scatter", "mode": "mix"}},
    "image": {"op": "render", "input": "mixed", "params": {"scene": "s.json", "image": "g.exr", "png": "g.png", "width": 16, "height": 12, "samples": 1}}
  },
  "outputs": {"image": "mixed.vdb", "sc": "sc.vdb"}
})");
    const auto report = vxf::runGraph(dir.path("p.json"), dir.path("cache"));
    CHECK(report.nodes.size() == 6);
    CHECK(std::filesystem::exists(dir.path("g.exr")));
    CHECK(std::filesystem::exists(dir.path("g.png")));
    std::filesystem::remove(dir.path("g.exr")); // a lost image is made again; nothing else reruns
    const auto again = vxf::runGraph(dir.path("p.json"), dir.path("cache"));
    CHECK(actions(again) == std::map<std::string, std::string>{{"image", "ran"}, {"mixed", "reused"}, {"sc", "reused"}});
    CHECK(std::filesystem::exists(dir.path("g.exr")));
    auto plain = vxf::readVoxelSet(dir.path("sc.vdb")).get<openvdb::Vec3SGrid>("scatter");
    auto mixed = vxf::readVoxelSet(dir.path("mixed.vdb")).get<openvdb::Vec3SGrid>("scatter");
    REQUIRE(plain->activeVoxelCount() > 0);
    double worst = 0.0;
    for (auto it = plain->cbeginValueOn(); it; ++it) {
        worst = std::max(worst, double((mixed->tree().getValue(it.getCoord()) - *it * 1.5f).length()));
    }
    CHECK(worst < 1e-5);
    vxf::test::spit(dir.path("q.json"),
        R"({"nodes": {"s": {"file": "sc.vdb"}, "v": {"op": "voxelize", "input": "s", "params": {"mesh": "builtin:box"}}}, "outputs": {"v": "v.vdb"}})");
    CHECK_THROWS_WITH(vxf::runGraph(dir.path("q.json"), dir.path("cache")), Catch::Contains("takes no input"));
}

TEST_CASE("cache keys name the program: the fingerprint of the running executable", "[graph]")
{
    // vxf run's stages and the graph's nodes key on it, so a rebuilt vxf does not take what
    // an older one computed. It is the executable's bytes, computed once.
    const std::string& fingerprint = vxf::programFingerprint();
    CHECK(fingerprint == vxf::fileFingerprint("/proc/self/exe"));
    CHECK(fingerprint.size() == 16);
    CHECK(&vxf::programFingerprint() == &fingerprint);
}
