// Uniform regions a march crosses in one go (vxf/transport/UniformBricks.h): found where the
// density is one value, with that value, not where it varies; from the tree's own tiles too.
#include <vxf/transport/UniformBricks.h>

#include <vxf/core/GridLookup.h>

#include <catch2/catch.hpp>

namespace {
openvdb::FloatGrid::Ptr boxWithRamp()
{
    // A 64³ box of density 3 whose first 8 slabs along x ramp up: uniform bricks only past them.
    auto density = openvdb::FloatGrid::create(0.0f);
    density->fill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(63)), 3.0f, true);
    for (int x = 0; x < 8; ++x) {
        for (int y = 0; y < 64; ++y) {
            for (int z = 0; z < 64; ++z) density->tree().setValueOn(openvdb::Coord(x, y, z), 0.3f * float(x + 1));
        }
    }
    return density;
}
} // namespace

TEST_CASE("uniform bricks: one density inside, none where it varies, and whole steps across them", "[transport][bricks]")
{
    const auto density = boxWithRamp();
    const openvdb::CoordBBox bounds = density->evalActiveVoxelBoundingBox();
    const auto dense = vxf::DenseCopy<openvdb::FloatGrid>::create(*density, 2, std::size_t(1) << 30);
    REQUIRE(dense);
    const vxf::UniformBricks bricks(dense.get(), bounds, nullptr, 1.0, /*hasSurface=*/false);
    CHECK(bricks.uniformBrickCount() > 0);

    openvdb::Vec3d lo, hi;
    float value = -1.0f;
    const openvdb::Vec3d centre(32.5, 32.5, 32.5);
    REQUIRE(bricks.find(centre, 1.0, lo, hi, value));
    CHECK(value == 3.0f);
    for (int a = 0; a < 3; ++a) {
        CHECK(lo[a] <= centre[a]);
        CHECK(centre[a] < hi[a]);
    }
    CHECK_FALSE(bricks.find(openvdb::Vec3d(3.5, 32.5, 32.5), 1.0, lo, hi, value)); // on the ramp

    // Whole steps along +x from the centre stay in uniform regions of density 3.
    float along = -1.0f;
    const int steps = bricks.stepsWithin(centre, openvdb::Vec3d(1.0, 0.0, 0.0), 1.0, 1000, along);
    CHECK(steps > 0);
    CHECK(steps <= 31);
    CHECK(along == 3.0f);
}

TEST_CASE("without a dense copy the tree's tiles and the empty space between its nodes are the regions", "[transport][bricks]")
{
    auto density = openvdb::FloatGrid::create(0.0f);
    density->fill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(127)), 2.0f, true); // an internal node's tile
    density->tree().setValueOn(openvdb::Coord(5000, 0, 0), 1.0f); // a far part: empty space between
    const vxf::UniformBricks regions(density);
    openvdb::Vec3d lo, hi;
    float value = -1.0f;
    REQUIRE(regions.find(openvdb::Vec3d(64.0, 64.0, 64.0), 1.0, lo, hi, value));
    CHECK(value == 2.0f);
    REQUIRE(regions.find(openvdb::Vec3d(2500.0, 64.0, 64.0), 1.0, lo, hi, value));
    CHECK(value == 0.0f);
    CHECK(hi.x() - lo.x() > 100.0); // crossed in one go
}
