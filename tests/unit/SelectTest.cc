#include <vxf/ops/Select.h>

#include <catch2/catch.hpp>

TEST_CASE("selections by box, sphere and range, remove and include", "[ops]")
{
    auto g = openvdb::FloatGrid::create(0.0f);
    g->setTransform(openvdb::math::Transform::createLinearTransform(0.5));
    for (int i = 0; i < 10; ++i) g->tree().setValueOn(openvdb::Coord(i, 0, 0), float(i));
    auto box = vxf::ops::selectBox(*g, openvdb::BBoxd(openvdb::Vec3d(0.9, -1, -1), openvdb::Vec3d(2.1, 1, 1)));
    CHECK(box->activeVoxelCount() == 3); // x = 1, 1.5, 2 → i = 2, 3, 4
    CHECK(box->tree().isValueOn(openvdb::Coord(2, 0, 0)));
    CHECK(box->transform() == g->transform());
    auto sphere = vxf::ops::selectSphere(*g, openvdb::Vec3d(0.0), 1.0);
    CHECK(sphere->activeVoxelCount() == 3); // i = 0, 1, 2
    auto range = vxf::ops::selectRange(*g, 7.0, 8.5);
    CHECK(range->activeVoxelCount() == 2);

    vxf::ops::removeActive(*g, *range);
    CHECK(g->activeVoxelCount() == 8);
    CHECK_FALSE(g->tree().isValueOn(openvdb::Coord(7, 0, 0)));
    CHECK(g->tree().getValue(openvdb::Coord(7, 0, 0)) == 7.0f); // value kept, inactive
    vxf::ops::includeActive(*g, *range);
    CHECK(g->activeVoxelCount() == 10);
}
