#include <vxf/io/MitsubaVolume.h>

#include <vxf/core/Error.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <cstring>

TEST_CASE("Mitsuba .vol: header, bounds over voxel cells, values x fastest", "[io][mitsuba]")
{
    vxf::test::TempDir dir;
    auto g = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    g->setName("sigma");
    g->setTransform(openvdb::math::Transform::createLinearTransform(0.5));
    g->tree().setValueOn(openvdb::Coord(0, 0, 0), openvdb::Vec3f(1, 2, 3));
    g->tree().setValueOn(openvdb::Coord(2, 1, 0), openvdb::Vec3f(4, 5, 6));
    const auto info = vxf::writeMitsubaVolume(dir.path("g.vol"), *g, 0);
    CHECK(info.resolution == openvdb::Coord(3, 2, 1));
    CHECK(info.channels == 3);
    const std::string bytes = vxf::test::slurp(dir.path("g.vol"));
    REQUIRE(bytes.size() == 48 + 3 * 2 * 1 * 3 * 4);
    CHECK(bytes.substr(0, 3) == "VOL");
    CHECK(int(bytes[3]) == 3);
    const auto i32 = [&](std::size_t at) {
        std::int32_t v;
        std::memcpy(&v, bytes.data() + at, 4);
        return v;
    };
    const auto f32 = [&](std::size_t at) {
        float v;
        std::memcpy(&v, bytes.data() + at, 4);
        return v;
    };
    CHECK(i32(4) == 1);
    CHECK(i32(8) == 3);
    CHECK(i32(12) == 2);
    CHECK(i32(16) == 1);
    CHECK(i32(20) == 3);
    CHECK(f32(24) == -0.25f); // cell of voxel 0: centre 0, half a voxel (0.25) each side
    CHECK(f32(36) == 1.25f); // x max: voxel 2's cell ends at 2.5 voxels = 1.25
    // Voxel (2, 1, 0): index ((0·2 + 1)·3 + 2)·3 channels.
    CHECK(f32(48 + 4 * ((1 * 3 + 2) * 3 + 1)) == 5.0f);
    CHECK(f32(48 + 4 * 2) == 3.0f);
    CHECK_THROWS_AS(vxf::writeMitsubaVolume(dir.path("b.vol"), *openvdb::BoolGrid::create(), 0), vxf::UsageError);
    CHECK_THROWS_AS(vxf::writeMitsubaVolume(dir.path("e.vol"), *openvdb::FloatGrid::create(), 0), vxf::UsageError);
}
