#include <vxf/io/GridChecksum.h>

#include <vxf/io/VoxelSetFile.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>
#include <tbb/global_control.h>

#include <fstream>

TEST_CASE("a grid's checksum follows its data (values, topology, tiles, halves), not the thread count", "[io][checksum]")
{
    auto grid = openvdb::FloatGrid::create(0.0f);
    for (int i = 0; i < 40; ++i) grid->tree().setValue(openvdb::Coord(i, 2 * i, -i), 0.1f * float(i));
    grid->tree().addTile(1, openvdb::Coord(64, 64, 64), 0.5f, true);
    const auto base = vxf::gridChecksum(*grid, false);
    REQUIRE(base);
    CHECK(vxf::gridChecksum(*grid->deepCopy(), false) == base);
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        CHECK(vxf::gridChecksum(*grid, false) == base);
    }
    auto value = grid->deepCopy();
    value->tree().setValue(openvdb::Coord(3, 6, -3), std::nextafter(0.3f, 1.0f));
    CHECK(vxf::gridChecksum(*value, false) != base);
    auto topology = grid->deepCopy();
    topology->tree().setValueOff(openvdb::Coord(3, 6, -3));
    CHECK(vxf::gridChecksum(*topology, false) != base);
    auto tile = grid->deepCopy();
    tile->tree().addTile(1, openvdb::Coord(64, 64, 64), 0.25f, true);
    CHECK(vxf::gridChecksum(*tile, false) != base);
    // As halves: a value that rounds to the same half hashes the same.
    auto near = grid->deepCopy();
    near->tree().setValue(openvdb::Coord(3, 6, -3), std::nextafter(0.3f, 1.0f));
    CHECK(vxf::gridChecksum(*near, true) == vxf::gridChecksum(*grid, true));
    CHECK_FALSE(vxf::gridChecksum(*openvdb::points::PointDataGrid::create(), false));
}

TEST_CASE("a byte damaged on disk that OpenVDB still reads is named on read, and other tools' files read as they are", "[io][checksum]")
{
    vxf::test::TempDir dir;
    const vxf::VoxelSet set = vxf::test::uniformSphere(vxf::test::albedoMaterial(4.0, 0.9), 1.0);
    for (const bool half : {false, true}) {
        CAPTURE(half);
        const std::string path = dir.path(half ? "half.vdb" : "float.vdb");
        vxf::VoxelSetWriteOptions options;
        options.compress = false; // the values lie in the file as they are
        options.half = half;
        vxf::writeVoxelSet(path, set, options);
        REQUIRE_NOTHROW(vxf::readVoxelSet(path)); // as written, it matches
        const std::string original = vxf::test::slurp(path);
        // Flip bytes from the end (the last grid's leaf values) until one reads as a file but
        // with other values: the checksum names the grid.
        bool found = false;
        for (std::size_t back = 16; back < 4096 && !found; back += 13) {
            std::string damaged = original;
            damaged[damaged.size() - back] = char(damaged[damaged.size() - back] ^ 0x40);
            vxf::test::spit(path, damaged);
            try {
                vxf::readVoxelSet(path);
            } catch (const vxf::Error& e) {
                const std::string what = e.what();
                if (what.find("damaged") == std::string::npos) continue; // OpenVDB's own error: not this case
                CHECK_THAT(what, Catch::Contains(path) && Catch::Contains("does not match the checksum vxf wrote"));
                std::vector<std::string> names;
                vxf::VoxelSetReadOptions accept;
                accept.acceptDamaged = true;
                accept.damaged = &names;
                CHECK_NOTHROW(vxf::readVoxelSet(path, accept));
                CHECK(names.size() == 1);
                found = true;
            }
        }
        CHECK(found);
    }
    // A file without checksums (Houdini's, Blender's, pyopenvdb's) reads as before.
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName("density");
    grid->tree().setValue(openvdb::Coord(0), 1.0f);
    openvdb::io::File(dir.path("other.vdb")).write({grid});
    CHECK(vxf::readVoxelSet(dir.path("other.vdb")).find("density"));
}
