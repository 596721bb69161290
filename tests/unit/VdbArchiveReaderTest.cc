// readVoxelSet's checked reading of .vdb files (libvxf/src/io/VdbArchiveReader.h and
// VdbChunkReaders.cc): what OpenVDB 10.0.1's own reader would size, overflow or misread from a
// crafted file is an error naming the file, and real files of every compression read as written.
#include <vxf/io/VoxelSetFile.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>
#include <openvdb/io/File.h>
#include <openvdb/points/PointConversion.h>

#include <cstring>
#include <string>

namespace {

/// The bytes of @a file with the 4 bytes after the first @a marker replaced by @a value.
std::string patchedAfter(const std::string& bytes, const std::string& marker, std::uint32_t value)
{
    const std::size_t at = bytes.find(marker);
    REQUIRE(at != std::string::npos);
    std::string patched = bytes;
    std::memcpy(&patched[at + marker.size()], &value, sizeof(value));
    return patched;
}

std::string readError(const std::string& path)
{
    try {
        (void)vxf::readVoxelSet(path);
    } catch (const vxf::Error& e) {
        return e.what();
    }
    return "";
}

openvdb::FloatGrid::Ptr smallDensity()
{
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName("density");
    for (int i = 0; i < 300; ++i) grid->tree().setValue(openvdb::Coord(i % 17, i / 17, i % 5), 0.5f + 0.01f * float(i));
    grid->setTransform(openvdb::math::Transform::createLinearTransform(0.1));
    return grid;
}

} // namespace

TEST_CASE("every crafted .vdb that made OpenVDB 10.0.1's reader write past a buffer is an error naming the file", "[io][vdb]")
{
    // Inputs found by fuzzing (docs/reliability.md, "OpenVDB's reader"): a raw chunk declaring
    // more bytes than its node holds, read under ASan as a heap-buffer-overflow before.
    for (const char* name : {"blosc_raw_chunk_longer_than_node", "blosc_raw_chunk_longer_than_node_2"}) {
        const std::string path = vxf::test::source("tests/regress/fuzz/vdb_info/") + name;
        const std::string error = readError(path);
        CAPTURE(name);
        CHECK_THAT(error,
            Catch::Contains(path) && Catch::Contains("not a readable OpenVDB file") &&
                Catch::Contains("uncompressed bytes where the node holds"));
    }
}

TEST_CASE("files compressed with zip, Blosc or nothing, as halves or floats, read back voxel for voxel", "[io][vdb]")
{
    vxf::test::TempDir dir;
    const auto grid = smallDensity();
    const std::uint32_t compressions[] = {openvdb::io::COMPRESS_NONE, openvdb::io::COMPRESS_ZIP,
        openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK, openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK};
    for (const std::uint32_t compression : compressions) {
        for (const bool half : {false, true}) {
            CAPTURE(compression, half);
            auto copy = grid->deepCopy();
            copy->setSaveFloatAsHalf(half);
            openvdb::io::File file(dir.path("c.vdb"));
            file.setCompression(compression);
            file.write({copy});
            file.close();
            const vxf::VoxelSet set = vxf::readVoxelSet(dir.path("c.vdb"));
            const auto read = set.get<openvdb::FloatGrid>("density");
            REQUIRE(read);
            CHECK(read->activeVoxelCount() == grid->activeVoxelCount());
            float worst = 0.0f;
            for (auto it = grid->cbeginValueOn(); it; ++it) {
                worst = std::max(worst, std::abs(read->tree().getValue(it.getCoord()) - *it));
            }
            CHECK(worst <= (half ? 1e-3f : 0.0f));
            // OpenVDB's delayed-load metadata describes the file read, never a file vxf writes.
            CHECK_FALSE((*read)[openvdb::GridBase::META_FILE_DELAYED_LOAD]);
        }
    }
}

TEST_CASE("a size in a .vdb's metadata that the file cannot hold, or a fixed-size value of another size, is refused before it is used",
    "[io][vdb]")
{
    vxf::test::TempDir dir;
    auto grid = smallDensity();
    grid->insertMeta("opacity_scale", openvdb::FloatMetadata(2.0f));
    grid->insertMeta("comment", openvdb::StringMetadata("made by a test"));
    openvdb::io::File(dir.path("good.vdb")).write({grid});
    const std::string good = vxf::test::slurp(dir.path("good.vdb"));
    REQUIRE_NOTHROW(vxf::readVoxelSet(dir.path("good.vdb")));

    // A string 4 GiB long in a 2 KiB file: OpenVDB would allocate and fill it first.
    const std::string opacityName = "opacity_scale";
    std::string longString = good;
    {
        // The item: name length, name, type length, "string", value length, value.
        const std::size_t at = good.find("comment");
        REQUIRE(at != std::string::npos);
        const std::size_t lengthAt = at + std::strlen("comment") + 4 + std::strlen("string");
        const std::uint32_t huge = 0xfffffff0u;
        std::memcpy(&longString[lengthAt], &huge, 4);
    }
    vxf::test::spit(dir.path("long.vdb"), longString);
    CHECK_THAT(readError(dir.path("long.vdb")),
        Catch::Contains(dir.path("long.vdb")) && Catch::Contains("the metadata of grid 'density'") &&
            Catch::Contains("declares 4294967280 bytes where the file has"));

    // A float declaring 8 bytes: OpenVDB reads 4 and takes the other 4 for the next item.
    vxf::test::spit(dir.path("float8.vdb"), patchedAfter(good, opacityName + std::string("\x05\0\0\0", 4) + "float", 8));
    CHECK_THAT(
        readError(dir.path("float8.vdb")), Catch::Contains("item 'opacity_scale' of type float declares 8 bytes where the type has 4"));

    // Delayed-load metadata (a count, then a mask per leaf) declaring 2^32 − 1 leaves: OpenVDB
    // would size a 4 GiB mask from it. vxf never loads piecewise, reads it as opaque bytes and drops it.
    const std::size_t delayed = good.find("__delayedload");
    REQUIRE(delayed != std::string::npos);
    std::string manyLeaves = good;
    const std::uint32_t count = 0xffffffffu;
    std::memcpy(&manyLeaves[delayed + std::strlen("__delayedload") + 4], &count, 4); // after the value's byte count
    vxf::test::spit(dir.path("delayed.vdb"), manyLeaves);
    const vxf::VoxelSet set = vxf::readVoxelSet(dir.path("delayed.vdb"));
    REQUIRE(set.get<openvdb::FloatGrid>("density"));
    CHECK(set.get<openvdb::FloatGrid>("density")->activeVoxelCount() == grid->activeVoxelCount());
    CHECK_FALSE((*set.get<openvdb::FloatGrid>("density"))[openvdb::GridBase::META_FILE_DELAYED_LOAD]);
}

TEST_CASE("a .vdb with point data beside its volumes (as Houdini writes) reads the volumes and names the points it skipped", "[io][vdb]")
{
    openvdb::initialize(); // the point attribute types (readVoxelSet initializes too, but later)
    vxf::test::TempDir dir;
    const std::vector<openvdb::Vec3R> positions{{0, 0, 0}, {0.5, 0.25, 1}, {1, 1, 1}};
    const openvdb::points::PointAttributeVector<openvdb::Vec3R> wrapper(positions);
    const auto transform = openvdb::math::Transform::createLinearTransform(0.5);
    auto points = openvdb::points::createPointDataGrid<openvdb::points::NullCodec, openvdb::points::PointDataGrid>(
        *openvdb::tools::createPointIndexGrid<openvdb::tools::PointIndexGrid>(wrapper, *transform), wrapper, *transform);
    points->setName("particles");
    openvdb::io::File(dir.path("mixed.vdb")).write({points, smallDensity()});

    std::vector<std::string> skipped;
    vxf::VoxelSetReadOptions options;
    options.skipped = &skipped;
    const vxf::VoxelSet set = vxf::readVoxelSet(dir.path("mixed.vdb"), options);
    CHECK(set.get<openvdb::FloatGrid>("density"));
    CHECK(set.grids().size() == 1);
    REQUIRE(skipped.size() == 1);
    CHECK_THAT(skipped[0], Catch::StartsWith("particles (Tree_ptdataidx32"));
    // `vxf info` lists the volume and says what it skipped.
    const auto info = vxf::test::run(vxf::test::binary("vxf") + " info '" + dir.path("mixed.vdb") + "'");
    CHECK(info.status == 0);
    CHECK_THAT(info.out, Catch::Contains("density"));
    CHECK_THAT(info.err, Catch::Contains("grid particles (Tree_ptdataidx32_5_4_3) skipped: not a voxel grid vxf reads"));
}
