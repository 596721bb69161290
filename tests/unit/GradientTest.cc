#include <vxf/ops/Gradient.h>

#include <vxf/core/Error.h>

#include <catch2/catch.hpp>

TEST_CASE("gradients: directional, radial, surface distance and multi-stop ramps, exactly", "[ops]")
{
    auto topology = openvdb::FloatGrid::create(0.0f);
    topology->setTransform(openvdb::math::Transform::createLinearTransform(0.1));
    for (int i = 0; i <= 10; ++i) topology->tree().setValueOn(openvdb::Coord(i, 0, 0), 1.0f);
    vxf::ops::GradientOptions o;
    o.from = openvdb::Vec3d(0.0);
    o.to = openvdb::Vec3d(1.0, 0.0, 0.0);
    o.stops = {{0.0, openvdb::Vec3d(0.0)}, {1.0, openvdb::Vec3d(1.0, 2.0, 4.0)}};
    auto g = vxf::ops::gradient(*topology, nullptr, o);
    CHECK(g->activeVoxelCount() == 11);
    CHECK(g->tree().getValue(openvdb::Coord(5, 0, 0))[2] == Approx(2.0f));
    CHECK(g->tree().getValue(openvdb::Coord(10, 0, 0)) == openvdb::Vec3f(1, 2, 4));

    o.kind = vxf::ops::GradientKind::Radial;
    o.centre = openvdb::Vec3d(0.0);
    o.radius = 0.5;
    o.falloff = 2.0;
    g = vxf::ops::gradient(*topology, nullptr, o);
    CHECK(g->tree().getValue(openvdb::Coord(2, 0, 0))[0] == Approx(0.16f)); // (0.2/0.5)²
    CHECK(g->tree().getValue(openvdb::Coord(9, 0, 0))[0] == 1.0f); // clamped beyond the radius

    CHECK(vxf::ops::rampColor({{0.0, openvdb::Vec3d(0)}, {0.5, openvdb::Vec3d(1)}, {1.0, openvdb::Vec3d(0)}}, 0.75)[0] == Approx(0.5));

    auto surface = openvdb::FloatGrid::create(0.3f);
    surface->setTransform(topology->transformPtr());
    surface->setGridClass(openvdb::GRID_LEVEL_SET);
    for (int i = 0; i <= 10; ++i) surface->tree().setValueOn(openvdb::Coord(i, 0, 0), -0.02f * float(i));
    o.kind = vxf::ops::GradientKind::SurfaceDistance;
    o.distance = 0.1;
    g = vxf::ops::gradient(*topology, surface.get(), o);
    CHECK(g->tree().getValue(openvdb::Coord(3, 0, 0))[0] == Approx(0.6f)); // depth 0.06 of 0.1
    CHECK_THROWS_AS(vxf::ops::gradient(*topology, nullptr, o), vxf::UsageError);
    o.stops.pop_back();
    CHECK_THROWS_WITH(vxf::ops::gradient(*topology, surface.get(), o), Catch::Contains("at least two colours"));
}
