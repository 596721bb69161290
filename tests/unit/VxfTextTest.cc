#include <vxf/io/VxfText.h>

#include <vxf/core/ProceduralMesh.h>
#include <vxf/io/VoxelSetFile.h>
#include <vxf/ops/Blend.h>
#include <vxf/voxelize/Voxelize.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <random>

using vxf::test::slurp;
using vxf::test::spit;
using vxf::test::TempDir;

namespace {

/// text → vdb → text → vdb: both .vdb files identical, both texts identical.
void checkRoundTrip(const std::string& text, const TempDir& dir)
{
    spit(dir.path("a.vxf"), text);
    const vxf::VoxelSet first = vxf::readVxfText(dir.path("a.vxf"));
    vxf::writeVoxelSet(dir.path("a.vdb"), first);
    vxf::writeVxfText(dir.path("b.vxf"), vxf::readVoxelSet(dir.path("a.vdb")));
    const vxf::VoxelSet second = vxf::readVxfText(dir.path("b.vxf"));
    vxf::writeVoxelSet(dir.path("b.vdb"), second);
    vxf::writeVxfText(dir.path("c.vxf"), vxf::readVoxelSet(dir.path("b.vdb")));

    REQUIRE(first.grids().size() == second.grids().size());
    CHECK(first.transform() == second.transform());
    for (std::size_t i = 0; i < first.grids().size(); ++i) {
        std::string why;
        INFO(first.grids()[i]->getName());
        CHECK(vxf::test::identicalGrids(*first.grids()[i], *second.grids()[i], &why));
        INFO(why);
    }
    CHECK(slurp(dir.path("b.vxf")) == slurp(dir.path("c.vxf")));
}

vxf::VoxelSet readText(const TempDir& dir, const std::string& text)
{
    spit(dir.path("in.vxf"), text);
    return vxf::readVxfText(dir.path("in.vxf"));
}

} // namespace

TEST_CASE("the thesis's header and default columns read as a color grid", "[io][vxf]")
{
    TempDir dir;
    const vxf::VoxelSet set = readText(dir,
        "# thesis-style file\n"
        "size 4 3 2 0.5\n"
        "min -1 -0.75 0\n"
        "max 1 0.75 1\n"
        "0 0 0 1 0.25 0.5 1\n"
        "\n"
        "3 2 1 0 -0.5 2.5 1e-3   # an inactive voxel with a negative value\n");
    auto color = set.get<openvdb::Vec3SGrid>("color");
    CHECK(color->activeVoxelCount() == 1);
    CHECK(color->tree().getValue(openvdb::Coord(0, 0, 0)) == openvdb::Vec3f(0.25f, 0.5f, 1.0f));
    CHECK(color->tree().getValue(openvdb::Coord(3, 2, 1)) == openvdb::Vec3f(-0.5f, 2.5f, 1e-3f));
    CHECK_FALSE(color->tree().isValueOn(openvdb::Coord(3, 2, 1)));
    // Voxel (i,j,k) has its centre at min + voxelsize (ijk + 1/2).
    const openvdb::Vec3d centre = set.transform().indexToWorld(openvdb::Coord(3, 2, 1));
    CHECK(centre.x() == Approx(0.75));
    CHECK(centre.y() == Approx(0.5));
    CHECK(centre.z() == Approx(0.75));
}

TEST_CASE("declared columns: several grids, classes, backgrounds, bools", "[io][vxf]")
{
    TempDir dir;
    const vxf::VoxelSet set = readText(dir,
        "vxf 1\n"
        "size 8 8 8 1\nmin 0 0 0\nmax 8 8 8\n"
        "grid surface float class=level_set background=3\n"
        "grid sigma_a vec3 background=0.1,0.2,0.3\n"
        "grid mask bool\n"
        "count 2\n"
        "1 1 1 1 -0.5 1 2 3 1\n"
        "+2 1 1 1 0.5 4 5 6 0\r\n");
    auto surface = set.get<openvdb::FloatGrid>("surface");
    CHECK(surface->getGridClass() == openvdb::GRID_LEVEL_SET);
    CHECK(surface->background() == 3.0f);
    CHECK(set.get<openvdb::Vec3SGrid>("sigma_a")->background() == openvdb::Vec3f(0.1f, 0.2f, 0.3f));
    CHECK(set.get<openvdb::Vec3SGrid>("sigma_a")->tree().getValue(openvdb::Coord(2, 1, 1)) == openvdb::Vec3f(4, 5, 6));
    CHECK(set.get<openvdb::BoolGrid>("mask")->tree().getValue(openvdb::Coord(1, 1, 1)));
    CHECK_FALSE(set.get<openvdb::BoolGrid>("mask")->tree().getValue(openvdb::Coord(2, 1, 1)));
}

TEST_CASE("text round trips are lossless", "[io][vxf]")
{
    TempDir dir;
    SECTION("dense block with awkward floats")
    {
        std::mt19937 rng(7);
        std::uniform_real_distribution<float> value(-3.0f, 3.0f);
        std::string text = "size 6 5 4 0.1\nmin -0.3 -0.25 -0.2\nmax 0.3 0.25 0.2\ngrid color vec3\ngrid density float\n";
        const float specials[] = {0.1f, 1.0f / 3.0f, 1e-40f /* subnormal */, -0.0f, 3.4e38f, 1.17549435e-38f};
        int n = 0;
        for (int i = 0; i < 6; ++i)
            for (int j = 0; j < 5; ++j)
                for (int k = 0; k < 4; ++k, ++n) {
                    const float d = n < 6 ? specials[n] : value(rng);
                    text += fmt::format("{} {} {} {} {} {} {} {}\n", i, j, k, n % 3 ? 1 : 0, value(rng), value(rng), value(rng), d);
                }
        checkRoundTrip(text, dir);
    }
    SECTION("sparse voxels far apart, far from the origin")
    {
        checkRoundTrip("size 100000 3 70000 0.001\nmin 100000.0005 -7 3\nmax 100100.0005 -6.997 73\n"
                       "0 0 0 1 1 2 3\n99999 2 69999 1 4 5 6\n500 1 7 0 7 8 9\n",
            dir);
    }
    SECTION("level set with inside tiles comes back with its sign")
    {
        std::string text = "size 40 40 40 0.05\nmin -1 -1 -1\nmax 1 1 1\ngrid surface float class=level_set background=0.15\n";
        // A sphere's narrow band written by hand: only the band, no interior.
        for (int i = 0; i < 40; ++i)
            for (int j = 0; j < 40; ++j)
                for (int k = 0; k < 40; ++k) {
                    const double d = std::sqrt(std::pow(i - 19.5, 2) + std::pow(j - 19.5, 2) + std::pow(k - 19.5, 2)) * 0.05 - 0.6;
                    if (std::abs(d) < 0.15) text += fmt::format("{} {} {} 1 {}\n", i, j, k, float(d));
                }
        checkRoundTrip(text, dir);
        const vxf::VoxelSet set = readText(dir, text);
        CHECK(set.get<openvdb::FloatGrid>("surface")->tree().getValue(openvdb::Coord(20, 20, 20)) == -0.15f);
        CHECK(set.get<openvdb::FloatGrid>("surface")->tree().getValue(openvdb::Coord(0, 0, 0)) == 0.15f);
    }
    SECTION("an empty volume") { checkRoundTrip("size 2 2 2 1\nmin 0 0 0\nmax 2 2 2\n", dir); }
}

TEST_CASE("vdb grids write as text and read back identically", "[io][vxf]")
{
    TempDir dir;
    auto xform = openvdb::math::Transform::createLinearTransform(0.25);
    vxf::VoxelSet set(xform);
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->setTransform(xform);
    density->setGridClass(openvdb::GRID_FOG_VOLUME);
    density->tree().addTile(1, openvdb::Coord(-16, 0, 0), 1.0f, true); // an interior tile
    density->tree().setValueOn(openvdb::Coord(-17, 3, 3), 0.5f);
    set.put(density);
    auto illumination = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    illumination->setName("illumination");
    illumination->setTransform(xform);
    illumination->tree().setValueOn(openvdb::Coord(-17, 3, 3), openvdb::Vec3f(1, 2, 3));
    set.put(illumination);

    const auto warnings = vxf::writeVxfText(dir.path("out.vxf"), set);
    REQUIRE(warnings.size() == 1); // different topologies are unioned, and said so
    CHECK(warnings[0].find("different active voxels") != std::string::npos);
    const std::string text = slurp(dir.path("out.vxf"));
    CHECK(text.find("size 9 8 8 0.25\n") != std::string::npos);
    CHECK(text.find("count 513\n") != std::string::npos);

    CHECK(text.find("min -4.375 -0.125 -0.125\n") != std::string::npos); // the corner of voxel (-17, 0, 0)

    // Back at the same index coordinates under the same transform: min lies on the corners of
    // the grid's own lattice (-4.375 / 0.25 + 0.5 = -17), so the text's index origin is known.
    const vxf::VoxelSet back = vxf::readVxfText(dir.path("out.vxf"));
    CHECK(back.transform() == *xform);
    auto readDensity = back.get<openvdb::FloatGrid>("density");
    CHECK(*readDensity->transformPtr() == *xform);
    CHECK(readDensity->getGridClass() == openvdb::GRID_FOG_VOLUME);
    CHECK(readDensity->activeVoxelCount() == 513);
    CHECK(readDensity->tree().activeTileCount() == 1); // the 8^3 tile is leaf-aligned again, and pruned back
    CHECK(readDensity->tree().getValue(openvdb::Coord(-17, 3, 3)) == 0.5f);
    CHECK(readDensity->tree().getValue(openvdb::Coord(-12, 5, 1)) == 1.0f);
    CHECK(back.get<openvdb::Vec3SGrid>("illumination")->tree().getValue(openvdb::Coord(-17, 3, 3)) == openvdb::Vec3f(1, 2, 3));
}

TEST_CASE("a voxelized mesh's grids come back from text at their own index coordinates, and blend with the originals", "[io][vxf]")
{
    TempDir dir;
    vxf::VoxelizeOptions options;
    options.dim = 24;
    const vxf::VoxelSet set = vxf::voxelize(vxf::makeSphere(openvdb::Vec3d(0.3, -0.2, 0.1), 1.0, 32, 64), options);
    vxf::writeVoxelSet(dir.path("a.vdb"), set);
    for (const char* name : {"density", "surface"}) {
        INFO(name);
        vxf::VxfWriteOptions write;
        write.grids = {name};
        vxf::writeVxfText(dir.path("a.vxf"), vxf::readVoxelSet(dir.path("a.vdb")), write);
        const vxf::VoxelSet back = vxf::readVxfText(dir.path("a.vxf"));
        const auto original = set.get<openvdb::FloatGrid>(name);
        const auto returned = back.get<openvdb::FloatGrid>(name);
        CHECK(*returned->transformPtr() == original->transform());
        CHECK(returned->getGridClass() == original->getGridClass());
        CHECK(returned->activeVoxelCount() == original->activeVoxelCount());
        bool same = true;
        auto acc = returned->getConstAccessor();
        for (auto it = original->cbeginValueOn(); it; ++it)
            same = same && acc.isValueOn(it.getCoord()) && acc.getValue(it.getCoord()) == *it;
        CHECK(same); // every active voxel at its index, bit-exact
        // Edited in text and back, the grid blends with its original as it is (no resample).
        auto sum = original->deepCopy();
        vxf::ops::BlendOptions add;
        add.mode = vxf::ops::BlendMode::Add;
        CHECK_NOTHROW(vxf::ops::blend(*sum, *returned, add));
        CHECK(sum->tree().getValue(original->cbeginValueOn().getCoord()) == 2.0f * *original->cbeginValueOn());
    }
}

TEST_CASE("writing text refuses what it cannot represent", "[io][vxf]")
{
    TempDir dir;
    vxf::VoxelSet set(openvdb::math::Transform::createLinearTransform(1.0));
    auto color = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    color->setName("color");
    color->setTransform(set.transformPtr());
    color->tree().setValueOn(openvdb::Coord(1, 2, 3), openvdb::Vec3f(1.0f, std::nanf(""), 0.0f));
    set.put(color);
    CHECK_THROWS_WITH(vxf::writeVxfText(dir.path("nan.vxf"), set),
        "grid 'color' holds a non-finite value at voxel (1, 2, 3); text VXF allows finite numbers only");
    CHECK_FALSE(std::filesystem::exists(dir.path("nan.vxf")));

    vxf::VxfWriteOptions options;
    options.grids = {"nothing"};
    CHECK_THROWS_WITH(vxf::writeVxfText(dir.path("x.vxf"), set, options), "no grid named 'nothing' to write");

    vxf::VoxelSet rotated(openvdb::math::Transform::createLinearTransform(1.0));
    rotated.transformPtr()->postRotate(0.3, openvdb::math::Z_AXIS);
    auto g = openvdb::FloatGrid::create();
    g->setName("density");
    g->setTransform(rotated.transformPtr());
    rotated.put(g);
    CHECK_THROWS_WITH(vxf::writeVxfText(dir.path("r.vxf"), rotated), Catch::Contains("axis-aligned cubic voxels"));
}

TEST_CASE("the example in schemas/vxf-text.md reads as specified", "[io][vxf][schema]")
{
    const std::string spec = slurp(vxf::test::source("schemas/vxf-text.md"));
    const auto start = spec.find("```\n# two grids");
    REQUIRE(start != std::string::npos);
    const auto end = spec.find("```", start + 3);
    TempDir dir;
    const vxf::VoxelSet set = readText(dir, spec.substr(start + 4, end - start - 4));
    CHECK(set.get<openvdb::Vec3SGrid>("color")->activeVoxelCount() == 2);
    CHECK(set.get<openvdb::FloatGrid>("density")->getGridClass() == openvdb::GRID_FOG_VOLUME);
    CHECK(set.get<openvdb::FloatGrid>("density")->tree().getValue(openvdb::Coord(1, 0, 0)) == 0.5f);
}

TEST_CASE("number syntax of the spec", "[io][vxf]")
{
    TempDir dir;
    const vxf::VoxelSet set = readText(dir, "size 2 2 2 1\nmin 0 0 0\nmax 2 2 2\n+1 0 1 1 .25 1E+10 -3e-7\n\t0 1 0 1 +2 -0 1.\n");
    auto color = set.get<openvdb::Vec3SGrid>("color");
    CHECK(color->tree().getValue(openvdb::Coord(1, 0, 1)) == openvdb::Vec3f(0.25f, 1e10f, -3e-7f));
    CHECK(color->tree().getValue(openvdb::Coord(0, 1, 0)) == openvdb::Vec3f(2.0f, 0.0f, 1.0f));
    CHECK_THROWS_WITH(readText(dir, "size 2 2 2 1\nmin 0 0 0\nmax 2 2 2\n0 0 0 1 0x10 0 0\n"),
        Catch::EndsWith("in.vxf:4:9: expected a number for grid 'color' r, found '0x10'"));
    CHECK_THROWS_WITH(readText(dir, "size 2 2 2 1\nmin 0 0 0\nmax 2 2 2\n0 0 0 1 1 Infinity 0\n"),
        Catch::EndsWith("in.vxf:4:11: grid 'color' g is infinite; only finite numbers are allowed"));
}
