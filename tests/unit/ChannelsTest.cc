#include <vxf/ops/Channels.h>

#include <vxf/core/Error.h>

#include <catch2/catch.hpp>

TEST_CASE("split a vec3s grid into channels and merge them back exactly", "[ops]")
{
    auto g = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    g->setName("Cd");
    g->tree().setValueOn(openvdb::Coord(1, 2, 3), openvdb::Vec3f(-1.5f, 2.0f, 7.25f));
    g->tree().addTile(1, openvdb::Coord(64), openvdb::Vec3f(0.5f, 0.25f, 0.125f), true);
    const auto parts = vxf::ops::splitChannels(*g);
    CHECK(parts[0]->getName() == "Cd.x");
    CHECK(parts[2]->getName() == "Cd.z");
    CHECK(parts[1]->tree().getValue(openvdb::Coord(1, 2, 3)) == 2.0f);
    CHECK(parts[0]->activeVoxelCount() == g->activeVoxelCount());
    CHECK(parts[2]->tree().getValueDepth(openvdb::Coord(64)) == g->tree().getValueDepth(openvdb::Coord(64))); // tile kept
    const auto merged = vxf::ops::mergeChannels(*parts[0], *parts[1], *parts[2], "Cd");
    CHECK(merged->activeVoxelCount() == g->activeVoxelCount());
    for (auto it = g->cbeginValueOn(); it; ++it) REQUIRE(merged->tree().getValue(it.getCoord()) == *it);

    auto other = parts[1]->deepCopy();
    other->setTransform(openvdb::math::Transform::createLinearTransform(2.0));
    CHECK_THROWS_AS(vxf::ops::mergeChannels(*parts[0], *other, *parts[2], "bad"), vxf::UsageError);
}
