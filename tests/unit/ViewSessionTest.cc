#include <vxf/view/ViewSession.h>

#include "TestSupport.h"

#include <vxf/io/ImageFile.h>
#include <vxf/io/VoxelSetFile.h>
#include <vxf/ops/Edit.h>
#include <vxf/ops/Select.h>
#include <vxf/pipeline/Graph.h>

#include <openvdb/tools/Composite.h>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <cmath>

using namespace vxf;

namespace {

/// A sphere of 16 cells per unit (about 17k voxels) with `density` and a `direct` colour that
/// varies along x, written to @a path.
void writeSphere(const std::string& path)
{
    VoxelSet set = test::uniformSphere(test::albedoMaterial(4.0, 0.9), 1.0);
    auto direct = set.get<openvdb::Vec3SGrid>("direct");
    for (auto it = direct->beginValueOn(); it; ++it) {
        const double x = direct->transform().indexToWorld(it.getCoord()).x();
        it.setValue(openvdb::Vec3f(float(1.0 + x), 0.5f, float(1.0 - x)));
    }
    writeVoxelSet(path, set);
}

/// The session's current set (a whole export) as a set.
VoxelSet currentOf(view::ViewSession& session, const std::string& name)
{
    return readVoxelSet(session.exportTo(name, view::ExportMode::Whole, "", 0));
}

/// Whether every grid of @a a is in @a b, bit for bit, and the other way round.
bool sameSets(const VoxelSet& a, const VoxelSet& b, std::string* why)
{
    if (a.grids().size() != b.grids().size()) {
        *why = fmt::format("{} grids against {}", a.grids().size(), b.grids().size());
        return false;
    }
    for (const auto& g : a.grids()) {
        const auto other = b.find(g->getName());
        if (!other) {
            *why = fmt::format("no grid '{}'", g->getName());
            return false;
        }
        if (!test::identicalGrids(*g, *other, why)) {
            *why = g->getName() + ": " + *why;
            return false;
        }
    }
    return true;
}

} // namespace

TEST_CASE("view: points per voxel within the budget, cells of 2, 3, 4, 6… voxels beyond it", "[view]")
{
    test::TempDir dir;
    writeSphere(dir.path("s.vdb"));
    const view::ViewSession session(dir.path("s.vdb"));
    const auto density = readVoxelSet(dir.path("s.vdb")).get<openvdb::FloatGrid>("density");
    const auto active = density->activeVoxelCount();

    const view::PointCloud all = session.points("density", active);
    CHECK(all.cellVoxels == 1);
    CHECK(all.positions.size() == 3 * active);
    CHECK(all.activeVoxels == active);
    CHECK(all.minValue == 1.0); // every voxel of the sphere holds density 1
    CHECK(all.maxValue == 1.0);

    const view::PointCloud coarse = session.points("density", 1000);
    CHECK(coarse.cellVoxels >= 2);
    CHECK(coarse.values.size() <= 1000);
    CHECK(coarse.values.size() > 1000 / 4); // the next size up holds at most 3.4 times fewer
    CHECK(coarse.cellSize == Approx(density->voxelSize()[0] * coarse.cellVoxels));
    CHECK(coarse.minValue == 1.0); // means of ones

    // A Vec3 grid's cells hold the mean colour of their voxels: the whole sphere in one cell
    // holds its mean (symmetric in x: red and blue average to 1).
    const view::PointCloud one = session.points("direct", 1);
    REQUIRE(one.values.size() == 3);
    CHECK(one.channels == 3);
    CHECK(one.values[0] == Approx(1.0).margin(1e-5));
    CHECK(one.values[1] == Approx(0.5));
    CHECK(one.values[2] == Approx(1.0).margin(1e-5));
    CHECK(std::abs(one.positions[0]) < 1e-5); // at the centre

    CHECK_THROWS_WITH(session.points("nope", 10), Catch::Contains("no grid 'nope'") && Catch::Contains("density"));
    CHECK(session.describe()["default_grid"] == "direct"); // the light's result before the density
}

TEST_CASE("view: a volume brick holds each cell's mean and coverage, the smallest cells within the budget", "[view]")
{
    test::TempDir dir;
    writeSphere(dir.path("s.vdb"));
    const view::ViewSession session(dir.path("s.vdb"));
    const auto density = readVoxelSet(dir.path("s.vdb")).get<openvdb::FloatGrid>("density");
    const openvdb::CoordBBox bounds = density->evalActiveVoxelBoundingBox();
    // A cell a voxel where the budget holds the whole box: each active voxel's value, coverage 1.
    const view::VolumeBrick fine = session.brick("density", std::size_t(bounds.volume()));
    CHECK(fine.cellVoxels == 1);
    CHECK(fine.dims[0] == bounds.dim().x());
    CHECK(fine.channels == 1);
    double covered = 0.0;
    for (std::size_t i = 0; i < fine.values.size(); i += 2) {
        REQUIRE((fine.values[i + 1] == 0.0f || fine.values[i + 1] == 1.0f));
        if (fine.values[i + 1] > 0.0f) REQUIRE(fine.values[i] == 1.0f);
        covered += fine.values[i + 1];
    }
    CHECK(covered == double(density->activeVoxelCount()));
    // Coarser within a budget: cells of k voxels, their coverage summing to the active voxels.
    const view::VolumeBrick coarse = session.brick("density", 2000);
    CHECK(coarse.cellVoxels > 1);
    CHECK(std::size_t(coarse.dims[0]) * coarse.dims[1] * coarse.dims[2] <= 2000);
    double voxels = 0.0;
    for (std::size_t i = 0; i < coarse.values.size(); i += 2) voxels += coarse.values[i + 1] * std::pow(coarse.cellVoxels, 3);
    CHECK(voxels == Approx(double(density->activeVoxelCount())).epsilon(1e-6));
    // The brick's world box: the cells' outer faces, the bounds' first voxel's low face at its corner.
    const openvdb::Vec3d corner = density->transform().indexToWorld(bounds.min().asVec3d() - openvdb::Vec3d(0.5));
    CHECK((coarse.worldMin - corner).length() < 1e-9);
    // A colour grid: three means a cell, then the coverage.
    const view::VolumeBrick colour = session.brick("direct", 5000);
    CHECK(colour.channels == 3);
    CHECK(colour.values.size() == std::size_t(colour.dims[0]) * colour.dims[1] * colour.dims[2] * 4);
    CHECK_THROWS_WITH(session.brick("nope", 10), Catch::Contains("no grid 'nope'"));
}

TEST_CASE("view: a slice holds the active voxels' values and NaN elsewhere", "[view]")
{
    test::TempDir dir;
    writeSphere(dir.path("s.vdb"));
    const view::ViewSession session(dir.path("s.vdb"));
    const auto direct = readVoxelSet(dir.path("s.vdb")).get<openvdb::Vec3SGrid>("direct");
    const view::Slice s = session.slice("direct", 2, 0);
    REQUIRE(s.channels == 3);
    REQUIRE(s.width > 0);
    int active = 0, checked = 0;
    for (int j = 0; j < s.height; ++j) {
        for (int i = 0; i < s.width; ++i) {
            const openvdb::Coord ijk = s.origin.offsetBy(i, j, 0);
            const float* v = &s.values[(std::size_t(j) * std::size_t(s.width) + std::size_t(i)) * 3];
            openvdb::Vec3f expected;
            if (direct->tree().probeValue(ijk, expected)) {
                ++active;
                checked += v[0] == expected[0] && v[1] == expected[1] && v[2] == expected[2];
            } else {
                CHECK(std::isnan(v[0]));
            }
        }
    }
    CHECK(active > 100);
    CHECK(checked == active);
    CHECK(session.slice("direct", 2, 100000).index == direct->evalActiveVoxelBoundingBox().max().z()); // clamped
    CHECK_THROWS_WITH(session.slice("direct", 3, 0), Catch::Contains("axis 3"));
}

TEST_CASE("view: edits are the registry's operators, undoable, and the pipeline replays them to the same bits", "[view]")
{
    test::TempDir dir;
    writeSphere(dir.path("s.vdb"));
    view::ViewSession session(dir.path("s.vdb"));
    const nlohmann::json select = {{"grid", "direct"}, {"shape", "box"}, {"min", {-1, -1, -1}}, {"max", {0, 1, 1}}};
    const std::string selected = session.apply("select", select);
    CHECK_THAT(selected, Catch::Contains("into 'mask'"));
    const std::string edited = session.apply("edit", {{"grid", "direct"}, {"selection", "mask"}, {"hue_shift", 120.0}});

    // What the operators give when called directly.
    VoxelSet expected = readVoxelSet(dir.path("s.vdb"));
    auto direct = expected.get<openvdb::Vec3SGrid>("direct");
    const auto mask = ops::selectBox(*direct, openvdb::BBoxd(openvdb::Vec3d(-1.0), openvdb::Vec3d(0.0, 1.0, 1.0)));
    ops::EditOptions hue;
    hue.hueShift = 120.0;
    // The reports count the voxels each step changed: the new mask's, then the hue-shifted ones (all of the mask's
    // voxels whose colour is not grey: a hue shift leaves grey as it is).
    const openvdb::Vec3SGrid::Ptr original = direct->deepCopy();
    ops::edit(*direct, mask.get(), hue);
    CHECK_THAT(selected, Catch::Contains(fmt::format("; changed {} voxels of 'mask'", mask->activeVoxelCount())));
    std::uint64_t shifted = 0;
    for (auto it = direct->cbeginValueOn(); it; ++it) shifted += *it != original->tree().getValue(it.getCoord()) ? 1 : 0;
    CHECK(shifted > 0);
    CHECK_THAT(edited, Catch::Contains(fmt::format("; changed {} voxels of 'direct'", shifted)));

    std::filesystem::create_directory(dir.path("out")); // exports create no folders
    const std::string whole = session.exportTo("out/whole.vdb", view::ExportMode::Whole, "", 0);
    const VoxelSet written = readVoxelSet(whole);
    std::string why;
    CHECK(test::identicalGrids(*written.find("direct"), *direct, &why));
    INFO(why);

    // The pipeline written beside it makes the same set (vxf graph).
    nlohmann::json graph = session.pipeline(dir.path("replayed.vdb"));
    test::spit(dir.path("p.json"), graph.dump());
    runGraph(dir.path("p.json"), dir.path("cache"));
    CHECK(test::identicalGrids(*readVoxelSet(dir.path("replayed.vdb")).find("direct"), *written.find("direct"), &why));
    CHECK(std::filesystem::exists(dir.path("out/whole.pipeline.json")));

    // The difference, as `vxf op diff` makes it, and the smoothed replay keeps the edit itself.
    const VoxelSet diff = readVoxelSet(session.exportTo("out/diff.vdb", view::ExportMode::Diff, "direct", 0));
    REQUIRE(diff.grids().size() == 1);
    CHECK(diff.grids().front()->getName() == "direct_diff");
    CHECK(diff.grids().front()->activeVoxelCount() == mask->activeVoxelCount());
    const VoxelSet smoothed = readVoxelSet(session.exportTo("out/smooth.vdb", view::ExportMode::Smoothed, "direct", 2));
    const auto s = smoothed.get<openvdb::Vec3SGrid>("direct");
    for (auto it = mask->cbeginValueOn(); it; ++it) REQUIRE(s->tree().getValue(it.getCoord()) == direct->tree().getValue(it.getCoord()));
    CHECK(!smoothed.find("mask")); // the original set's grids, the edit re-applied

    // Removing and adding voxels: every voxel of `direct` removed, then the density's voxels
    // added back with a colour, selected among the density's (the page's "among").
    session.apply("select", {{"grid", "direct"}, {"shape", "box"}, {"min", {-2, -2, -2}}, {"max", {2, 2, 2}}, {"out", "all"}});
    session.apply("edit", {{"grid", "direct"}, {"selection", "all"}, {"remove", true}});
    session.apply("select", {{"grid", "density"}, {"shape", "box"}, {"min", {-2, -2, -2}}, {"max", {2, 2, 2}}, {"out", "wider"}});
    session.apply("edit", {{"grid", "direct"}, {"selection", "wider"}, {"add", true}, {"set", {1, 1, 1}}});
    const auto added = readVoxelSet(session.exportTo("out/added.vdb", view::ExportMode::Whole, "", 0)).get<openvdb::Vec3SGrid>("direct");
    CHECK(added->activeVoxelCount() == readVoxelSet(dir.path("s.vdb")).find("density")->activeVoxelCount());
    for (auto it = added->cbeginValueOn(); it; ++it) REQUIRE(*it == openvdb::Vec3f(1.0f));
    for (int i = 0; i < 4; ++i) CHECK(session.undo());

    // Undo: back to the file as read, bit for bit.
    CHECK(session.undo());
    CHECK(session.undo());
    CHECK_FALSE(session.undo());
    session.exportTo("out/undone.vdb", view::ExportMode::Whole, "", 0);
    CHECK(test::identicalGrids(
        *readVoxelSet(dir.path("out/undone.vdb")).find("direct"), *readVoxelSet(dir.path("s.vdb")).find("direct"), &why));
}

TEST_CASE("view: bad edits and exports are refused with a message and change nothing", "[view]")
{
    test::TempDir dir;
    writeSphere(dir.path("s.vdb"));
    view::ViewSession session(dir.path("s.vdb"));
    CHECK_THROWS_WITH(session.apply("scatter", nlohmann::json::object()), Catch::Contains("not 'scatter'"));
    CHECK_THROWS_WITH(session.apply("edit", {{"grid", "direct"}, {"hue_shift", 999}}), Catch::Contains("hue_shift"));
    CHECK_THROWS_WITH(
        session.apply("copy", {{"grid", "direct"}, {"from_file", "/etc/passwd"}, {"out", "x"}}), Catch::Contains("from_file"));
    CHECK_THROWS_WITH(session.apply("edit", {{"grid", "density"}, {"hue_shift", 30}}), Catch::Contains("'density' holds numbers"));
    CHECK_THROWS_WITH(session.apply("edit", {{"grid", "density"}, {"set", {1, 0, 0}}}), Catch::Contains("one number"));
    CHECK(session.describe()["steps"].empty());
    CHECK_THROWS_WITH(session.exportTo("../x.vdb", view::ExportMode::Whole, "", 0), Catch::Contains("'..'"));
    CHECK_THROWS_WITH(session.exportTo("/tmp/x.vdb", view::ExportMode::Whole, "", 0), Catch::Contains("relative"));
    CHECK_THROWS_WITH(session.exportTo("x.txt", view::ExportMode::Whole, "", 0), Catch::Contains(".vdb"));
    CHECK_THROWS_WITH(session.exportTo("s.vdb", view::ExportMode::Whole, "", 0), Catch::Contains("served file itself"));
    CHECK_THROWS_WITH(session.exportTo("d.vdb", view::ExportMode::Diff, "nope", 0), Catch::Contains("no grid 'nope'"));
    CHECK_FALSE(std::filesystem::exists(dir.path("x.vdb")));
    CHECK_FALSE(std::filesystem::exists(dir.path("d.vdb")));
    CHECK_THROWS_WITH(view::ViewSession(dir.path("missing.vdb")), Catch::Contains("missing.vdb"));
}

TEST_CASE("view: a render re-runs the scatter stage only after an edit of what it reads", "[view]")
{
    test::TempDir dir;
    test::spit(dir.path("s.json"), R"({
  "objects": [{"mesh": "builtin:sphere", "material": {"albedo": 0.8, "mean_free_path": 0.3}}],
  "lights": [{"type": "point", "position": [0, 0, 2], "intensity": 3}],
  "camera": {"position": [0, -4, 0], "look_at": [0, 0, 0]}
})");
    test::spit(dir.path("p.json"), R"({
  "nodes": {
    "vox": {"op": "voxelize", "params": {"mesh": "builtin:sphere", "dim": 16}},
    "lit": {"op": "light", "input": "vox", "params": {"scene": "s.json"}},
    "sc": {"op": "scatter", "input": "lit", "params": {"kernel": "sweep", "directions": 8}}
  },
  "outputs": {"sc": "sc.vdb"}
})");
    runGraph(dir.path("p.json"), dir.path("cache"));
    view::ViewSession session(dir.path("sc.vdb"));
    const auto brightness = [&](const std::string& folder) {
        double sum = 0.0;
        const RgbImage image = readExr(dir.path(folder + "/view.exr"));
        for (const openvdb::Vec3f& v : image.pixels) sum += double(v[0]) + double(v[1]) + double(v[2]);
        return sum;
    };

    const auto first = session.render(dir.path("s.json"), 24, 18, dir.path("r1"));
    CHECK(first.ran == std::vector<std::string>{"render"}); // nothing edited: the file's scatter as it is
    CHECK(std::filesystem::exists(first.png));
    const double before = brightness("r1");
    CHECK(before > 0.0);

    session.apply("mul", {{"grid", "scatter"}, {"value", 0.0}});
    CHECK(session.render(dir.path("s.json"), 24, 18, dir.path("r2")).ran == std::vector<std::string>{"render"}); // downstream only
    CHECK(brightness("r2") < before);

    session.undo();
    session.apply("mul", {{"grid", "scatter_source"}, {"value", 0.5}});
    CHECK(session.render(dir.path("s.json"), 24, 18, dir.path("r3")).ran == std::vector<std::string>{"scatter", "render"});
    const double halved = brightness("r3");
    CHECK(halved < before);
    const auto again = session.render(dir.path("s.json"), 24, 18, dir.path("r4"));
    CHECK(again.ran.front() == "scatter (kept from the last render)");
    CHECK(brightness("r4") == halved);

    // An edit of the scatter's input, then an edit of `scatter` itself: the stage re-runs after
    // the first, and the second applies to its result (the render dropped it before).
    session.apply("mul", {{"grid", "scatter"}, {"value", 0.0}});
    const auto both = session.render(dir.path("s.json"), 24, 18, dir.path("r5"));
    CHECK(both.ran == std::vector<std::string>{"scatter (kept from the last render)", "1 later steps", "render"});
    CHECK(brightness("r5") < halved);

    // A select among `density` reads it and writes only its mask: no scatter, and a later edit shows.
    session.undo();
    session.undo();
    session.apply("select", {{"grid", "density"}, {"shape", "box"}, {"min", {-2, -2, -2}}, {"max", {2, 2, 2}}, {"out", "mask"}});
    session.apply("mul", {{"grid", "scatter"}, {"value", 0.0}});
    const auto selected = session.render(dir.path("s.json"), 24, 18, dir.path("r6"));
    CHECK(selected.ran == std::vector<std::string>{"render"});
    CHECK(brightness("r6") < before);
}

TEST_CASE("view: the history: undo, redo, steps switched off, moved and removed, each what its steps make", "[view]")
{
    test::TempDir dir;
    writeSphere(dir.path("s.vdb"));
    view::ViewSession session(dir.path("s.vdb"));
    const nlohmann::json select = {{"grid", "direct"}, {"shape", "box"}, {"min", {-1, -1, -1}}, {"max", {0, 1, 1}}};
    const nlohmann::json hue = {{"grid", "direct"}, {"selection", "mask"}, {"hue_shift", 120.0}};
    const nlohmann::json twice = {{"grid", "direct"}, {"value", 2.0}};
    const nlohmann::json thinner = {{"grid", "density"}, {"selection", "mask"}, {"value", 0.5}, {"offset", 0.25}};
    session.apply("select", select);
    session.apply("edit", hue);
    session.apply("mul", twice);
    const std::string thinned = session.apply("edit", thinner);
    CHECK_THAT(thinned, Catch::Contains("voxels of 'density'"));
    const VoxelSet all = currentOf(session, "all.vdb");
    // A float grid's edit: v·value + offset on the selection, the rest as it was.
    const auto mask = all.get<openvdb::BoolGrid>("mask");
    const auto density = all.get<openvdb::FloatGrid>("density");
    for (auto it = density->cbeginValueOn(); it; ++it) {
        REQUIRE(*it == (mask->tree().isValueOn(it.getCoord()) ? 0.75f : 1.0f));
    }
    std::string why;

    // What a fresh session makes of the given steps, in order.
    const auto madeBy = [&](const std::vector<std::pair<std::string, nlohmann::json>>& steps, const std::string& name) {
        view::ViewSession fresh(dir.path("s.vdb"));
        for (const auto& [op, params] : steps) fresh.apply(op, params);
        return currentOf(fresh, name);
    };
    const auto history = [&](std::vector<nlohmann::json> steps) {
        session.setSteps(nlohmann::json(steps));
        return currentOf(session, "now.vdb");
    };
    const nlohmann::json a = {{"op", "select"}, {"params", select}}, b = {{"op", "edit"}, {"params", hue}},
                         c = {{"op", "mul"}, {"params", twice}}, d = {{"op", "edit"}, {"params", thinner}};
    nlohmann::json bOff = b;
    bOff["enabled"] = false;

    // Switched off: the set as if the step were not there, and the pipeline leaves it out.
    CHECK(sameSets(history({a, bOff, c, d}), madeBy({{"select", select}, {"mul", twice}, {"edit", thinner}}, "acd.vdb"), &why));
    INFO(why);
    CHECK(session.steps()[1]["enabled"] == false);
    nlohmann::json graph = session.pipeline(dir.path("replayed.vdb"));
    test::spit(dir.path("p.json"), graph.dump());
    runGraph(dir.path("p.json"), dir.path("cache"));
    CHECK(sameSets(readVoxelSet(dir.path("replayed.vdb")), currentOf(session, "now.vdb"), &why));
    // On again, moved, removed.
    CHECK(sameSets(history({a, b, c, d}), all, &why));
    CHECK(
        sameSets(history({a, c, b, d}), madeBy({{"select", select}, {"mul", twice}, {"edit", hue}, {"edit", thinner}}, "acbd.vdb"), &why));
    CHECK(sameSets(history({a, c}), madeBy({{"select", select}, {"mul", twice}}, "ac.vdb"), &why));
    // A history whose step fails (the hue edit before the select that makes its mask) is refused
    // naming the step, the session as it was.
    const VoxelSet before = currentOf(session, "before.vdb");
    CHECK_THROWS_WITH(history({b, a}), Catch::Contains("step 1") && Catch::Contains("mask"));
    CHECK_THROWS_WITH(session.setSteps(nlohmann::json::array({{{"op", "scatter"}}})), Catch::Contains("step 1"));
    CHECK(session.steps().size() == 2);
    CHECK(sameSets(currentOf(session, "after.vdb"), before, &why));

    // Undo and redo: each state exactly, past the states kept (replayed from the file as read).
    history({a, b, c, d});
    std::vector<VoxelSet> states{currentOf(session, "state0.vdb")};
    const std::size_t more = view::ViewSession::kKeptStates + 3;
    for (std::size_t i = 0; i < more; ++i) {
        session.apply("add", {{"grid", "direct"}, {"value", 0.125}});
        states.push_back(currentOf(session, fmt::format("state{}.vdb", i + 1)));
    }
    for (std::size_t i = more + 4; i-- > 0;) {
        REQUIRE(session.undo());
        if (i >= 4) CHECK(sameSets(currentOf(session, "undone.vdb"), states[i - 4], &why));
    }
    CHECK_FALSE(session.undo());
    CHECK(sameSets(currentOf(session, "original.vdb"), readVoxelSet(dir.path("s.vdb")), &why));
    CHECK(session.redoable() == more + 4);
    for (std::size_t i = 0; i < more + 4; ++i) REQUIRE(session.redo());
    CHECK_FALSE(session.redo());
    CHECK(sameSets(currentOf(session, "redone.vdb"), states.back(), &why));
    session.undo();
    session.apply("mul", twice); // a new step: nothing left to redo
    CHECK(session.redoable() == 0);
}

TEST_CASE("view: an edit of direct or scatter recomputes illumination, and an export keeps the grids asked for", "[view]")
{
    test::TempDir dir;
    {
        VoxelSet set = test::uniformSphere(test::albedoMaterial(4.0, 0.9), 1.0);
        test::putConstantFluence(set, "scatter", 0.5);
        auto illumination = set.get<openvdb::Vec3SGrid>("direct")->deepCopy();
        auto scatter = set.get<openvdb::Vec3SGrid>("scatter")->deepCopy();
        openvdb::tools::compSum(*illumination, *scatter);
        illumination->setName("illumination");
        set.put(illumination);
        writeVoxelSet(dir.path("s.vdb"), set);
    }
    view::ViewSession session(dir.path("s.vdb"));
    const std::string report = session.apply("mul", {{"grid", "direct"}, {"value", 3.0}});
    CHECK_THAT(report, Catch::Contains("recomputed 'illumination' = direct + scatter"));
    CHECK(session.steps()[0]["refreshes"] == nlohmann::json::array({"illumination"}));
    const VoxelSet now = currentOf(session, "now.vdb");
    auto sum = now.get<openvdb::Vec3SGrid>("direct")->deepCopy();
    auto scatter = now.get<openvdb::Vec3SGrid>("scatter")->deepCopy();
    openvdb::tools::compSum(*sum, *scatter);
    std::string why;
    CHECK(test::identicalGrids(*now.find("illumination"), *sum, &why));
    INFO(why);
    // An edit of another grid leaves it alone.
    CHECK_THAT(session.apply("mul", {{"grid", "density"}, {"value", 2.0}}), !Catch::Contains("recomputed"));
    // The pipeline recomputes it as the session did.
    test::spit(dir.path("p.json"), session.pipeline(dir.path("replayed.vdb")).dump());
    runGraph(dir.path("p.json"), dir.path("cache"));
    CHECK(test::identicalGrids(*readVoxelSet(dir.path("replayed.vdb")).find("illumination"), *sum, &why));

    // A whole export of the grids picked (the helper mask left out), its pipeline the same.
    session.apply("select", {{"grid", "density"}, {"shape", "box"}, {"min", {-1, -1, -1}}, {"max", {0, 1, 1}}});
    const VoxelSet picked = readVoxelSet(session.exportTo("picked.vdb", view::ExportMode::Whole, "", 0, {"density", "illumination"}));
    std::vector<std::string> names;
    for (const auto& g : picked.grids()) names.push_back(g->getName());
    CHECK(names == std::vector<std::string>{"density", "illumination"});
    nlohmann::json graph = nlohmann::json::parse(test::slurp(dir.path("picked.pipeline.json")));
    graph["outputs"] = {{graph["outputs"].begin().key(), dir.path("picked-replayed.vdb")}};
    test::spit(dir.path("q.json"), graph.dump());
    runGraph(dir.path("q.json"), dir.path("cache"));
    CHECK(sameSets(readVoxelSet(dir.path("picked-replayed.vdb")), picked, &why));
    CHECK_THROWS_WITH(session.exportTo("x.vdb", view::ExportMode::Whole, "", 0, {"nope"}), Catch::Contains("no grid 'nope'"));
    CHECK_FALSE(std::filesystem::exists(dir.path("x.vdb")));
}
