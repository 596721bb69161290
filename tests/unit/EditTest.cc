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
