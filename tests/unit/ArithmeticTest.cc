#include <vxf/ops/Arithmetic.h>

#include <vxf/core/Error.h>

#include <catch2/catch.hpp>

using vxf::ops::ArithmeticOp;

TEST_CASE("arithmetic: exact per voxel, tiles stay tiles, division by zero and pow of negatives defined", "[ops]")
{
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->tree().setValueOn(openvdb::Coord(0), -8.0f);
    grid->tree().setValueOn(openvdb::Coord(1, 0, 0), 2.0f);
    grid->tree().setValueOff(openvdb::Coord(2, 0, 0), 5.0f); // inactive: untouched
    grid->tree().addTile(1, openvdb::Coord(64), 3.0f, true);
    const auto v = [&](int x, int y = 0, int z = 0) { return grid->tree().getValue(openvdb::Coord(x, y, z)); };

    vxf::ops::arithmetic(*grid, ArithmeticOp::Add, openvdb::Vec3d(1.0));
    CHECK(v(0) == -7.0f);
    CHECK(v(1) == 3.0f);
    CHECK(v(2) == 5.0f);
    CHECK(v(64, 64, 64) == 4.0f);
    CHECK(grid->tree().getValueDepth(openvdb::Coord(64)) < int(openvdb::FloatTree::DEPTH) - 1); // still a tile
    CHECK(grid->background() == 0.0f);

    vxf::ops::arithmetic(*grid, ArithmeticOp::Div, openvdb::Vec3d(0.0));
    CHECK(v(0) == 0.0f); // x / 0 = 0
    CHECK(v(2) == 5.0f);

    grid->tree().setValueOn(openvdb::Coord(0), -8.0f);
    vxf::ops::arithmetic(*grid, ArithmeticOp::Pow, openvdb::Vec3d(1.0 / 3.0));
    CHECK(v(0) == Approx(-2.0f)); // odd extension: −|x|^p
    vxf::ops::arithmetic(*grid, ArithmeticOp::Mul, openvdb::Vec3d(1e38));
    vxf::ops::arithmetic(*grid, ArithmeticOp::Mul, openvdb::Vec3d(1e38));
    CHECK(v(0) == -std::numeric_limits<float>::max()); // clamped, never Inf
    grid->tree().setValueOn(openvdb::Coord(0), 0.0f);
    vxf::ops::arithmetic(*grid, ArithmeticOp::Pow, openvdb::Vec3d(-1.0));
    CHECK(v(0) == 0.0f); // 0 ^ negative = 0, never Inf

    auto colour = openvdb::Vec3SGrid::create();
    colour->tree().setValueOn(openvdb::Coord(0), openvdb::Vec3f(1, 2, 3));
    vxf::ops::arithmetic(*colour, ArithmeticOp::Mul, openvdb::Vec3d(2, 0.5, -1));
    CHECK(colour->tree().getValue(openvdb::Coord(0)) == openvdb::Vec3f(2, 1, -3));

    auto flags = openvdb::BoolGrid::create();
    CHECK_THROWS_AS(vxf::ops::arithmetic(*flags, ArithmeticOp::Add, openvdb::Vec3d(1.0)), vxf::UsageError);
}
