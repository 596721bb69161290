#include <vxf/ops/Paint.h>

#include <vxf/core/Error.h>

#include <catch2/catch.hpp>

#include <cmath>

namespace {

/// A block of 21³ active voxels of @a value, voxel size 0.1, centred on the origin.
template <typename GridT>
typename GridT::Ptr block(typename GridT::ValueType value)
{
    auto g = GridT::create(typename GridT::ValueType(0));
    g->setTransform(openvdb::math::Transform::createLinearTransform(0.1));
    g->tree().fill(openvdb::CoordBBox(openvdb::Coord(-10), openvdb::Coord(10)), value, true);
    return g;
}

} // namespace

TEST_CASE("paint: a stroke mixes toward its value by (1 − (d/r)²)^falloff, each voxel once, inside the radius only", "[ops]")
{
    auto g = block<openvdb::FloatGrid>(1.0f);
    vxf::ops::PaintOptions o;
    o.points = {openvdb::Vec3d(0.0), openvdb::Vec3d(0.0), openvdb::Vec3d(0.05, 0.0, 0.0)}; // the centre twice: painted once
    o.radius = 0.35;
    o.falloff = 2.0;
    o.strength = 0.5;
    o.value = openvdb::Vec3d(3.0);
    const std::uint64_t painted = vxf::ops::paint(*g, o);
    // Voxels within 0.35 of either point: the largest weight of the two.
    std::uint64_t within = 0;
    for (auto it = g->cbeginValueOn(); it; ++it) {
        const openvdb::Vec3d x = g->transform().indexToWorld(it.getCoord());
        double w = 0.0;
        bool inside = false;
        for (const auto& p : o.points) {
            const double d2 = (x - p).lengthSqr();
            if (d2 > o.radius * o.radius) continue;
            inside = true;
            w = std::max(w, 0.5 * std::pow(1.0 - d2 / (o.radius * o.radius), 2.0));
        }
        within += inside ? 1 : 0;
        INFO(it.getCoord());
        REQUIRE(*it == Approx(1.0 + w * (3.0 - 1.0)).epsilon(1e-6));
    }
    CHECK(painted == within);
    CHECK(g->tree().getValue(openvdb::Coord(0)) == Approx(2.0)); // the centre: half way to 3
    CHECK(g->activeVoxelCount() == 21 * 21 * 21); // paint adds no voxels

    // Add mode on colours, a hard brush: + value inside, nothing outside.
    auto c = block<openvdb::Vec3SGrid>(openvdb::Vec3f(0.1f, 0.2f, 0.3f));
    vxf::ops::PaintOptions add;
    add.points = {openvdb::Vec3d(0.5, 0.5, 0.5)};
    add.radius = 0.2;
    add.falloff = 0.0;
    add.value = openvdb::Vec3d(1.0, 0.0, 0.0);
    add.mode = vxf::ops::PaintMode::Add;
    vxf::ops::paint(*c, add);
    CHECK(c->tree().getValue(openvdb::Coord(5, 5, 5)) == openvdb::Vec3f(1.1f, 0.2f, 0.3f));
    CHECK(c->tree().getValue(openvdb::Coord(5, 5, 3)) == openvdb::Vec3f(1.1f, 0.2f, 0.3f)); // 0.2 away: on the edge
    CHECK(c->tree().getValue(openvdb::Coord(5, 5, 2)) == openvdb::Vec3f(0.1f, 0.2f, 0.3f));

    vxf::ops::PaintOptions bad = o;
    bad.points.clear();
    CHECK_THROWS_AS(vxf::ops::paint(*g, bad), vxf::UsageError);
    bad = o;
    bad.strength = 1.5;
    CHECK_THROWS_WITH(vxf::ops::paint(*g, bad), Catch::Contains("strength"));
    bad = o;
    bad.radius = 0.0;
    CHECK_THROWS_WITH(vxf::ops::paint(*g, bad), Catch::Contains("radius"));
}
