#include <vxf/ops/Fill.h>

#include <catch2/catch.hpp>

TEST_CASE("blur_special fills unset voxels from their neighbours, the artist's voxels stay bit-identical", "[ops]")
{
    auto region = openvdb::FloatGrid::create(0.0f);
    region->tree().fill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(9, 0, 0)), 1.0f, true); // a row of 10
    auto g = openvdb::FloatGrid::create(0.0f);
    g->tree().setValueOn(openvdb::Coord(0, 0, 0), 0.1f);
    g->tree().setValueOn(openvdb::Coord(9, 0, 0), 0.9f);
    g->tree().setValueOn(openvdb::Coord(20, 0, 0), 5.0f); // set by the artist outside the region: untouched
    vxf::ops::FillOptions o;
    o.region = region.get();
    o.smoothing = 500; // converge: the filled row becomes the linear ramp between the two ends
    CHECK(vxf::ops::fill(*g, o) == 8);
    CHECK(g->tree().getValue(openvdb::Coord(0, 0, 0)) == 0.1f);
    CHECK(g->tree().getValue(openvdb::Coord(9, 0, 0)) == 0.9f);
    CHECK(g->tree().getValue(openvdb::Coord(20, 0, 0)) == 5.0f);
    for (int x = 1; x < 9; ++x) {
        INFO(x);
        CHECK(g->tree().isValueOn(openvdb::Coord(x, 0, 0)));
        CHECK(g->tree().getValue(openvdb::Coord(x, 0, 0)) == Approx(0.1 + 0.8 * x / 9.0).margin(1e-4));
    }
    CHECK_FALSE(g->tree().isValueOn(openvdb::Coord(10, 0, 0)));

    // A selection recomputes set voxels too; nothing else changes.
    auto selection = openvdb::BoolGrid::create(false);
    selection->tree().setValueOn(openvdb::Coord(5, 0, 0), true);
    g->tree().setValueOn(openvdb::Coord(5, 0, 0), 100.0f);
    o.selection = selection.get();
    o.smoothing = 0;
    CHECK(vxf::ops::fill(*g, o) == 1);
    CHECK(g->tree().getValue(openvdb::Coord(5, 0, 0)) ==
        Approx(0.5 * (g->tree().getValue(openvdb::Coord(4, 0, 0)) + g->tree().getValue(openvdb::Coord(6, 0, 0)))));
}
