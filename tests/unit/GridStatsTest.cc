#include <vxf/core/GridStats.h>

#include <catch2/catch.hpp>
#include <openvdb/openvdb.h>

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

TEST_CASE("byte counts are formatted for people", "[core][stats]")
{
    CHECK(vxf::formatBytes(512) == "512 B");
    CHECK(vxf::formatBytes(1536) == "1.5 KiB");
    CHECK(vxf::formatBytes(3u << 20) == "3.0 MiB");
}
