#include <vxf/ops/Blur.h>

#include <vxf/core/Error.h>

#include <catch2/catch.hpp>

TEST_CASE("blur: box mean of a spike, topology kept, selection limits it", "[ops]")
{
    auto g = openvdb::FloatGrid::create(0.0f);
    g->tree().fill(openvdb::CoordBBox(openvdb::Coord(-4), openvdb::Coord(4)), 0.0f, true);
    g->tree().voxelizeActiveTiles();
    g->tree().setValueOn(openvdb::Coord(0), 27.0f);
    const auto voxels = g->activeVoxelCount();
    auto copy = g->deepCopy();
    vxf::ops::BlurOptions o;
    vxf::ops::blur(*g, o);
    // Separable 3-wide mean: the spike spreads evenly over its 3³ neighbourhood.
    CHECK(g->tree().getValue(openvdb::Coord(0)) == Approx(1.0f));
    CHECK(g->tree().getValue(openvdb::Coord(1, 1, 1)) == Approx(1.0f));
    CHECK(g->tree().getValue(openvdb::Coord(2, 0, 0)) == 0.0f);
    CHECK(g->activeVoxelCount() == voxels);

    // Only where the selection allows.
    auto selection = openvdb::BoolGrid::create(false);
    selection->tree().setValueOn(openvdb::Coord(1, 0, 0), true);
    const auto weights = vxf::ops::weightsFromSelection(*selection);
    o.mask = weights.get();
    vxf::ops::blur(*copy, o);
    CHECK(copy->tree().getValue(openvdb::Coord(0)) == 27.0f);
    CHECK(copy->tree().getValue(openvdb::Coord(1, 0, 0)) == Approx(1.0f));
    CHECK(copy->tree().getValue(openvdb::Coord(0, 1, 0)) == 0.0f);

    auto colour = openvdb::Vec3SGrid::create();
    colour->tree().setValueOn(openvdb::Coord(0), openvdb::Vec3f(27.0f));
    vxf::ops::blur(*colour, {});
    CHECK(colour->tree().getValue(openvdb::Coord(0))[1] == Approx(1.0f));
    o.radius = 0;
    CHECK_THROWS_AS(vxf::ops::blur(*g, o), vxf::UsageError);
}
