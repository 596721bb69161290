#include <vxf/ops/Edit.h>

#include <catch2/catch.hpp>

TEST_CASE("edit on a selection: set, hue, saturation, value, add and remove, the rest untouched", "[ops]")
{
    CHECK((vxf::ops::hsvToRgb(vxf::ops::rgbToHsv(openvdb::Vec3d(0.2, 0.5, 0.9))) - openvdb::Vec3d(0.2, 0.5, 0.9)).length() < 1e-12);
    CHECK(vxf::ops::rgbToHsv(openvdb::Vec3d(1, 0, 0))[0] == 0.0);
    CHECK((vxf::ops::hsvToRgb(openvdb::Vec3d(120, 1, 1)) - openvdb::Vec3d(0, 1, 0)).length() < 1e-12);

    auto g = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    g->tree().setValueOn(openvdb::Coord(0), openvdb::Vec3f(1, 0, 0));
    g->tree().setValueOn(openvdb::Coord(1, 0, 0), openvdb::Vec3f(1, 0, 0));
    auto selection = openvdb::BoolGrid::create(false);
    selection->tree().setValueOn(openvdb::Coord(0), true);
    selection->tree().setValueOn(openvdb::Coord(5, 0, 0), true); // inactive in g
    vxf::ops::EditOptions o;
    o.hueShift = 120.0;
    vxf::ops::edit(*g, selection.get(), o);
    CHECK((g->tree().getValue(openvdb::Coord(0)) - openvdb::Vec3f(0, 1, 0)).length() < 1e-6f);
    CHECK(g->tree().getValue(openvdb::Coord(1, 0, 0)) == openvdb::Vec3f(1, 0, 0));
    CHECK_FALSE(g->tree().isValueOn(openvdb::Coord(5, 0, 0)));

    vxf::ops::EditOptions set;
    set.set = openvdb::Vec3d(2.0, 1.0, 0.5); // above one is allowed
    set.add = true;
    vxf::ops::edit(*g, selection.get(), set);
    CHECK(g->tree().getValue(openvdb::Coord(5, 0, 0)) == openvdb::Vec3f(2.0f, 1.0f, 0.5f));
    CHECK(g->activeVoxelCount() == 3);

    vxf::ops::EditOptions value;
    value.value = 0.5;
    value.saturation = 0.0;
    vxf::ops::edit(*g, selection.get(), value);
    CHECK(g->tree().getValue(openvdb::Coord(5, 0, 0)) == openvdb::Vec3f(1.0f)); // grey at half the value

    vxf::ops::EditOptions remove;
    remove.remove = true;
    vxf::ops::edit(*g, selection.get(), remove);
    CHECK(g->activeVoxelCount() == 1);
}

TEST_CASE("edit on a float grid: set, scale and offset on the selection, colours refused", "[ops]")
{
    auto g = openvdb::FloatGrid::create(0.0f);
    g->tree().addTile(1, openvdb::Coord(0), 2.0f, true); // 8³ voxels of 2 as one tile
    auto selection = openvdb::BoolGrid::create(false);
    selection->tree().setValueOn(openvdb::Coord(1, 2, 3), true);
    selection->tree().setValueOn(openvdb::Coord(20, 0, 0), true); // inactive in g
    vxf::ops::EditOptions o;
    o.value = 1.5;
    o.offset = -0.25;
    vxf::ops::edit(*g, selection.get(), o);
    CHECK(g->tree().getValue(openvdb::Coord(1, 2, 3)) == 2.75f); // 2·1.5 − 0.25
    CHECK(g->tree().getValue(openvdb::Coord(1, 2, 4)) == 2.0f); // outside the selection: the tile's
    CHECK_FALSE(g->tree().isValueOn(openvdb::Coord(20, 0, 0)));
    CHECK(g->activeVoxelCount() == 512);

    vxf::ops::EditOptions set;
    set.set = openvdb::Vec3d(0.5);
    set.add = true;
    vxf::ops::edit(*g, selection.get(), set);
    CHECK(g->tree().getValue(openvdb::Coord(1, 2, 3)) == 0.5f);
    CHECK(g->tree().getValue(openvdb::Coord(20, 0, 0)) == 0.5f);
    CHECK(g->activeVoxelCount() == 513);

    vxf::ops::EditOptions hue;
    hue.hueShift = 10.0;
    CHECK_THROWS_WITH(vxf::ops::edit(*g, nullptr, hue), Catch::Contains("holds numbers"));
    vxf::ops::EditOptions colour;
    colour.set = openvdb::Vec3d(1.0, 0.0, 0.0);
    CHECK_THROWS_WITH(vxf::ops::edit(*g, nullptr, colour), Catch::Contains("one number"));
    vxf::ops::EditOptions remove;
    remove.remove = true;
    vxf::ops::edit(*g, selection.get(), remove);
    CHECK(g->activeVoxelCount() == 511);
}
