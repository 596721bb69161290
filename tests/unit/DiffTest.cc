#include <vxf/ops/Diff.h>

#include <catch2/catch.hpp>

TEST_CASE("diff holds only the edited voxels, applying it replays the edit, smoothing blends the edge", "[ops]")
{
    auto original = openvdb::FloatGrid::create(0.0f);
    original->tree().fill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(15, 0, 0)), 1.0f, true);
    auto edited = original->deepCopy();
    edited->tree().setValueOn(openvdb::Coord(7, 0, 0), 5.0f);
    edited->tree().setValueOn(openvdb::Coord(30, 0, 0), 2.0f); // added by the artist
    const auto d = vxf::ops::difference(*original, *edited);
    CHECK(d->activeVoxelCount() == 2);
    auto df = openvdb::gridPtrCast<openvdb::FloatGrid>(d);
    CHECK(df->tree().getValue(openvdb::Coord(7, 0, 0)) == 4.0f);
    CHECK(vxf::ops::difference(*original, *edited, 10.0)->activeVoxelCount() == 1); // only the added voxel

    auto replay = original->deepCopy();
    vxf::ops::applyDifference(*replay, *d);
    for (auto it = edited->cbeginValueOn(); it; ++it) REQUIRE(replay->tree().getValue(it.getCoord()) == *it);
    CHECK(replay->activeVoxelCount() == edited->activeVoxelCount());

    auto smooth = original->deepCopy();
    vxf::ops::applyDifferenceSmoothed(*smooth, *d, 2);
    CHECK(smooth->tree().getValue(openvdb::Coord(7, 0, 0)) == 5.0f); // the edit itself stays
    const float near = smooth->tree().getValue(openvdb::Coord(6, 0, 0)), far = smooth->tree().getValue(openvdb::Coord(3, 0, 0));
    CHECK(near > 1.0f); // its neighbours blend toward it
    CHECK(near < 5.0f);
    CHECK(far == 1.0f); // beyond the radius: untouched
}
