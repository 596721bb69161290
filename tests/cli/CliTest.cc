// The real binaries on real files, as a user runs them.
#include "TestSupport.h"

#include <vxf/io/ImageFile.h>
#include <vxf/io/VoxelSetFile.h>
#include <vxf/transport/Medium.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>

#include <unistd.h>

using vxf::test::binary;
using vxf::test::run;
using vxf::test::slurp;
using vxf::test::source;
using vxf::test::TempDir;

namespace fs = std::filesystem;

namespace {
std::string quoted(const std::string& s) { return "'" + s + "'"; }

/// The file `vxf run` cached for a stage (@a prefix: "voxelize-", "light-", "scatter-") in
/// @a cache, or empty for none.
std::string cachedStage(const std::string& cache, const std::string& prefix)
{
    std::string found;
    for (const auto& e : fs::directory_iterator(cache)) {
        if (e.path().filename().string().rfind(prefix, 0) == 0) found = e.path().string();
    }
    return found;
}

std::string trimmed(std::string s)
{
    while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.pop_back();
    return s;
}
/// builtin:sphere voxelized at @a dim (DIR/s.vdb) in a scene of @a material (JSON) lit by a
/// point light above it (DIR/scene.json), and lit (DIR/l.vdb).
void litSphere(const TempDir& dir, int dim, const std::string& material)
{
    REQUIRE(run(fmt::format("{} voxelize builtin:sphere -o {} --dim {} -q", binary("vxf"), dir.path("s.vdb"), dim)).status == 0);
    vxf::test::spit(dir.path("scene.json"),
        fmt::format(R"({{
  "objects": [{{"mesh": "builtin:sphere", "material": {}}}],
  "lights": [{{"type": "point", "position": [0, 0, 2], "intensity": 4}}],
  "camera": {{"position": [0, -4, 0], "look_at": [0, 0, 0]}}
}})",
            material));
    REQUIRE(run(fmt::format("{} light {} --scene {} -o {} -q", binary("vxf"), dir.path("s.vdb"), dir.path("scene.json"), dir.path("l.vdb")))
                .status == 0);
}

} // namespace

TEST_CASE("every bad input in tests/regress gives its error and no output", "[cli][regress]")
{
    int cases = 0;
    for (const auto& entry : fs::directory_iterator(source("tests/regress"))) {
        const fs::path input = entry.path();
        if (!entry.is_regular_file() || input.extension() == ".expect") continue; // fuzz/: replayed by its targets
        const fs::path expectFile = fs::path(input).replace_extension(".expect");
        REQUIRE(fs::exists(expectFile));
        const std::string expected = trimmed(slurp(expectFile.string()));
        TempDir dir;
        const std::string output = dir.path("out.vdb");
        const std::string ext = input.extension().string();
        const std::string command = ext == ".vxf" ? fmt::format("{} {} {}", binary("vxf2vdb"), quoted(input.string()), quoted(output))
            : ext == ".vdb"                       ? fmt::format("{} info {}", binary("vxf"), quoted(input.string()))
                            : fmt::format("{} voxelize {} -o {} --dim 16", binary("vxf"), quoted(input.string()), quoted(output));
        const auto result = run(command);
        INFO(input.filename().string() << "\nstderr: " << result.err);
        CHECK(result.status == 1);
        CHECK(result.err.find(expected) != std::string::npos);
        CHECK(result.err.find(ext == ".vxf" ? "vxf2vdb: " : ext == ".vdb" ? "vxf: info: " : "vxf: voxelize: ") == 0);
        CHECK_FALSE(fs::exists(output));
        CHECK(fs::is_empty(dir.root())); // no temporary left behind either
        ++cases;
    }
    CHECK(cases >= 25);
}

TEST_CASE("a failed conversion keeps the existing output file", "[cli][regress]")
{
    TempDir dir;
    const std::string output = dir.path("keep.vdb");
    REQUIRE(run(fmt::format("{} {} {}", binary("vxf2vdb"), source("tests/data/thesis_sample.vxf"), output)).status == 0);
    const std::string before = slurp(output);
    CHECK(run(fmt::format("{} {} {}", binary("vxf2vdb"), source("tests/regress/duplicate_voxel.vxf"), output)).status == 1);
    CHECK(slurp(output) == before);
}

TEST_CASE("vxf voxelize writes a voxel set that OpenVDB's tools read", "[cli][voxelize]")
{
    TempDir dir;
    const std::string output = dir.path("sphere.vdb");
    const auto result = run(fmt::format("{} voxelize builtin:sphere -o {} --dim 48 --band 2", binary("vxf"), output));
    INFO(result.err);
    REQUIRE(result.status == 0);
    CHECK(result.out.find("voxelized builtin:sphere") != std::string::npos);
    CHECK(result.out.find("active voxels") != std::string::npos);
    CHECK(result.out.find("seconds") != std::string::npos);

    const auto print = run("vdb_print -l " + output);
    REQUIRE(print.status == 0);
    CHECK(print.out.find("Name: surface") != std::string::npos);
    CHECK(print.out.find("class: level set") != std::string::npos);
    CHECK(print.out.find("Name: density") != std::string::npos);
    CHECK(print.out.find("class: fog volume") != std::string::npos);
    CHECK(print.out.find("vxf:stage: voxelize") != std::string::npos);

    const auto python = run("/usr/bin/python3 -c \"import pyopenvdb as vdb; grids, meta = vdb.readAll('" + output +
        "'); print(sorted((g.name, g.gridClass, g.activeVoxelCount() > 0) for g in grids)); "
        "print(meta['vxf:stage'])\"");
    INFO(python.err);
    REQUIRE(python.status == 0);
    CHECK(python.out == "[('density', 'fog volume', True), ('surface', 'level set', True)]\nvoxelize\n");

    const auto info = run(fmt::format("{} info --json {}", binary("vxf"), output));
    REQUIRE(info.status == 0);
    const auto json = nlohmann::json::parse(info.out);
    CHECK(json["metadata"]["vxf:stage"] == "voxelize");
    CHECK(json["metadata"]["vxf:params"]["dim"] == 48);
    CHECK(json["metadata"]["vxf:params"]["band"] == 2.0);
    CHECK(json["grids"].size() == 2);
    // The provenance of a real file against the metadata schema.
    CHECK(vxf::test::schemaErrors(json["metadata"], "schemas/vxf-metadata.schema.json") == "");
    const auto table = run(fmt::format("{} info {}", binary("vxf"), output));
    CHECK(table.status == 0);
    CHECK(table.out.find("stage 'voxelize'") != std::string::npos);
    CHECK(table.out.find("world units") != std::string::npos);
}

TEST_CASE("files made by other tools (pyopenvdb) are read, listed and converted", "[cli][interop]")
{
    TempDir dir;
    const std::string made = dir.path("houdini.vdb");
    const auto python = run("/usr/bin/python3 -c \"import pyopenvdb as vdb\n"
                            "d = vdb.FloatGrid(); d.name = 'density'; d.gridClass = vdb.GridClass.FOG_VOLUME\n"
                            "d.transform = vdb.createLinearTransform(voxelSize=0.5)\n"
                            "a = d.getAccessor(); a.setValueOn((-1, 0, 0), 1.0); a.setValueOn((-1, 0, 1), 0.5)\n"
                            "a.setValueOn((-1, 1, 0), 0.25)\n"
                            "v = vdb.Vec3SGrid(); v.name = 'vel'; v.transform = vdb.createLinearTransform(voxelSize=0.25)\n"
                            "v.getAccessor().setValueOn((0, 0, 0), (1.0, 2.0, 3.0))\n"
                            "d['blender/solver'] = 'mantaflow'; d.saveFloatAsHalf = True\n"
                            "vdb.write('" +
        made + "', grids=[d, v], metadata={'creator': 'pyopenvdb'})\"");
    INFO(python.err);
    REQUIRE(python.status == 0);
    const auto info = run(fmt::format("{} info --json {}", binary("vxf"), made));
    REQUIRE(info.status == 0);
    const auto json = nlohmann::json::parse(info.out);
    CHECK(json["metadata"]["creator"] == "pyopenvdb");
    REQUIRE(json["grids"].size() == 2);
    // Each grid's value range over its active voxels, its storage, and its writer's metadata.
    const auto& density = json["grids"][0]["name"] == "density" ? json["grids"][0] : json["grids"][1];
    const auto& vel = json["grids"][0]["name"] == "density" ? json["grids"][1] : json["grids"][0];
    CHECK(density["min"] == 0.25);
    CHECK(density["max"] == 1.0);
    CHECK(density["mean"].get<double>() == Approx(1.75 / 3.0));
    CHECK(density["storage"] == "half");
    CHECK(density["metadata"]["blender/solver"] == "mantaflow");
    CHECK(vel["storage"] == "float");
    CHECK(vel["mean"] == nlohmann::json{1.0, 2.0, 3.0});
    const auto table = run(fmt::format("{} info {}", binary("vxf"), made));
    CHECK(table.out.find("(no vxf provenance)") != std::string::npos);
    CHECK(table.out.find("(passed through)") != std::string::npos); // 'vel' has no vxf role
    CHECK(table.out.find("(own transform)") != std::string::npos); // nor the shared transform
    CHECK(table.out.find("0.25 / 0.5833 / 1") != std::string::npos); // min / mean / max

    const auto text = run(fmt::format("{} {} {}", binary("vdb2vxf"), made, dir.path("h.vxf")));
    INFO(text.err);
    REQUIRE(text.status == 0);
    CHECK(text.err.find("skipped grid 'vel': its transform differs from the other grids'") != std::string::npos);
    CHECK(slurp(dir.path("h.vxf")).find("grid density float class=fog_volume\ncount 3\n") != std::string::npos);
}

TEST_CASE("vxf run says what repairing a scene's mesh did, as vxf voxelize does", "[cli][run]")
{
    TempDir dir;
    vxf::test::spit(dir.path("open.off"),
        "OFF\n8 5 0\n-1 -1 -1\n1 -1 -1\n-1 1 -1\n1 1 -1\n-1 -1 1\n1 -1 1\n-1 1 1\n1 1 1\n"
        "4 0 4 6 2\n4 1 3 7 5\n4 0 1 5 4\n4 2 6 7 3\n4 0 2 3 1\n");
    vxf::test::spit(dir.path("open.json"), R"({
  "objects": [{"name": "box", "mesh": "open.off", "material": {"albedo": 0.5, "mean_free_path": 0.5}},
              {"name": "floor", "mesh": "open.off", "role": "occluder", "transform": {"translate": [0, 0, -3]}}],
  "lights": [{"type": "directional", "direction": [0, 0, -1]}],
  "camera": {"position": [0, -6, 0], "look_at": [0, 0, 0]},
  "voxelize": {"dim": 16}, "scatter": {"passes": 1, "directions": 4},
  "render": {"width": 16, "height": 12, "samples": 1}
})");
    for (int pass = 0; pass < 2; ++pass) { // run, then every stage but the render cached: the same words
        const auto result = run(fmt::format("{} run {} --out {}", binary("vxf"), dir.path("open.json"), dir.path("out")));
        INFO(result.out << result.err);
        REQUIRE(result.status == 0);
        const std::string said = fmt::format("vxf: run: warning: {}: the mesh is open: 1 holes", dir.path("open.off"));
        CHECK(result.err.find(said) != std::string::npos);
        CHECK(result.err.find(said, result.err.find(said) + 1) == std::string::npos); // once per file
    }
}

TEST_CASE("vxf voxelize on a real open mesh warns and still voxelizes", "[cli][voxelize]")
{
    TempDir dir;
    vxf::test::spit(dir.path("open.off"),
        "OFF\n8 5 0\n-1 -1 -1\n1 -1 -1\n-1 1 -1\n1 1 -1\n-1 -1 1\n1 -1 1\n-1 1 1\n1 1 1\n"
        "4 0 4 6 2\n4 1 3 7 5\n4 0 1 5 4\n4 2 6 7 3\n4 0 2 3 1\n");
    const auto result = run(fmt::format("{} voxelize {} -o {} --voxel-size 0.1", binary("vxf"), dir.path("open.off"), dir.path("o.vdb")));
    CHECK(result.status == 0);
    CHECK(result.err.find("vxf: voxelize: warning: ") == 0);
    CHECK(result.err.find("the mesh is open: 1 holes") != std::string::npos);
    const auto set = vxf::readVoxelSet(dir.path("o.vdb"));
    CHECK(set.find("density")->activeVoxelCount() > 6000); // a filled 20^3 cube, not a leaky shell
}

TEST_CASE("real meshes from Debian's libcgal-demo: the bunny and broken ones", "[cli][voxelize][real]")
{
    TempDir dir;
    const std::string data = "/usr/share/doc/libcgal-dev/data.tar.gz";
    REQUIRE(fs::exists(data)); // scripts/install-deps installs libcgal-demo
    REQUIRE(run(fmt::format("tar -xzf {} -C {} data/meshes/bunny00.off data/meshes/elephant-with-holes.off "
                            "data/meshes/cube-ouvert.off data/meshes/blobby_3cc.off",
                    data, dir.root().string()))
                .status == 0);
    const auto mesh = [&](const char* name) { return dir.path(std::string("data/meshes/") + name); };

    const auto bunny = run(fmt::format("{} voxelize {} -o {} --dim 64", binary("vxf"), mesh("bunny00.off"), dir.path("bunny.vdb")));
    INFO(bunny.err);
    REQUIRE(bunny.status == 0);
    CHECK(bunny.err.empty()); // a clean closed mesh: no warnings
    CHECK(bunny.out.find("(75408 triangles)") != std::string::npos);

    const auto elephant =
        run(fmt::format("{} voxelize {} -o {} --dim 64", binary("vxf"), mesh("elephant-with-holes.off"), dir.path("e.vdb")));
    INFO(elephant.err);
    REQUIRE(elephant.status == 0);
    CHECK(elephant.err.find("the mesh is open") != std::string::npos);
    CHECK(elephant.err.find("filled") != std::string::npos);

    // An open cube (one face missing): filled, so the interior is the whole cube, not a shell.
    REQUIRE(run(fmt::format("{} voxelize {} -o {} --dim 32 -q", binary("vxf"), mesh("cube-ouvert.off"), dir.path("c.vdb"))).status == 0);
    const auto cube = vxf::readVoxelSet(dir.path("c.vdb"));
    const auto density = cube.get<openvdb::FloatGrid>("density");
    const auto box = cube.find("surface")->evalActiveVoxelBoundingBox();
    const openvdb::Coord centre((box.min().asVec3i() + box.max().asVec3i()) / 2);
    CHECK(density->tree().getValue(centre) == 1.0f);

    // Three components in one file.
    const auto blobs = run(fmt::format("{} voxelize {} -o {} --dim 48 -q", binary("vxf"), mesh("blobby_3cc.off"), dir.path("b.vdb")));
    INFO(blobs.err);
    CHECK(blobs.status == 0);
}

TEST_CASE("command-line usage errors exit with status 2", "[cli]")
{
    TempDir dir;
    const std::string vxf = binary("vxf");
    const auto noOutput = run(vxf + " voxelize builtin:box --dim 8");
    CHECK(noOutput.status == 2);
    CHECK(noOutput.err.find("vxf: voxelize: --output is required") == 0);
    const auto both = run(fmt::format("{} voxelize builtin:box -o {} --dim 8 --voxel-size 0.1", vxf, dir.path("x.vdb")));
    CHECK(both.status == 2);
    CHECK(both.err == "vxf: voxelize: give --voxel-size or --dim, not both\n");
    const auto unknown = run(fmt::format("{} voxelize builtin:teapot -o {} --dim 8", vxf, dir.path("x.vdb")));
    CHECK(unknown.status == 2);
    CHECK(unknown.err.find("unknown built-in mesh 'builtin:teapot'") != std::string::npos);
    const auto badBand = run(fmt::format("{} voxelize builtin:box -o {} --dim 8 --band 0", vxf, dir.path("x.vdb")));
    CHECK(badBand.status == 2);
    CHECK(badBand.err.find("--band") != std::string::npos);
    const auto zeroSize = run(fmt::format("{} voxelize builtin:box -o {} --voxel-size 0", vxf, dir.path("x.vdb")));
    CHECK(zeroSize.status == 2);
    CHECK(zeroSize.err == "vxf: voxelize: --voxel-size is 0.0, out of range (expected number >= 1.5e-05)\n");
    // The stage commands' options are their operators' parameters (pipeline/Operators.cc): checked
    // before any work, named as the user spelled them.
    for (const char* cutoff : {"0", "0.7"}) {
        const auto badCutoff = run(fmt::format("{} scatter {} -o {} --cutoff {}", vxf, dir.path("in.vdb"), dir.path("x.vdb"), cutoff));
        CHECK(badCutoff.status == 2);
        CHECK(badCutoff.err.find(fmt::format("vxf: scatter: --cutoff is {}", cutoff)) == 0);
        CHECK(badCutoff.err.find("out of range (expected number in [1e-12, 0.5])") != std::string::npos);
    }
    const auto badFactor = run(fmt::format("{} scatter {} -o {} --coarse-factor 3", vxf, dir.path("in.vdb"), dir.path("x.vdb")));
    CHECK(badFactor.err == "vxf: scatter: --coarse-factor is 3 (expected one of 2|4|8)\n");
    const auto badWidth = run(fmt::format("{} render s.json --volume {} -o {} --width 1.5", vxf, dir.path("in.vdb"), dir.path("x.exr")));
    CHECK(badWidth.err == "vxf: render: --width: cannot read '1.5' as integer in [1, 32768]\n");
    CHECK(run(vxf + " frobnicate").status == 2);
    CHECK(run(vxf).status == 2);
    CHECK_FALSE(fs::exists(dir.path("x.vdb")));

    const auto help = run(vxf + " --help");
    CHECK(help.status == 0);
    for (const char* sub : {"voxelize", "info", "demo"}) CHECK(help.out.find(sub) != std::string::npos);
    CHECK(run(vxf + " --version").out.find("vxf 0.") == 0);
    CHECK(run(binary("vdb2vxf") + " --help").status == 0);

    const auto missing = run(fmt::format("{} info {}", vxf, dir.path("none.vdb")));
    CHECK(missing.status == 1);
    CHECK(missing.err.find("none.vdb: no such file") != std::string::npos);
}

TEST_CASE("vxf2vdb and vdb2vxf round-trip real files", "[cli][convert]")
{
    TempDir dir;
    const std::string sample = source("tests/data/thesis_sample.vxf");
    REQUIRE(run(fmt::format("{} {} {}", binary("vxf2vdb"), sample, dir.path("a.vdb"))).status == 0);
    REQUIRE(run(fmt::format("{} {} {}", binary("vdb2vxf"), dir.path("a.vdb"), dir.path("b.vxf"))).status == 0);
    REQUIRE(run(fmt::format("{} {} {}", binary("vxf2vdb"), dir.path("b.vxf"), dir.path("b.vdb"))).status == 0);
    REQUIRE(run(fmt::format("{} {} {}", binary("vdb2vxf"), dir.path("b.vdb"), dir.path("c.vxf"))).status == 0);
    CHECK(slurp(dir.path("b.vxf")) == slurp(dir.path("c.vxf")));
    const std::string text = slurp(dir.path("b.vxf"));
    CHECK(text.find("size 4 4 2 0.25\nmin -0.5 -0.5 0\nmax 0.5 0.5 0.5\n") != std::string::npos);
    // "3 0 0 0 0 0 0" (inactive, background value) carries nothing and is not written back.
    CHECK(text.find("grid color vec3\ncount 7\n") != std::string::npos);
    CHECK(text.find("2 2 1 1 0.333333 0.666667 1\n") != std::string::npos);
    const auto a = vxf::readVoxelSet(dir.path("a.vdb"));
    const auto b = vxf::readVoxelSet(dir.path("b.vdb"));
    CHECK(vxf::test::identicalGrids(*a.find("color"), *b.find("color")));
    CHECK(a.stage() == "convert");

    // A voxelized mesh through text and back: same voxels, level-set interior restored.
    REQUIRE(run(fmt::format("{} voxelize builtin:sphere -o {} --dim 24 -q", binary("vxf"), dir.path("s.vdb"))).status == 0);
    const auto toText = run(fmt::format("{} {} {} --grid surface --grid density", binary("vdb2vxf"), dir.path("s.vdb"), dir.path("s.vxf")));
    INFO(toText.err);
    REQUIRE(toText.status == 0);
    CHECK(toText.err.find("different active voxels") != std::string::npos);
    REQUIRE(run(fmt::format("{} {} {}", binary("vxf2vdb"), dir.path("s.vxf"), dir.path("s2.vdb"))).status == 0);
    const auto original = vxf::readVoxelSet(dir.path("s.vdb"));
    const auto back = vxf::readVoxelSet(dir.path("s2.vdb"));
    auto surface = back.get<openvdb::FloatGrid>("surface");
    CHECK(surface->getGridClass() == openvdb::GRID_LEVEL_SET);
    const openvdb::Coord centre = back.transform().worldToIndexCellCentered(openvdb::Vec3d(0.0));
    CHECK(surface->tree().getValue(centre) < 0.0f); // inside, from the signed flood fill
    // Same values at the same world positions.
    auto originalSurface = original.get<openvdb::FloatGrid>("surface");
    int compared = 0;
    for (auto it = originalSurface->cbeginValueOn(); it; ++it, ++compared) {
        const auto moved = back.transform().worldToIndexCellCentered(original.transform().indexToWorld(it.getCoord()));
        if (surface->tree().getValue(moved) != *it) FAIL("surface value moved at " << it.getCoord());
    }
    CHECK(compared > 1000);

    const auto badGrid = run(fmt::format("{} {} {} --grid nothing", binary("vdb2vxf"), dir.path("s.vdb"), dir.path("n.vxf")));
    CHECK(badGrid.status == 2); // a usage error, as vdb2vol's
    CHECK(badGrid.err == fmt::format("vdb2vxf: {}: no grid named 'nothing' to write\n", dir.path("s.vdb")));
    CHECK_FALSE(fs::exists(dir.path("n.vxf")));
}

TEST_CASE(
    "SIGINT, SIGTERM and SIGHUP stop a long scatter: exit 128+N, the previous output intact, no temporary file left", "[cli][interrupt]")
{
    TempDir dir;
    litSphere(dir, 32, R"({"albedo": 0.999, "mean_free_path": 0.05})");
    fs::copy_file(dir.path("l.vdb"), dir.path("out.vdb")); // a previous result the interrupted run must not touch
    const std::string before = slurp(dir.path("out.vdb"));
    // Ctrl-C, what `timeout`, schedulers and farms send, and a closed terminal: the same.
    for (const auto& [name, status] : {std::pair<std::string, int>{"INT", 130}, {"TERM", 143}, {"HUP", 129}}) {
        CAPTURE(name);
        // Thousands of plain gather passes at albedo 0.999 (minutes), interrupted after a second.
        const auto result = run(fmt::format("({} scatter {} -o {} --passes 5000 --tolerance 0 --directions 64 & pid=$!; sleep 1; "
                                            "kill -{} $pid; wait $pid)",
            binary("vxf"), dir.path("l.vdb"), dir.path("out.vdb"), name));
        CHECK(result.status == status);
        CHECK(result.err.find(fmt::format("vxf: scatter: interrupted (SIG{}); no output written", name)) != std::string::npos);
        CHECK(slurp(dir.path("out.vdb")) == before);
        std::vector<std::string> left;
        for (const auto& entry : fs::directory_iterator(dir.root())) left.push_back(entry.path().filename().string());
        std::sort(left.begin(), left.end());
        CHECK(left == std::vector<std::string>{"l.vdb", "out.vdb", "s.vdb", "scene.json"});
    }
}

TEST_CASE("a scatter refuses light that is not finite, naming the file, grid and voxel, and writes nothing", "[cli][scatter]")
{
    // One NaN in the source spread downwind through every sweep: the whole scatter came out NaN
    // and was written as zeros, exit 0. Files from other tools or edited by hand can hold them.
    TempDir dir;
    litSphere(dir, 16, R"({"albedo": 0.9, "mean_free_path": 0.2})");
    REQUIRE(run(fmt::format("{} scatter {} -o {} -q", binary("vxf"), dir.path("l.vdb"), dir.path("ok.vdb"))).status == 0);
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    for (const auto& [grid, value] : {std::pair<std::string, openvdb::Vec3f>{"scatter_source", openvdb::Vec3f(nan, 1.0f, 1.0f)},
             {"direct", openvdb::Vec3f(1.0f, inf, 1.0f)}}) {
        CAPTURE(grid);
        vxf::VoxelSet set = vxf::readVoxelSet(dir.path("l.vdb"));
        auto poisoned = set.get<openvdb::Vec3SGrid>(grid)->deepCopy();
        const openvdb::Coord first = poisoned->cbeginValueOn().getCoord();
        poisoned->tree().setValue(first, value);
        poisoned->tree().setValue(first.offsetBy(0, 0, 1), value);
        set.put(poisoned);
        vxf::writeVoxelSet(dir.path("bad.vdb"), set);
        const auto refused = run(fmt::format("{} scatter {} -o {} -q", binary("vxf"), dir.path("bad.vdb"), dir.path("x.vdb")));
        INFO(refused.err);
        CHECK(refused.status == 1);
        CHECK_THAT(refused.err,
            Catch::Contains(fmt::format("vxf: scatter: {}: grid '{}' holds 2 NaN or infinite values (the first at voxel ({}, {}, {}))",
                dir.path("bad.vdb"), grid, first.x(), first.y(), first.z())));
        CHECK_FALSE(fs::exists(dir.path("x.vdb")));
    }
}

TEST_CASE("a write past the file size limit is an error that keeps the previous output", "[cli][interrupt]")
{
    TempDir dir;
    vxf::test::spit(dir.path("out.vdb"), "the previous output");
    const auto result =
        run(fmt::format("(ulimit -f 64; {} voxelize builtin:sphere -o {} --dim 64 -q)", binary("vxf"), dir.path("out.vdb")));
    CHECK(result.status == 1);
    CHECK(result.err == fmt::format("vxf: voxelize: {}: cannot write: File too large\n", dir.path("out.vdb")));
    CHECK(slurp(dir.path("out.vdb")) == "the previous output");
    CHECK(std::distance(fs::directory_iterator(dir.root()), fs::directory_iterator()) == 1); // no temporary file left
    // The converters' own writers (text VXF, Mitsuba's volume) too.
    REQUIRE(run(fmt::format("{} voxelize builtin:sphere -o {} --dim 64 -q", binary("vxf"), dir.path("big.vdb"))).status == 0);
    for (const auto& [tool, out] : {std::pair<std::string, std::string>{"vdb2vxf", "out.vxf"}, {"vdb2vol", "out.vol"}}) {
        vxf::test::spit(dir.path(out), "the previous output");
        const auto converted =
            run(fmt::format("(ulimit -f 16; {} {} {} --grid density)", binary(tool), dir.path("big.vdb"), dir.path(out)));
        INFO(converted.err);
        CHECK(converted.status == 1);
        CHECK(converted.err.find(dir.path(out) + ": ") != std::string::npos);
        CHECK(slurp(dir.path(out)) == "the previous output");
    }
    CHECK(std::distance(fs::directory_iterator(dir.root()), fs::directory_iterator()) == 4);
}

TEST_CASE("an unwritable folder is an error that keeps the previous output", "[cli][interrupt]")
{
    // Root writes into any folder, so as root the command runs as nobody (setpriv), for whom the
    // folder is read-only; as anyone else the folder is made read-only.
    TempDir dir;
    vxf::test::spit(dir.path("out.vdb"), "the previous output");
    const bool root = ::geteuid() == 0;
    const auto readable =
        fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec | fs::perms::others_read | fs::perms::others_exec;
    fs::permissions(dir.root(), root ? readable : readable & ~fs::perms::owner_write);
    fs::permissions(dir.path("out.vdb"), fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read | fs::perms::others_read);
    const std::string as = root ? "setpriv --reuid=65534 --regid=65534 --clear-groups " : "";
    if (root && run(as + binary("vxf") + " --version").status != 0) {
        WARN("nobody cannot run " << binary("vxf") << " (a folder on its path is closed to others): not tested");
        return;
    }
    const auto result = run(fmt::format("{}{} voxelize builtin:sphere -o {} --dim 16 -q", as, binary("vxf"), dir.path("out.vdb")));
    fs::permissions(dir.root(), fs::perms::owner_all); // TempDir removes it
    CHECK(result.status == 1);
    CHECK(result.err == fmt::format("vxf: voxelize: {}: cannot write: Permission denied\n", dir.path("out.vdb")));
    CHECK(slurp(dir.path("out.vdb")) == "the previous output");
    CHECK(std::distance(fs::directory_iterator(dir.root()), fs::directory_iterator()) == 1); // nothing else written
}

TEST_CASE("vdb2vol writes one grid as Mitsuba's dense volume", "[cli][convert][mitsuba]")
{
    TempDir dir;
    REQUIRE(run(fmt::format("{} voxelize builtin:box -o {} --dim 8 -q", binary("vxf"), dir.path("box.vdb"))).status == 0);
    const auto result = run(fmt::format("{} {} {} --grid density --pad 0", binary("vdb2vol"), dir.path("box.vdb"), dir.path("box.vol")));
    INFO(result.err);
    REQUIRE(result.status == 0);
    // The density's active bounding box: the box's 8 voxels across and the ones its surface cuts.
    const auto set = vxf::readVoxelSet(dir.path("box.vdb"));
    const openvdb::CoordBBox box = set.find("density")->evalActiveVoxelBoundingBox();
    const openvdb::Coord size = box.dim();
    CHECK(result.out.find(fmt::format("-> {}: {}x{}x{}, 1 channel(s)", dir.path("box.vol"), size.x(), size.y(), size.z())) !=
        std::string::npos);
    const std::string bytes = slurp(dir.path("box.vol"));
    CHECK(bytes.substr(0, 3) == "VOL");
    CHECK(bytes.size() == 48 + std::size_t(size.x()) * std::size_t(size.y()) * std::size_t(size.z()) * 4);

    const auto badGrid = run(fmt::format("{} {} {} --grid nothing", binary("vdb2vol"), dir.path("box.vdb"), dir.path("n.vol")));
    CHECK(badGrid.status == 2); // a usage error: the argument names no grid of the file
    CHECK(badGrid.err == fmt::format("vdb2vol: {}: no grid named 'nothing'\n", dir.path("box.vdb")));
    CHECK_FALSE(fs::exists(dir.path("n.vol")));
}

TEST_CASE("vxf demo runs the main job on the embedded scene", "[cli][demo]")
{
    TempDir dir;
    // Small, so the test is quick; scripts/demo runs the scene's own size.
    const auto result = run(fmt::format("{} demo --out {} --dim 24 --width 64 --height 36", binary("vxf"), dir.path("out")));
    INFO(result.err);
    REQUIRE(result.status == 0);
    CHECK(result.out.find("demo: a wax candle lit by its flame") != std::string::npos);
    for (const char* stage : {"voxelize", "light", "scatter", "render"})
        CHECK(result.out.find(std::string("  ") + stage) != std::string::npos);
    const auto set = vxf::readVoxelSet(dir.path("out/demo.vdb"));
    for (const char* name : {"surface", "density", "direct", "scatter_source", "scatter", "illumination"}) {
        INFO(name);
        CHECK(set.find(name));
    }
    CHECK(fs::file_size(dir.path("out/demo.exr")) > 0);
    CHECK(slurp(dir.path("out/demo.png")).substr(1, 3) == "PNG");
    // The flame shows: the brightest pixel is its emission (3, 1.7, 0.55), above the candle
    // (its top at row 8 of 36), on the centre line.
    const vxf::RgbImage image = vxf::readExr(dir.path("out/demo.exr"));
    const auto brightest = std::max_element(
        image.pixels.begin(), image.pixels.end(), [](const openvdb::Vec3f& a, const openvdb::Vec3f& b) { return a.x() < b.x(); });
    const std::ptrdiff_t at = brightest - image.pixels.begin();
    CHECK(brightest->x() == Approx(3.0f));
    CHECK(brightest->z() == Approx(0.55f));
    CHECK(at / image.width < 8);
    CHECK(std::abs(int(at % image.width) - image.width / 2) <= 1);
    // The embedded scene is examples/candle.json, and it is valid.
    CHECK(run(fmt::format("{} light {} --scene {} -o {} -q", binary("vxf"), dir.path("out/demo.vdb"), source("examples/candle.json"),
                  dir.path("relit.vdb")))
              .status == 0);
}

TEST_CASE("vxf light lights a voxel set from a scene file", "[cli][light]")
{
    TempDir dir;
    REQUIRE(run(fmt::format("{} voxelize builtin:sphere -o {} --dim 24 -q", binary("vxf"), dir.path("s.vdb"))).status == 0);
    vxf::test::spit(dir.path("scene.json"), R"({
  "objects": [{"mesh": "builtin:sphere", "material": {"albedo": 0.9, "mean_free_path": 0.2}}],
  "lights": [{"name": "key", "type": "point", "position": [0, 0, 2], "intensity": 4},
             {"name": "off", "type": "directional", "direction": [0, 0, -1], "intensity": 0}],
  "camera": {"position": [0, -4, 0], "look_at": [0, 0, 0]}
})");
    const auto lit =
        run(fmt::format("{} light {} --scene {} -o {}", binary("vxf"), dir.path("s.vdb"), dir.path("scene.json"), dir.path("l.vdb")));
    INFO(lit.err);
    REQUIRE(lit.status == 0);
    CHECK(lit.out.find("off              skipped: zero colour or intensity") != std::string::npos);
    const auto set = vxf::readVoxelSet(dir.path("l.vdb"));
    CHECK(set.stage() == "light");
    auto direct = set.get<openvdb::Vec3SGrid>("direct");
    CHECK(direct->activeVoxelCount() > set.find("density")->activeVoxelCount()); // the medium and one voxel beyond
    // Brighter near the light (top) than on the far side (bottom).
    const auto top = set.transform().worldToIndexCellCentered(openvdb::Vec3d(0, 0, 0.95));
    const auto bottom = set.transform().worldToIndexCellCentered(openvdb::Vec3d(0, 0, -0.95));
    CHECK(direct->tree().getValue(top).x() > 100.0f * direct->tree().getValue(bottom).x());
    CHECK(set.find("surface")); // the input grids are carried along
    CHECK(set.metadata().metaValue<std::string>("vxf:material").find("sigma_s") != std::string::npos);
    // The march step: the scene's (scatter.step, 1 unless set), as vxf run lights it; --step wins.
    CHECK(nlohmann::json::parse(set.paramsJson()).at("step").get<double>() == 1.0);
    REQUIRE(run(fmt::format("{} light {} --scene {} -o {} -q --step 0.25", binary("vxf"), dir.path("s.vdb"), dir.path("scene.json"),
                    dir.path("l4.vdb")))
                .status == 0);
    CHECK(nlohmann::json::parse(vxf::readVoxelSet(dir.path("l4.vdb")).paramsJson()).at("step").get<double>() == 0.25);

    // Scatter from the file alone (the material travels in its metadata).
    const auto scattered = run(fmt::format("{} scatter {} -o {} --passes 3 --directions 16 --keep-passes --tolerance 0", binary("vxf"),
        dir.path("l.vdb"), dir.path("s2.vdb")));
    INFO(scattered.err);
    REQUIRE(scattered.status == 0);
    CHECK(scattered.out.find("3 passes (reached 3 passes") != std::string::npos);
    CHECK(scattered.out.find("the rest of the series would add about") != std::string::npos);
    const auto lit2 = vxf::readVoxelSet(dir.path("s2.vdb"));
    CHECK(lit2.stage() == "scatter");
    for (const char* name : {"scatter_pass_1", "scatter_pass_2", "scatter_pass_3", "scatter", "illumination"}) {
        INFO(name);
        CHECK(lit2.find(name));
    }
    // The sweep kernel: accelerated sweeps report themselves as such; plain sweeps keep the orders.
    const auto swept =
        run(fmt::format("{} scatter {} -o {} --kernel sweep --directions 16", binary("vxf"), dir.path("l.vdb"), dir.path("sw.vdb")));
    INFO(swept.err);
    REQUIRE(swept.status == 0);
    CHECK(swept.out.find("accelerated sweeps") != std::string::npos);
    CHECK(swept.out.find("converged in") != std::string::npos);
    CHECK(swept.out.find("voxels swept per direction") != std::string::npos);
    CHECK(vxf::readVoxelSet(dir.path("sw.vdb")).find("illumination"));
    const auto ordered = run(fmt::format("{} scatter {} -o {} --kernel sweep --directions 8 --passes 2 --keep-passes --tolerance 0",
        binary("vxf"), dir.path("l.vdb"), dir.path("sw2.vdb")));
    INFO(ordered.err);
    REQUIRE(ordered.status == 0);
    CHECK(ordered.out.find("accelerated") == std::string::npos);
    CHECK(vxf::readVoxelSet(dir.path("sw2.vdb")).find("scatter_pass_2"));
    const auto badKernel = run(fmt::format("{} scatter {} -o {} --kernel march", binary("vxf"), dir.path("l.vdb"), dir.path("bk.vdb")));
    CHECK(badKernel.status == 2);
    CHECK(badKernel.err.find("--kernel") != std::string::npos);
    CHECK_FALSE(fs::exists(dir.path("bk.vdb")));

    const auto notLit = run(fmt::format("{} scatter {} -o {}", binary("vxf"), dir.path("s.vdb"), dir.path("y.vdb")));
    CHECK(notLit.status == 1);
    CHECK(notLit.err.find("records no material") != std::string::npos);
    CHECK_FALSE(fs::exists(dir.path("y.vdb")));

    // A sigma_s grid on another lattice than the density's: the error names the file.
    {
        vxf::VoxelSet mixed = vxf::readVoxelSet(dir.path("l.vdb"));
        auto sigma = openvdb::Vec3SGrid::create(openvdb::Vec3f(1.0f));
        sigma->setName("sigma_s");
        sigma->setTransform(openvdb::math::Transform::createLinearTransform(0.5));
        sigma->fill(openvdb::CoordBBox(openvdb::Coord(-2), openvdb::Coord(2)), openvdb::Vec3f(1.0f));
        mixed.putAsIs(sigma);
        vxf::writeVoxelSet(dir.path("mixed.vdb"), mixed);
        const auto mismatch = run(fmt::format("{} scatter {} -o {}", binary("vxf"), dir.path("mixed.vdb"), dir.path("z.vdb")));
        CHECK(mismatch.status == 1);
        CHECK(mismatch.err.find("mixed.vdb: grid 'sigma_s' does not share the transform of 'density'") != std::string::npos);
        CHECK_FALSE(fs::exists(dir.path("z.vdb")));
    }

    // A bad scene names the file and the field; nothing is written.
    vxf::test::spit(dir.path("bad.json"), R"({"objects": [{"mesh": "builtin:sphere"}], "lights": [], "camera": {"position": [0, -4, 0]}})");
    const auto bad =
        run(fmt::format("{} light {} --scene {} -o {}", binary("vxf"), dir.path("s.vdb"), dir.path("bad.json"), dir.path("x.vdb")));
    CHECK(bad.status == 1);
    CHECK(bad.err.find("bad.json: /camera: Missing required property 'look_at'") != std::string::npos);
    CHECK_FALSE(fs::exists(dir.path("x.vdb")));
}

TEST_CASE("vxf run simulates only what the scene needs and reuses what did not change", "[cli][run]")
{
    TempDir dir;
    const auto scene = [&](const std::string& fov, const std::string& intensity, const std::string& material, const std::string& outputs) {
        vxf::test::spit(dir.path("s.json"),
            R"({
  "objects": [{"mesh": "builtin:sphere", "material": )" +
                material + R"(}],
  "lights": [{"type": "point", "position": [0, 0, 2], "intensity": )" +
                intensity + R"(}],
  "camera": {"position": [0, -4, 0], "look_at": [0, 0, 0], "fov": )" +
                fov + R"(},
  "voxelize": {"dim": 16},
  "scatter": {"passes": 2, "directions": 8},
  "render": {"width": 32, "height": 24, "samples": 1},
  "outputs": )" +
                outputs + "}");
        const auto result = run(fmt::format("{} run {} --out {}", binary("vxf"), dir.path("s.json"), dir.path("out")));
        INFO(result.err);
        REQUIRE(result.status == 0);
        return result.out;
    };
    const std::string wax = R"({"albedo": 0.9, "mean_free_path": 0.2})";
    const std::string first = scene("40", "3", wax, R"(["image"])");
    CHECK(first.find("voxelize  ran") != std::string::npos);
    CHECK(first.find("scatter   ran") != std::string::npos);
    CHECK(fs::exists(dir.path("out/s.exr")));
    CHECK(fs::exists(dir.path("out/s.png")));

    const std::string again = scene("40", "3", wax, R"(["image"])");
    CHECK(again.find("voxelize  reused") != std::string::npos);
    CHECK(again.find("light     reused") != std::string::npos);
    CHECK(again.find("scatter   reused") != std::string::npos);

    const std::string camera = scene("30", "3", wax, R"(["image"])"); // only the camera changed
    CHECK(camera.find("scatter   reused") != std::string::npos);
    CHECK(camera.find("render    ran") != std::string::npos);

    const std::string brighter = scene("30", "5", wax, R"(["image"])"); // one light changed
    CHECK(brighter.find("voxelize  reused") != std::string::npos);
    CHECK(brighter.find("light     ran") != std::string::npos);
    CHECK(brighter.find("scatter   ran") != std::string::npos);

    const std::string absorbing = scene("30", "5", R"({"sigma_a": 3, "sigma_s": 0})", R"(["image"])");
    CHECK(absorbing.find("scatter   skipped") != std::string::npos);
    CHECK(absorbing.find("does not scatter") != std::string::npos);

    const std::string directOnly = scene("30", "5", wax, R"(["direct"])");
    CHECK(directOnly.find("scatter   skipped") != std::string::npos);
    CHECK(directOnly.find("no requested output needs it") != std::string::npos);
    CHECK(directOnly.find("render    skipped") != std::string::npos);
}

TEST_CASE("scatter with a band, render through Embree or the level set, occluders in the chain", "[cli][render]")
{
    TempDir dir;
    vxf::test::spit(dir.path("scene.json"), R"({
  "objects": [{"mesh": "builtin:sphere", "material": {"albedo": 0.9, "mean_free_path": 0.1}},
              {"name": "card", "mesh": "builtin:box", "role": "occluder", "transform": {"scale": [0.3, 0.3, 0.02], "translate": [0, 0, 1.5]}}],
  "lights": [{"name": "key", "type": "point", "position": [0, 0, 2.5], "intensity": 4}],
  "camera": {"position": [0, -4, 0], "look_at": [0, 0, 0]},
  "render": {"width": 40, "height": 30, "samples": 1}
})");
    REQUIRE(run(fmt::format("{} voxelize builtin:sphere -o {} --dim 40 -q", binary("vxf"), dir.path("v.vdb"))).status == 0);
    const auto lit =
        run(fmt::format("{} light {} --scene {} -o {} -q", binary("vxf"), dir.path("v.vdb"), dir.path("scene.json"), dir.path("l.vdb")));
    INFO(lit.err);
    REQUIRE(lit.status == 0);
    // The card shadows the top of the sphere: the light arrives only around it.
    const auto set = vxf::readVoxelSet(dir.path("l.vdb"));
    auto direct = set.get<openvdb::Vec3SGrid>("direct");
    const auto index = [&](double x, double y, double z) { return set.transform().worldToIndexCellCentered(openvdb::Vec3d(x, y, z)); };
    CHECK(direct->tree().getValue(index(0, 0, 0.95)).x() == 0.0f);
    CHECK(direct->tree().getValue(index(0.7, 0, 0.65)).x() > 0.0f);

    const auto banded =
        run(fmt::format("{} scatter {} -o {} --passes 2 --directions 8 --band 0.2", binary("vxf"), dir.path("l.vdb"), dir.path("s.vdb")));
    INFO(banded.err);
    REQUIRE(banded.status == 0);
    CHECK(banded.out.find("band 0.2: ") != std::string::npos);
    CHECK(banded.out.find(" 8^3 and 0 128^3 tiles") != std::string::npos);

    for (const char* mode : {"", "--level-set"}) {
        INFO(mode);
        const auto image = run(fmt::format("{} render {} --volume {} -o {} --png {} {}", binary("vxf"), dir.path("scene.json"),
            dir.path("s.vdb"), dir.path("i.exr"), dir.path("i.png"), mode));
        INFO(image.err);
        REQUIRE(image.status == 0);
        CHECK(slurp(dir.path("i.png")).substr(1, 3) == "PNG");
        Imf::InputFile exr(dir.path("i.exr").c_str());
        for (const char* channel : {"R", "A", "surface.R", "direct.R", "scatter.R", "depth.Z", "normal.X"}) {
            INFO(channel);
            CHECK(exr.header().channels().findChannel(channel));
        }
    }
    // The render reads only the grids it uses: one it does not (a DCC file's velocities, damaged
    // here: its data, the file's last bytes, overwritten) stays on disk, and stops nothing.
    {
        vxf::VoxelSet withVelocity = vxf::readVoxelSet(dir.path("s.vdb"));
        auto velocity = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
        velocity->setName("vel");
        velocity->setTransform(withVelocity.transform().copy());
        velocity->tree().fill(openvdb::CoordBBox(openvdb::Coord(-16), openvdb::Coord(15)), openvdb::Vec3f(1.0f, 2.0f, 3.0f), true);
        velocity->tree().voxelizeActiveTiles();
        withVelocity.putAsIs(velocity);
        vxf::writeVoxelSet(dir.path("vel.vdb"), withVelocity, vxf::VoxelSetWriteOptions{false, false});
        std::string bytes = slurp(dir.path("vel.vdb"));
        REQUIRE(bytes.size() > 4096);
        for (std::size_t i = bytes.size() - 2048; i < bytes.size() - 16; ++i) bytes[i] = char(0x5a);
        vxf::test::spit(dir.path("vel.vdb"), bytes);
        CHECK_THROWS_WITH(vxf::readVoxelSet(dir.path("vel.vdb")), Catch::Contains("vel"));
        const auto image = run(
            fmt::format("{} render {} --volume {} -o {}", binary("vxf"), dir.path("scene.json"), dir.path("vel.vdb"), dir.path("v.exr")));
        INFO(image.err);
        CHECK(image.status == 0);
        CHECK(slurp(dir.path("v.exr")).size() > 0);
    }
    // The image writers past the file size limit: an error naming the file, the previous images
    // intact, no temporary file beside them.
    const std::string exrBefore = slurp(dir.path("i.exr")), pngBefore = slurp(dir.path("i.png"));
    const auto entries = [&] { return std::distance(fs::directory_iterator(dir.root()), fs::directory_iterator()); };
    const auto files = entries();
    const auto limited = run(fmt::format("(ulimit -f 4; {} render {} --volume {} -o {} --png {})", binary("vxf"), dir.path("scene.json"),
        dir.path("s.vdb"), dir.path("i.exr"), dir.path("i.png")));
    INFO(limited.err);
    CHECK(limited.status == 1);
    CHECK(limited.err.find(dir.path("i.exr") + ": ") != std::string::npos);
    CHECK(limited.err.find("File too large") != std::string::npos);
    CHECK(slurp(dir.path("i.exr")) == exrBefore);
    CHECK(slurp(dir.path("i.png")) == pngBefore);
    CHECK(entries() == files);
}

TEST_CASE("vxf op runs operators on real files, records them, and vxf graph replays them", "[cli][ops]")
{
    TempDir dir;
    REQUIRE(run(fmt::format("{} voxelize builtin:sphere -o {} --dim 24 -q", binary("vxf"), dir.path("v.vdb"))).status == 0);
    const std::string graph = dir.path("p.json");
    const auto mul = run(fmt::format("{} op mul {} -o {} --grid density --value 0.5,1,2 --out tinted --record {}", binary("vxf"),
        dir.path("v.vdb"), dir.path("a.vdb"), graph));
    INFO(mul.err);
    REQUIRE(mul.status == 0);
    CHECK(mul.out.find("mul on 'tinted'") != std::string::npos);
    const auto gradient = run(fmt::format("{} op gradient {} -o {} --kind radial --radius 1 --colors \"1,0,0;0,0,1\" --record {}",
        binary("vxf"), dir.path("a.vdb"), dir.path("b.vdb"), graph));
    INFO(gradient.err);
    REQUIRE(gradient.status == 0);
    const auto blur = run(fmt::format("{} op blur {} -o {} --grid gradient --kind distance --radius 2 --record {}", binary("vxf"),
        dir.path("b.vdb"), dir.path("c.vdb"), graph));
    INFO(blur.err);
    REQUIRE(blur.status == 0);
    const auto set = vxf::readVoxelSet(dir.path("c.vdb"));
    CHECK(set.stage() == "op");
    // density × the mean of (0.5, 1, 2) on a float grid; the input grid stays as it was.
    const openvdb::Coord centre(0);
    CHECK(set.get<openvdb::FloatGrid>("tinted")->tree().getValue(centre) ==
        Approx(set.get<openvdb::FloatGrid>("density")->tree().getValue(centre) * 3.5f / 3.0f));
    for (const char* name : {"surface", "density", "tinted", "gradient"}) {
        INFO(name);
        CHECK(set.find(name));
    }
    // The graph replays the three commands into fresh files, identically.
    const auto recorded = nlohmann::json::parse(slurp(graph));
    CHECK(recorded["nodes"].size() == 4);
    fs::remove(dir.path("c.vdb"));
    const auto replay = run(fmt::format("{} graph {} --cache {}", binary("vxf"), graph, dir.path("cache")));
    INFO(replay.err);
    REQUIRE(replay.status == 0);
    CHECK(replay.out.find("blur             ran") != std::string::npos);
    CHECK(vxf::test::identicalGrids(*set.find("gradient"), *vxf::readVoxelSet(dir.path("c.vdb")).find("gradient")));
    const auto again = run(fmt::format("{} graph {} --cache {}", binary("vxf"), graph, dir.path("cache")));
    CHECK(again.out.find("blur             reused") != std::string::npos);
    CHECK(again.out.find(" ran ") == std::string::npos);

    // Bad parameters: usage errors naming the operator and the parameter; nothing written.
    const auto range =
        run(fmt::format("{} op blur {} -o {} --grid density --radius 0", binary("vxf"), dir.path("v.vdb"), dir.path("x.vdb")));
    CHECK(range.status == 2);
    CHECK(range.err.find("vxf: op: blur: --radius is 0, out of range (expected integer in [1, 64])") == 0);
    const auto text = run(fmt::format("{} op mul {} -o {} --grid density --value x", binary("vxf"), dir.path("v.vdb"), dir.path("x.vdb")));
    CHECK(text.status == 2);
    CHECK(text.err.find("vxf: op: mul: --value: cannot read 'x'") == 0);
    const auto grid = run(fmt::format("{} op mul {} -o {} --grid nope --value 2", binary("vxf"), dir.path("v.vdb"), dir.path("x.vdb")));
    CHECK(grid.status == 2);
    CHECK(grid.err.find("mul: no grid named 'nope'") != std::string::npos);
    const auto unknown =
        run(fmt::format("{} op mul {} -o {} --grid density --value 2 --radius 3", binary("vxf"), dir.path("v.vdb"), dir.path("x.vdb")));
    CHECK(unknown.status == 2);
    CHECK(unknown.err.find("mul: unknown parameter or extra argument '--radius'") != std::string::npos);
    CHECK_FALSE(fs::exists(dir.path("x.vdb")));
}

TEST_CASE("the operator table of docs/cli.md and the pipeline schema are what the registry generates", "[cli][ops][drift]")
{
    const auto table = run(fmt::format("{} op --markdown", binary("vxf")));
    REQUIRE(table.status == 0);
    const std::string readme = slurp(source("docs/cli.md"));
    const std::string begin = "<!-- operators:begin -->\n", end = "<!-- operators:end -->";
    const auto from = readme.find(begin), to = readme.find(end);
    REQUIRE(from != std::string::npos);
    REQUIRE(to != std::string::npos);
    INFO("run scripts/generate to refresh docs/cli.md and schemas/pipeline.schema.json");
    CHECK(readme.substr(from + begin.size(), to - from - begin.size()) == table.out);
    const auto schema = run(fmt::format("{} op --schema", binary("vxf")));
    REQUIRE(schema.status == 0);
    CHECK(nlohmann::json::parse(schema.out) == nlohmann::json::parse(slurp(source("schemas/pipeline.schema.json"))));
    // Every operator's own help comes from the registry too.
    const auto help = run(fmt::format("{} op blend --help", binary("vxf")));
    CHECK(help.out.find("--normalize_b") != std::string::npos);
    CHECK(help.out.find("one of add|subtract|multiply|darker|lighter|mix") != std::string::npos);
}

TEST_CASE("the stage commands take the scene's knobs: flags on by default turn off with --no-NAME, overrides win", "[cli][knobs]")
{
    TempDir dir;
    litSphere(dir, 16, R"({"albedo": 0.8, "mean_free_path": 0.5})");
    // --no-accelerate: plain source iteration, one order a pass (its report says passes, not sweeps).
    const auto plain = run(fmt::format("{} scatter {} -o {} --kernel sweep --directions 8 --passes 3 --no-accelerate", binary("vxf"),
        dir.path("l.vdb"), dir.path("p.vdb")));
    INFO(plain.out << plain.err);
    REQUIRE(plain.status == 0);
    CHECK(plain.out.find("accelerated") == std::string::npos);
    CHECK(plain.out.find("3 passes") != std::string::npos);
    const auto help = run(fmt::format("{} scatter --help", binary("vxf")));
    CHECK(help.out.find("--no-accelerate") != std::string::npos);
    CHECK(help.out.find("on by default") != std::string::npos);
    // The render's knobs override the scene's: --direct lights, --no-surface, the size.
    const auto render = run(fmt::format("{} render {} --volume {} -o {} --direct lights --no-surface --width 20 --height 10 --samples 1",
        binary("vxf"), dir.path("scene.json"), dir.path("p.vdb"), dir.path("i.exr")));
    INFO(render.out << render.err);
    REQUIRE(render.status == 0);
    CHECK(render.out.find("20x10") != std::string::npos);
    const auto bad = run(fmt::format(
        "{} render {} --volume {} -o {} --direct sideways", binary("vxf"), dir.path("scene.json"), dir.path("p.vdb"), dir.path("j.exr")));
    CHECK(bad.status == 2);
    CHECK(bad.err.find("--direct") != std::string::npos);
    CHECK_FALSE(fs::exists(dir.path("j.exr")));
    // The scene schema vxf checks scenes against, its settings made from the knobs, is the committed one.
    const auto schema = run(fmt::format("{} run --schema", binary("vxf")));
    REQUIRE(schema.status == 0);
    CHECK(nlohmann::json::parse(schema.out) == nlohmann::json::parse(slurp(source("schemas/scene.schema.json"))));
}

TEST_CASE("vxf run lights and renders a fog volume made by vdb_tool (a volume object, no mesh)", "[cli][run][volume]")
{
    TempDir dir;
    const auto made = run(fmt::format("vdb_tool -sphere d=32 r=1 -ls2fog -write {}", dir.path("fog.vdb")));
    INFO(made.out << made.err);
    REQUIRE(made.status == 0);
    vxf::test::spit(dir.path("fog.json"), R"({
  "objects": [{"name": "fog", "volume": "fog.vdb", "grid": "ls2fog_sphere", "material": {"albedo": 0.9, "mean_free_path": 0.5}}],
  "lights": [{"type": "directional", "direction": [0, 0, -1], "intensity": 3}],
  "camera": {"position": [0, -4, 0], "look_at": [0, 0, 0], "fov": 40},
  "scatter": {"passes": 8, "directions": 8, "kernel": "sweep"},
  "render": {"width": 32, "height": 24, "samples": 1}
})");
    const auto result = run(fmt::format("{} run {} --out {}", binary("vxf"), dir.path("fog.json"), dir.path("out")));
    INFO(result.out << result.err);
    REQUIRE(result.status == 0);
    CHECK(result.out.find("scatter   ran") != std::string::npos);
    // The voxel set is the grid itself: its density, no surface.
    const std::string voxelFile = cachedStage(dir.path("out/cache"), "voxelize-");
    REQUIRE_FALSE(voxelFile.empty());
    const vxf::VoxelSet voxels = vxf::readVoxelSet(voxelFile);
    CHECK_FALSE(voxels.find("surface"));
    CHECK(voxels.get<openvdb::FloatGrid>("density")->activeVoxelCount() > 0);

    // The image (readExr refuses NaN and negative values): the fog lit where the camera ray
    // meets it, nearly opaque through its middle (a chord of 2 = 4 mean free paths: alpha
    // 1 − e^{−4} = 0.98); the corners miss it: black, alpha 0.
    const vxf::RgbImage image = vxf::readExr(dir.path("out/fog.exr"));
    REQUIRE(image.width == 32);
    const openvdb::Vec3f centre = image.pixels[12 * 32 + 16], corner = image.pixels[0];
    CHECK(centre[0] > 0.01f);
    CHECK(corner == openvdb::Vec3f(0.0f));
    Imf::InputFile exr(dir.path("out/fog.exr").c_str());
    std::vector<float> alpha(std::size_t(32 * 24));
    Imf::FrameBuffer frame;
    frame.insert("A", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(alpha.data()), sizeof(float), sizeof(float) * 32));
    exr.setFrameBuffer(frame);
    const Imath::Box2i window = exr.header().dataWindow();
    REQUIRE((window.min.x == 0 && window.min.y == 0));
    exr.readPixels(window.min.y, window.max.y);
    CHECK(alpha[12 * 32 + 16] == Approx(1.0 - std::exp(-4.0)).epsilon(0.05));
    CHECK(alpha[0] == 0.0f);

    // Asked for half its voxels: solved on them coarsened 2x (said so), the medium's mass kept, so
    // the chord through its middle is as opaque.
    std::string scene = vxf::test::slurp(dir.path("fog.json"));
    scene.insert(scene.find("\"scatter\""), R"("voxelize": {"dim": 16}, )");
    vxf::test::spit(dir.path("fog.json"), scene);
    const auto coarse = run(fmt::format("{} run {} --out {}", binary("vxf"), dir.path("fog.json"), dir.path("coarse")));
    INFO(coarse.out << coarse.err);
    REQUIRE(coarse.status == 0);
    CHECK_THAT(coarse.out, Catch::Contains("'fog' solved at voxel size") && Catch::Contains("coarsened 2x"));
    const vxf::VoxelSet halved = vxf::readVoxelSet(cachedStage(dir.path("coarse/cache"), "voxelize-"));
    CHECK(halved.transform().voxelSize()[0] == Approx(2.0 * voxels.transform().voxelSize()[0]));
    Imf::InputFile coarseExr(dir.path("coarse/fog.exr").c_str());
    coarseExr.setFrameBuffer(frame);
    coarseExr.readPixels(window.min.y, window.max.y);
    CHECK(alpha[12 * 32 + 16] == Approx(1.0 - std::exp(-4.0)).epsilon(0.05));
    CHECK(alpha[0] == 0.0f);
}

TEST_CASE(
    "vxf run lights a noise density made with OpenVDB (scripts/make-smoke), scattering forward by its phase", "[cli][run][volume][phase]")
{
    TempDir dir;
    const auto made = run(fmt::format("{} {} --resolution 32", vxf::test::source("scripts/make-smoke"), quoted(dir.path("smoke.vdb"))));
    INFO(made.out << made.err);
    REQUIRE(made.status == 0);
    // Lit from behind: light scattered forward comes toward the camera, backward away from it.
    const auto render = [&](double g) {
        vxf::test::spit(dir.path("smoke.json"),
            fmt::format(R"({{
  "objects": [{{"name": "smoke", "volume": "smoke.vdb", "grid": "density",
               "material": {{"albedo": 0.95, "mean_free_path": 0.05, "phase": {{"g": {}}}}}}}],
  "lights": [{{"type": "directional", "direction": [0, -1, 0], "intensity": 2}}, {{"type": "environment", "intensity": 0.1, "samples": 8}}],
  "camera": {{"position": [0, -2, 0], "look_at": [0, 0, 0], "fov": 40}},
  "scatter": {{"directions": 8}},
  "render": {{"width": 32, "height": 24, "samples": 1}}
}})",
                g));
        fs::remove_all(dir.path("out/cache")); // one stage file of each kind below
        const auto result = run(fmt::format("{} run {} --out {}", binary("vxf"), dir.path("smoke.json"), dir.path("out")));
        INFO(result.out << result.err);
        REQUIRE(result.status == 0);
        CHECK(result.out.find("light     ran") != std::string::npos);
        // A forward phase's first moment: the light stage's and the accelerated sweeps' (the
        // scene's kernel then by default); a backward phase goes by the similarity relation.
        const std::string scattered = cachedStage(dir.path("out/cache"), "scatter-");
        REQUIRE_FALSE(scattered.empty());
        const vxf::VoxelSet set = vxf::readVoxelSet(scattered);
        CHECK(bool(set.find("scatter_source_anisotropy")) == (g > 0.0));
        CHECK(bool(set.find("scatter_anisotropy")) == (g > 0.0));
        return vxf::readExr(dir.path("out/smoke.exr")); // refuses NaN and negative values
    };
    const vxf::RgbImage forward = render(0.6), backward = render(-0.6);
    double forwardSum = 0.0, backwardSum = 0.0;
    for (std::size_t i = 0; i < forward.pixels.size(); ++i) {
        forwardSum += forward.pixels[i][0];
        backwardSum += backward.pixels[i][0];
    }
    // (1.6x at 32^3: the backward medium's reduced σs' = 1.6σs scatters more light around, the
    // background shows through both alike.)
    CHECK(forwardSum > 1.3 * backwardSum);
    // The phase is recorded with the material in the lit set, so vxf render and vxf op read it.
    const std::string litFile = cachedStage(dir.path("out/cache"), "light-");
    REQUIRE_FALSE(litFile.empty());
    CHECK(vxf::recordedMaterial(vxf::readVoxelSet(litFile)).phaseG != 0.0);
}

TEST_CASE("vxf view refuses what it cannot serve before listening", "[cli][view]")
{
    TempDir dir;
    const std::string vxf = binary("vxf");
    const auto missing = run(vxf + " view " + quoted(dir.path("none.vdb")) + " --no-browser --port 0");
    CHECK(missing.status == 1);
    CHECK_THAT(missing.err, Catch::Contains("none.vdb"));
    REQUIRE(run(vxf + " voxelize builtin:sphere -o " + quoted(dir.path("s.vdb")) + " --dim 12 -q").status == 0);
    const auto grid = run(vxf + " view " + quoted(dir.path("s.vdb")) + " --no-browser --port 0 --grid nope");
    CHECK(grid.status == 2);
    CHECK_THAT(grid.err, Catch::Contains("--grid: no grid 'nope'"));
    const auto scene = run(vxf + " view " + quoted(dir.path("s.vdb")) + " --no-browser --port 0 --scene " + quoted(dir.path("no.json")));
    CHECK(scene.status == 2);
    CHECK_THAT(scene.err, Catch::Contains("no.json"));
}

TEST_CASE("vxf light places a volume object's own file by the object's transform, and says when it cannot", "[cli][light][transform]")
{
    TempDir dir;
    const auto made = run(fmt::format("{} {} --resolution 16", vxf::test::source("scripts/make-smoke"), quoted(dir.path("smoke.vdb"))));
    REQUIRE(made.status == 0);
    vxf::test::spit(dir.path("smoke.json"), R"({
  "objects": [{"name": "smoke", "volume": "smoke.vdb", "transform": {"translate": [2, 0, 0]},
               "material": {"albedo": 0.9, "mean_free_path": 0.1}}],
  "lights": [{"type": "directional", "direction": [0, 0, -1]}],
  "camera": {"position": [2, -3, 0], "look_at": [2, 0, 0]}
})");
    const auto lit = run(fmt::format("{} light {} --scene {} -o {} -q", binary("vxf"), quoted(dir.path("smoke.vdb")),
        quoted(dir.path("smoke.json")), quoted(dir.path("lit.vdb"))));
    INFO(lit.err);
    REQUIRE(lit.status == 0);
    CHECK(lit.err.empty());
    const vxf::VoxelSet set = vxf::readVoxelSet(dir.path("lit.vdb"));
    const openvdb::CoordBBox box = set.get<openvdb::Vec3SGrid>("direct")->evalActiveVoxelBoundingBox();
    CHECK(set.transform().indexToWorld(box.getCenter()).x() == Approx(2.0).margin(0.1)); // where the scene puts it
    CHECK(set.transform().voxelSize()[0] == Approx(1.0 / 16.0));

    // The scene's voxelize asks for half its voxels: lit on them, moved or not, as vxf run would.
    const std::string moved = R"("transform": {"translate": [2, 0, 0]},)";
    for (const std::string& transform : {moved, std::string()}) {
        std::string scene = vxf::test::slurp(dir.path("smoke.json"));
        scene.replace(scene.find(moved), moved.size(), transform);
        scene.insert(scene.rfind('}'), R"(, "voxelize": {"dim": 8})");
        vxf::test::spit(dir.path("half.json"), scene);
        const auto half = run(fmt::format("{} light {} --scene {} -o {} -q", binary("vxf"), quoted(dir.path("smoke.vdb")),
            quoted(dir.path("half.json")), quoted(dir.path("half.vdb"))));
        INFO(scene << half.err);
        REQUIRE(half.status == 0);
        CHECK(vxf::readVoxelSet(dir.path("half.vdb")).transform().voxelSize()[0] == Approx(1.0 / 8.0));
    }

    // A mesh medium voxelized on its own: lit where it lies, with a word about the transform.
    REQUIRE(run(fmt::format("{} voxelize builtin:sphere -o {} --dim 12 -q", binary("vxf"), quoted(dir.path("ball.vdb")))).status == 0);
    vxf::test::spit(dir.path("ball.json"), R"({
  "objects": [{"name": "ball", "mesh": "builtin:sphere", "transform": {"translate": [2, 0, 0]},
               "material": {"albedo": 0.9, "mean_free_path": 0.1}}],
  "lights": [{"type": "directional", "direction": [0, 0, -1]}],
  "camera": {"position": [2, -3, 0], "look_at": [2, 0, 0]}
})");
    const auto warned = run(fmt::format("{} light {} --scene {} -o {} -q", binary("vxf"), quoted(dir.path("ball.vdb")),
        quoted(dir.path("ball.json")), quoted(dir.path("ball-lit.vdb"))));
    CHECK(warned.status == 0);
    CHECK_THAT(warned.err, Catch::Contains("warning: object 'ball'") && Catch::Contains("has a transform"));
}

TEST_CASE("an output that cannot be written is refused before any work, and a converter never replaces its input", "[cli][output]")
{
    TempDir dir;
    const std::string vxf = binary("vxf");
    REQUIRE(run(fmt::format("{} voxelize builtin:sphere -o {} --dim 12 -q", vxf, quoted(dir.path("s.vdb")))).status == 0);
    const auto voxelize = run(fmt::format("{} voxelize builtin:sphere -o {} --dim 12 -q", vxf, quoted(dir.path("nodir/s.vdb"))));
    CHECK(voxelize.status == 2);
    CHECK_THAT(voxelize.err, Catch::Contains("folder '" + dir.path("nodir") + "' does not exist"));
    const auto folder = run(fmt::format("{} voxelize builtin:sphere -o {} --dim 12 -q", vxf, quoted(dir.root().string())));
    CHECK(folder.status == 2);
    CHECK_THAT(folder.err, Catch::Contains("is a folder, not a file to write"));
    // Both of render's outputs are checked first: the .exr is not written when the PNG cannot be.
    vxf::test::spit(dir.path("scene.json"), R"({"objects": [{"mesh": "builtin:sphere", "material": {"albedo": 0.5, "mean_free_path": 1}}],
      "lights": [{"type": "point", "position": [0, 0, 3]}], "camera": {"position": [0, -4, 0], "look_at": [0, 0, 0]}})");
    const auto render = run(fmt::format("{} render {} --scene {} -o {} --png {}", vxf, quoted(dir.path("s.vdb")),
        quoted(dir.path("scene.json")), quoted(dir.path("ok.exr")), quoted(dir.path("nodir/x.png"))));
    CHECK(render.status == 2);
    CHECK_FALSE(fs::exists(dir.path("ok.exr")));
    for (const auto& [tool, output] : {std::pair<std::string, std::string>{"vdb2vxf", "s.vdb"}, {"vdb2vol", "s.vdb"}}) {
        CAPTURE(tool);
        const std::string before = slurp(dir.path("s.vdb"));
        const auto over = run(fmt::format("{} {} {}", binary(tool), quoted(dir.path("s.vdb")), quoted(dir.path(output))));
        CHECK(over.status == 2);
        CHECK_THAT(over.err, Catch::Contains("is the input"));
        CHECK(slurp(dir.path("s.vdb")) == before);
    }
}

TEST_CASE("no command writes over one of its inputs or another of its outputs: refused before any work, every file kept", "[cli][output]")
{
    // Each command with each of its outputs set to each file it reads (the input, the scene, the
    // scene's mesh, by another spelling or through a link) and to another of its outputs.
    TempDir dir;
    const std::string vxf = binary("vxf");
    vxf::test::spit(dir.path("m.obj"), "v -1 -1 -1\nv 1 -1 -1\nv 0 1 -1\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n");
    vxf::test::spit(
        dir.path("s.json"), R"({"objects": [{"name": "tet", "mesh": "m.obj", "material": {"albedo": 0.8, "mean_free_path": 0.5}}],
      "lights": [{"type": "point", "position": [0, 0, 3]}], "camera": {"position": [0, -4, 0], "look_at": [0, 0, 0]},
      "voxelize": {"dim": 12}, "render": {"width": 8, "height": 6, "samples": 1}})");
    REQUIRE(run(fmt::format("{} voxelize {} -o {} --dim 12 -q", vxf, dir.path("m.obj"), dir.path("v.vdb"))).status == 0);
    REQUIRE(run(fmt::format("{} light {} --scene {} -o {} -q", vxf, dir.path("v.vdb"), dir.path("s.json"), dir.path("l.vdb"))).status == 0);
    fs::create_symlink(dir.path("m.obj"), dir.path("link.obj"));
    std::map<std::string, std::string> before;
    for (const char* f : {"m.obj", "s.json", "v.vdb", "l.vdb"}) before[f] = slurp(dir.path(f));
    const auto p = [&](const char* f) { return dir.path(f); };
    const std::vector<std::pair<std::string, std::string>> cases = {
        {fmt::format("voxelize {} -o {}", p("m.obj"), p("m.obj")), "is the mesh"},
        {fmt::format("voxelize {} -o {}/./m.obj", p("m.obj"), dir.root().string()), "is the mesh"},
        {fmt::format("voxelize {} -o {}", p("link.obj"), p("m.obj")), "is the mesh"},
        {fmt::format("light {} --scene {} -o {}", p("v.vdb"), p("s.json"), p("v.vdb")), "is the input"},
        {fmt::format("light {} --scene {} -o {}", p("v.vdb"), p("s.json"), p("s.json")), "is the scene"},
        {fmt::format("light {} --scene {} -o {}", p("v.vdb"), p("s.json"), p("m.obj")), "is object 'tet''s mesh"},
        {fmt::format("scatter {} --scene {} -o {}", p("l.vdb"), p("s.json"), p("s.json")), "is the scene"},
        {fmt::format("scatter {} -o {}", p("l.vdb"), p("l.vdb")), "is the input"},
        {fmt::format("render {} --volume {} -o {}", p("s.json"), p("l.vdb"), p("l.vdb")), "is --volume"},
        {fmt::format("render {} --volume {} -o {}", p("s.json"), p("l.vdb"), p("s.json")), "is the scene"},
        {fmt::format("render {} --volume {} -o {} --png {}", p("s.json"), p("l.vdb"), p("x.exr"), p("m.obj")), "is object 'tet''s mesh"},
        {fmt::format("render {} --volume {} -o {} --png {}", p("s.json"), p("l.vdb"), p("x.exr"), p("x.exr")), "is also -o"},
        {fmt::format("bake {} -o {}", p("s.json"), p("m.obj")), "is object 'tet''s mesh"},
        {fmt::format("op mul {} -o {} --grid direct --value 2 --record {}", p("l.vdb"), p("y.vdb"), p("l.vdb")), "is the input"},
        {fmt::format("op mul {} -o {} --grid direct --value 2 --record {}", p("l.vdb"), p("y.vdb"), p("y.vdb")), "is also -o"},
    };
    for (const auto& [args, message] : cases) {
        INFO(args);
        const auto refused = run(vxf + " " + args);
        INFO(refused.err);
        CHECK(refused.status == 2);
        CHECK_THAT(refused.err, Catch::Contains(message) && Catch::Contains(dir.root().string()));
        for (const auto& [file, bytes] : before) CHECK(slurp(dir.path(file)) == bytes);
        CHECK_FALSE(fs::exists(dir.path("x.exr")));
        CHECK_FALSE(fs::exists(dir.path("y.vdb")));
    }
    // An operator may still edit a file in place (read whole, then replaced atomically).
    CHECK(run(fmt::format("{} op mul {} -o {} --grid direct --value 2", vxf, p("l.vdb"), p("l.vdb"))).status == 0);
}

TEST_CASE("vxf run recomputes a cache entry it cannot read (truncated or damaged) with a warning", "[cli][run][cache]")
{
    TempDir dir;
    vxf::test::spit(dir.path("s.json"), R"({"objects": [{"mesh": "builtin:sphere", "material": {"albedo": 0.8, "mean_free_path": 0.3}}],
      "lights": [{"type": "point", "position": [0, 0, 3]}], "camera": {"position": [0, -4, 0], "look_at": [0, 0, 0]},
      "voxelize": {"dim": 16}, "scatter": {"kernel": "sweep", "directions": 8}, "render": {"width": 16, "height": 12, "samples": 1}})");
    const std::string command = fmt::format("{} run {} --out {}", binary("vxf"), quoted(dir.path("s.json")), quoted(dir.path("out")));
    REQUIRE(run(command).status == 0);
    const std::string image = slurp(dir.path("out/s.exr"));
    const std::string light = cachedStage(dir.path("out/cache"), "light-");
    REQUIRE_FALSE(light.empty());
    // A machine killed before the file system wrote it all: half the file.
    const std::string whole = slurp(light);
    vxf::test::spit(light, whole.substr(0, whole.size() / 2));
    fs::remove(cachedStage(dir.path("out/cache"), "scatter-")); // so that the light entry is read
    const auto rerun = run(command);
    INFO(rerun.out << rerun.err);
    CHECK(rerun.status == 0);
    CHECK_THAT(rerun.err,
        Catch::Contains("warning: cache entry " + light + " could not be read") && Catch::Contains("removed, and its stage recomputed"));
    CHECK(rerun.out.find("light     ran") != std::string::npos);
    CHECK(slurp(dir.path("out/s.exr")) == image); // the same image as before the damage
    const auto third = run(command);
    CHECK(third.err.empty());
    CHECK(third.out.find("scatter   reused") != std::string::npos);
}

TEST_CASE("two runs on one cache compute each stage once: the second waits for the first's entries", "[cli][run][cache]")
{
    TempDir dir;
    vxf::test::spit(dir.path("s.json"), R"({"objects": [{"mesh": "builtin:sphere", "material": {"albedo": 0.99, "mean_free_path": 0.02}}],
      "lights": [{"type": "point", "position": [0, 0, 3]}], "camera": {"position": [0, -4, 0], "look_at": [0, 0, 0]},
      "voxelize": {"dim": 40}, "scatter": {"kernel": "gather", "directions": 32}, "render": {"width": 16, "height": 12, "samples": 1}})");
    const std::string command = fmt::format("{} run {} --out {}", binary("vxf"), quoted(dir.path("s.json")), quoted(dir.path("out")));
    const auto both =
        run(fmt::format("({} > {} 2>&1 & {} > {} 2>&1 & wait)", command, quoted(dir.path("a.txt")), command, quoted(dir.path("b.txt"))));
    REQUIRE(both.status == 0);
    const std::string a = slurp(dir.path("a.txt")), b = slurp(dir.path("b.txt"));
    INFO(a << "\n" << b);
    for (const char* stage : {"voxelize  ran", "light     ran", "scatter   ran"}) {
        const auto count = [&](const std::string& text) { return text.find(stage) != std::string::npos ? 1 : 0; };
        CHECK(count(a) + count(b) == 1);
    }
    CHECK(a.find("wrote ") != std::string::npos);
    CHECK(b.find("wrote ") != std::string::npos);
}

TEST_CASE("a FIFO, a device, a folder or a symbolic link loop is refused by name, never read", "[cli][input]")
{
    TempDir dir;
    const std::string vxf = binary("vxf");
    REQUIRE(run("mkfifo " + quoted(dir.path("fifo.json")) + " " + quoted(dir.path("fifo.off"))).status == 0);
    REQUIRE(run("ln -s loop1 " + quoted(dir.path("loop2")) + " && ln -s loop2 " + quoted(dir.path("loop1"))).status == 0);
    const auto refused = [&](const std::string& command, const std::string& why) {
        // `timeout`: a reader that opened the FIFO would wait for a writer forever.
        const auto r = run("timeout 20 " + command);
        INFO(command << "\n" << r.err);
        CHECK((r.status == 1 || r.status == 2));
        CHECK_THAT(r.err, Catch::Contains(why));
    };
    refused(fmt::format("{} run {}", vxf, quoted(dir.path("fifo.json"))), "is not a regular file");
    refused(fmt::format("{} run {}", vxf, quoted(dir.root().string())), "is a folder, not a file");
    refused(fmt::format("{} run {}", vxf, quoted(dir.path("loop1"))), "a loop of symbolic links");
    refused(fmt::format("{} run /dev/zero", vxf), "is not a regular file");
    refused(
        fmt::format("{} voxelize {} -o {} --dim 8", vxf, quoted(dir.path("fifo.off")), quoted(dir.path("x.vdb"))), "is not a regular file");
    refused(fmt::format("{} graph /dev/zero", vxf), "is not a regular file");
    refused(fmt::format("{} {} {}", binary("vxf2vdb"), "/dev/zero", quoted(dir.path("x.vdb"))), "is not a regular file");
    refused(fmt::format("{} info {}", vxf, quoted(dir.path("fifo.off"))), "is not a regular file");
}

TEST_CASE("two scenes of one file name in one --out: the second is refused before any work, no image lost", "[cli][run][output]")
{
    TempDir dir;
    fs::create_directories(dir.path("a"));
    fs::create_directories(dir.path("b"));
    const std::string scene = R"({"objects": [{"mesh": "builtin:sphere", "material": {"albedo": 0.5, "mean_free_path": 1}}],
      "lights": [{"type": "point", "position": [0, 0, 3]}], "camera": {"position": [0, -4, 0], "look_at": [0, 0, 0]},
      "voxelize": {"dim": 12}, "render": {"width": 8, "height": 6, "samples": 1}})";
    vxf::test::spit(dir.path("a/s.json"), scene);
    vxf::test::spit(dir.path("b/s.json"), scene);
    const auto runScene = [&](const std::string& which) {
        return run(fmt::format("{} run {} --out {}", binary("vxf"), quoted(dir.path(which + "/s.json")), quoted(dir.path("out"))));
    };
    REQUIRE(runScene("a").status == 0);
    const std::string image = slurp(dir.path("out/s.exr"));
    CHECK(runScene("a").status == 0); // the same scene again: its own name
    const auto other = runScene("b");
    CHECK(other.status == 2);
    CHECK_THAT(other.err, Catch::Contains("is rendered there from " + fs::weakly_canonical(dir.path("a/s.json")).string()));
    CHECK(other.out.find("ran") == std::string::npos); // nothing computed
    CHECK(slurp(dir.path("out/s.exr")) == image);

    // A run that fails claims nothing: the next scene of that name renders there.
    fs::create_directories(dir.path("c"));
    fs::create_directories(dir.path("d"));
    vxf::test::spit(dir.path("c/broken.obj"), "v 0 0 0\nf 1 2 3 x\n");
    vxf::test::spit(dir.path("c/t.json"), R"({"objects": [{"mesh": "broken.obj", "material": {"albedo": 0.5, "mean_free_path": 1}}],
      "lights": [{"type": "point", "position": [0, 0, 3]}], "camera": {"position": [0, -4, 0], "look_at": [0, 0, 0]}})");
    const auto failed = run(fmt::format("{} run {} --out {}", binary("vxf"), quoted(dir.path("c/t.json")), quoted(dir.path("out"))));
    INFO(failed.err);
    CHECK(failed.status == 1);
    CHECK_FALSE(fs::exists(dir.path("out/.t.scene")));
    vxf::test::spit(dir.path("d/t.json"), scene);
    CHECK(run(fmt::format("{} run {} --out {}", binary("vxf"), quoted(dir.path("d/t.json")), quoted(dir.path("out")))).status == 0);
    // A graph to record into, in a folder that does not exist: refused before the operator runs.
    const auto record = run(fmt::format("{} op mul {} -o {} --grid density --value 2 --record {}", binary("vxf"),
        quoted(dir.path("out/cache") + "/" + fs::path(cachedStage(dir.path("out/cache"), "voxelize-")).filename().string()),
        quoted(dir.path("x.vdb")), quoted(dir.path("nodir/p.json"))));
    CHECK(record.status == 2);
    CHECK_THAT(record.err, Catch::Contains("nodir") && Catch::Contains("does not exist"));
    CHECK_FALSE(fs::exists(dir.path("x.vdb")));
}

TEST_CASE("every crafted .vdb that overflowed OpenVDB 10.0.1's reader is a clear error through every command that reads a .vdb",
    "[cli][input][vdb]")
{
    // Inputs found by fuzzing (tests/regress/fuzz/vdb_info): under OpenVDB's own chunk reader
    // each aborted `vxf info` and the converters ("free(): invalid pointer") and crashed `vxf run`
    // and `vxf op copy --from_file` (SIGSEGV).
    TempDir dir;
    const std::string vxf = binary("vxf");
    REQUIRE(run(vxf + " voxelize builtin:sphere -o " + quoted(dir.path("s.vdb")) + " --dim 12 -q").status == 0);
    for (const char* name : {"blosc_raw_chunk_longer_than_node", "blosc_raw_chunk_longer_than_node_2"}) {
        const std::string crafted = dir.path(std::string(name) + ".vdb");
        fs::copy_file(source("tests/regress/fuzz/vdb_info/") + name, crafted);
        // The scene's object names the crafted grid: a volume object's file is read for that grid alone.
        vxf::test::spit(dir.path("scene.json"),
            fmt::format(R"({{
  "objects": [{{"name": "smoke", "volume": {}, "grid": "color", "material": {{"albedo": 0.9, "mean_free_path": 0.5}}}}],
  "lights": [{{"type": "directional", "direction": [0, 0, -1], "intensity": 3}}],
  "camera": {{"position": [0, -4, 0], "look_at": [0, 0, 0], "fov": 40}},
  "render": {{"width": 8, "height": 6, "samples": 1}}
}})",
                nlohmann::json(crafted).dump()));
        const std::vector<std::string> commands{
            fmt::format("{} info {}", vxf, quoted(crafted)),
            fmt::format("{} info --json {}", vxf, quoted(crafted)),
            fmt::format("{} {} {}", binary("vdb2vxf"), quoted(crafted), quoted(dir.path("out.vxf"))),
            fmt::format("{} {} {} --grid density", binary("vdb2vol"), quoted(crafted), quoted(dir.path("out.vol"))),
            fmt::format("{} op copy {} -o {} --grid density --from_file {} --to other", vxf, quoted(dir.path("s.vdb")),
                quoted(dir.path("out.vdb")), quoted(crafted)),
            fmt::format("{} light {} --scene {} -o {}", vxf, quoted(crafted), quoted(dir.path("scene.json")), quoted(dir.path("out.vdb"))),
            fmt::format("{} run {} --out {}", vxf, quoted(dir.path("scene.json")), quoted(dir.path("runs"))),
            fmt::format("{} view {} --no-browser --port 0", vxf, quoted(crafted)),
        };
        for (const auto& command : commands) {
            const auto r = run("timeout 60 " + command);
            INFO(command << "\n" << r.out << r.err);
            CHECK(r.status == 1);
            CHECK_THAT(r.err, Catch::Contains(crafted) && Catch::Contains("not a readable OpenVDB file"));
        }
        CHECK_FALSE(fs::exists(dir.path("out.vdb")));
        CHECK_FALSE(fs::exists(dir.path("out.vxf")));
        CHECK_FALSE(fs::exists(dir.path("out.vol")));
    }
}

TEST_CASE(
    "every command that allocates estimates its peak first: above --max-memory, a ulimit or the machine it stops at once with the estimate",
    "[cli][memory]")
{
    TempDir dir;
    const std::string vxf = binary("vxf");
    const auto tiny = run(fmt::format("{} voxelize builtin:sphere --dim 64 -o {} --max-memory 1M", vxf, quoted(dir.path("s.vdb"))));
    CHECK(tiny.status == 1);
    CHECK_THAT(tiny.err,
        Catch::Contains("voxelize needs about") && Catch::Contains("narrow-band voxels × 56 bytes") &&
            Catch::Contains("more than the memory budget of 1.0 MiB (--max-memory)"));
    CHECK_FALSE(fs::exists(dir.path("s.vdb")));
    CHECK(run(fmt::format("{} voxelize builtin:sphere --dim 64 -o {} --max-memory 8X", vxf, quoted(dir.path("s.vdb")))).status == 2);

    // An image of 32768² pixels: refused before a pixel is allocated (about 60 MB resident, against 160 GiB).
    REQUIRE(run(fmt::format("{} voxelize builtin:sphere --dim 24 -q -o {}", vxf, quoted(dir.path("s.vdb")))).status == 0);
    vxf::test::spit(
        dir.path("s.json"), R"({"objects": [{"name": "ball", "mesh": "builtin:sphere", "material": {"albedo": 0.9, "mean_free_path": 0.5}}],
 "lights": [{"type": "point", "position": [0, -3, 2], "intensity": 10}],
 "camera": {"position": [0, -4, 0], "look_at": [0, 0, 0], "fov": 40},
 "render": {"width": 32, "height": 24, "samples": 1}})");
    const auto huge = run(fmt::format("/usr/bin/time -f 'peak %M KB' {} render {} --volume {} -o {} --width 32768 --height 32768", vxf,
        quoted(dir.path("s.json")), quoted(dir.path("s.vdb")), quoted(dir.path("big.exr"))));
    CHECK(huge.status == 1);
    CHECK_THAT(huge.err, Catch::Contains("render needs about") && Catch::Contains("1.07e+09 pixels × 160 bytes"));
    const auto peak = huge.err.rfind("peak ");
    REQUIRE(peak != std::string::npos);
    CHECK(std::stol(huge.err.substr(peak + 5)) < 400 * 1024);
    CHECK_FALSE(fs::exists(dir.path("big.exr")));

    // Refused from the file's own count (`file_voxel_count`), before its data are read: with the
    // density's data damaged (the file's last bytes), light, scatter and render name their
    // estimate under a small budget, and the file's damage only without one.
    {
        const vxf::VoxelSet read = vxf::readVoxelSet(dir.path("s.vdb"));
        vxf::VoxelSet densityLast(read.transformPtr());
        for (const auto& grid : read.grids()) {
            if (grid->getName() != "density") densityLast.putAsIs(grid);
        }
        densityLast.putAsIs(read.find("density"));
        vxf::writeVoxelSet(dir.path("d.vdb"), densityLast, vxf::VoxelSetWriteOptions{false, false});
        std::string bytes = slurp(dir.path("d.vdb"));
        REQUIRE(bytes.size() > 4096);
        for (std::size_t i = bytes.size() - 1024; i < bytes.size() - 16; ++i) bytes[i] = char(0x5a);
        vxf::test::spit(dir.path("d.vdb"), bytes);
        const std::string d = quoted(dir.path("d.vdb")), scene = quoted(dir.path("s.json"));
        for (const auto& [stage, command] : std::vector<std::pair<std::string, std::string>>{
                 {"light", fmt::format("{} light {} --scene {} -o {}", vxf, d, scene, quoted(dir.path("l.vdb")))},
                 {"scatter", fmt::format("{} scatter {} -o {}", vxf, d, quoted(dir.path("x.vdb")))},
                 {"render", fmt::format("{} render {} --volume {} -o {}", vxf, scene, d, quoted(dir.path("r.exr")))}}) {
            const auto refused = run(command + " --max-memory 50M");
            INFO(command << "\n" << refused.err);
            CHECK(refused.status == 1);
            CHECK_THAT(refused.err, Catch::Contains(stage + " needs about") && Catch::Contains("(--max-memory)"));
            const auto damaged = run(command);
            INFO(damaged.err);
            CHECK(damaged.status == 1);
            CHECK_THAT(damaged.err, Catch::Contains(dir.path("d.vdb") + ": ") && !Catch::Contains("needs about")); // the damage
        }
        CHECK_FALSE(fs::exists(dir.path("l.vdb")));
        CHECK_FALSE(fs::exists(dir.path("x.vdb")));
        CHECK_FALSE(fs::exists(dir.path("r.exr")));
    }

    // Under an address-space limit the default budget is what the limit leaves: a clear error,
    // not an allocation failing inside OpenVDB (which ended in std::terminate, SIGABRT).
    const auto limited =
        run(fmt::format("bash -c 'ulimit -v 2000000 && exec {} voxelize builtin:sphere --dim 4096 -o {}'", vxf, dir.path("big.vdb")));
    CHECK(limited.status == 1);
    CHECK_THAT(limited.err, Catch::Contains("voxelize needs about") && Catch::Contains("the memory this machine has available"));
    // Past the estimate (a budget raised above the limit): the allocation that fails inside
    // OpenVDB's meshToVolume is a clear error, not std::terminate from its unwinding (SIGABRT).
    const auto beyond = run(fmt::format(
        "bash -c 'ulimit -v 1500000 && exec {} voxelize builtin:sphere --dim 4096 -o {} --max-memory 100G'", vxf, dir.path("big.vdb")));
    CHECK(beyond.status == 1);
    CHECK_THAT(beyond.err, Catch::Contains("out of memory"));
    CHECK_FALSE(fs::exists(dir.path("big.vdb")));
    // And through a whole run: the stage that would pass the budget names itself.
    const auto whole = run(fmt::format("{} run {} --out {} --max-memory 101M", vxf, quoted(dir.path("s.json")), quoted(dir.path("out"))));
    CHECK(whole.status == 1);
    CHECK_THAT(whole.err, Catch::Contains("needs about") && Catch::Contains("(--max-memory)"));
    CHECK_FALSE(fs::exists(dir.path("out/s.exr")));
}

TEST_CASE("no stage output goes negative on its own: the candle through both kernels and both render modes", "[cli][run][numbers]")
{
    // Issue 59 saw scatter.B down to -0.00092 on the demo candle with no edit; every grid and
    // every image layer (but normals) of the unedited pipeline must stay at or above zero.
    TempDir dir;
    std::string scene = slurp(source("examples/candle.json"));
    const auto replace = [&](const std::string& from, const std::string& to) {
        const auto at = scene.find(from);
        REQUIRE(at != std::string::npos);
        scene.replace(at, from.size(), to);
    };
    replace(R"("width": 640, "height": 360, "samples": 4)", R"("width": 160, "height": 90, "samples": 2)");
    for (const char* kernel : {"sweep", "gather"}) {
        for (const char* mode : {"view", "gather"}) {
            CAPTURE(kernel, mode);
            std::string variant = scene;
            variant.replace(
                variant.find(R"("kernel": "sweep")"), std::strlen(R"("kernel": "sweep")"), fmt::format(R"("kernel": "{}")", kernel));
            variant.replace(variant.find(R"("mode": "view")"), std::strlen(R"("mode": "view")"), fmt::format(R"("mode": "{}")", mode));
            vxf::test::spit(dir.path("candle.json"), variant);
            const auto r = run(fmt::format("{} run {} --out {}", binary("vxf"), quoted(dir.path("candle.json")), quoted(dir.path("out"))));
            INFO(r.out << r.err);
            REQUIRE(r.status == 0);
            const vxf::VoxelSet set = vxf::readVoxelSet(cachedStage(dir.path("out/cache"), "scatter-"));
            for (const char* name : {"direct", "scatter_source", "scatter", "illumination"}) {
                const auto grid = set.get<openvdb::Vec3SGrid>(name);
                REQUIRE(grid);
                float lowest = 0.0f;
                for (auto it = grid->cbeginValueOn(); it; ++it) lowest = std::min({lowest, (*it)[0], (*it)[1], (*it)[2]});
                CAPTURE(name);
                CHECK(lowest >= 0.0f);
            }
            Imf::InputFile exr(dir.path("out/candle.exr").c_str());
            const Imath::Box2i window = exr.header().dataWindow();
            const int width = window.max.x - window.min.x + 1, height = window.max.y - window.min.y + 1;
            for (auto c = exr.header().channels().begin(); c != exr.header().channels().end(); ++c) {
                const std::string channel = c.name();
                if (channel.rfind("normal.", 0) == 0) continue;
                std::vector<float> values(std::size_t(width) * std::size_t(height));
                Imf::FrameBuffer frame;
                frame.insert(channel, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(values.data()), sizeof(float), sizeof(float) * width));
                exr.setFrameBuffer(frame);
                exr.readPixels(window.min.y, window.max.y);
                CAPTURE(channel);
                CHECK(*std::min_element(values.begin(), values.end()) >= 0.0f);
            }
        }
    }
}

TEST_CASE("a density with no positive value is lit with a warning, never silently black", "[cli][light][numbers]")
{
    TempDir dir;
    const std::string vxf = binary("vxf");
    REQUIRE(run(fmt::format("{} voxelize builtin:sphere --dim 16 -q -o {}", vxf, quoted(dir.path("s.vdb")))).status == 0);
    REQUIRE(
        run(fmt::format("{} op mul {} -o {} --grid density --value 0", vxf, quoted(dir.path("s.vdb")), quoted(dir.path("z.vdb")))).status ==
        0);
    vxf::test::spit(
        dir.path("s.json"), R"({"objects": [{"name": "ball", "mesh": "builtin:sphere", "material": {"albedo": 0.9, "mean_free_path": 0.5}}],
 "lights": [{"type": "point", "position": [0, -3, 2], "intensity": 10}],
 "camera": {"position": [0, -4, 0], "look_at": [0, 0, 0], "fov": 40}})");
    const auto empty = run(
        fmt::format("{} light {} --scene {} -o {}", vxf, quoted(dir.path("z.vdb")), quoted(dir.path("s.json")), quoted(dir.path("l.vdb"))));
    CHECK(empty.status == 0);
    CHECK_THAT(
        empty.err, Catch::Contains("warning: the medium's density ('density', ") && Catch::Contains("has no positive value (largest 0)"));
    const auto lit = run(
        fmt::format("{} light {} --scene {} -o {}", vxf, quoted(dir.path("s.vdb")), quoted(dir.path("s.json")), quoted(dir.path("l.vdb"))));
    CHECK(lit.status == 0);
    CHECK(lit.err.find("no positive value") == std::string::npos);
}
