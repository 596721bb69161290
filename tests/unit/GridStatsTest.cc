#include <vxf/core/GridStats.h>

#include <catch2/catch.hpp>
#include <openvdb/openvdb.h>

#include <limits>

TEST_CASE("grid statistics count voxels, leaves and tiles", "[core][stats]")
{
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->tree().setValueOn(openvdb::Coord(1, 2, 3), 1.0f);
    grid->tree().setValueOn(openvdb::Coord(100, 2, 3), 1.0f);
    grid->tree().addTile(2, openvdb::Coord(256, 0, 0), 1.0f, true); // a 128^3 tile
    const vxf::GridStats s = vxf::gridStats(*grid);
    CHECK(s.activeVoxels == 2 + 128 * 128 * 128);
    CHECK(s.leafNodes == 2);
    CHECK(s.activeTiles == 1);
    CHECK(s.activeBBox == openvdb::CoordBBox(openvdb::Coord(1, 0, 0), openvdb::Coord(383, 127, 127)));
    CHECK(s.memoryBytes > 0);
}

TEST_CASE("NaN and infinite values are counted, voxels and tiles, with the first of them", "[core][stats]")
{
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    auto grid = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    grid->tree().setValueOn(openvdb::Coord(1, 2, 3), openvdb::Vec3f(1.0f));
    CHECK(vxf::nonFiniteValues(*grid).count == 0);
    grid->tree().setValueOn(openvdb::Coord(40, 2, 3), openvdb::Vec3f(1.0f, nan, 1.0f));
    grid->tree().setValueOn(openvdb::Coord(9, 9, 9), openvdb::Vec3f(inf, 1.0f, 1.0f));
    grid->tree().setValueOff(openvdb::Coord(9, 9, 10), openvdb::Vec3f(nan)); // inactive: not the grid's value
    grid->tree().addTile(1, openvdb::Coord(800, 0, 0), openvdb::Vec3f(-inf), true);
    const vxf::NonFiniteValues bad = vxf::nonFiniteValues(*grid);
    CHECK(bad.count == 3); // two voxels, one tile
    CHECK(bad.first == openvdb::Coord(9, 9, 9));
    auto density = openvdb::FloatGrid::create(0.0f);
    density->tree().setValueOn(openvdb::Coord(5, 5, 5), nan);
    CHECK(vxf::nonFiniteValues(*density).count == 1);
    CHECK(vxf::nonFiniteValues(*openvdb::BoolGrid::create()).count == 0); // a type without such values
}

TEST_CASE("byte counts are formatted for people", "[core][stats]")
{
    CHECK(vxf::formatBytes(512) == "512 B");
    CHECK(vxf::formatBytes(1536) == "1.5 KiB");
    CHECK(vxf::formatBytes(3u << 20) == "3.0 MiB");
}
