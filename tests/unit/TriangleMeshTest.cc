// A triangle mesh's bounds and signed volume (vxf/core/TriangleMesh.h), by the built-in meshes.
#include <vxf/core/TriangleMesh.h>

#include <vxf/core/ProceduralMesh.h>

#include <catch2/catch.hpp>

#include <cmath>

TEST_CASE("a closed mesh's volume is signed by its orientation and its bounds hold every point", "[core][mesh]")
{
    auto box = vxf::builtinMesh("builtin:box");
    REQUIRE(box);
    const openvdb::BBoxd bounds = box->bounds();
    const openvdb::Vec3d extent = bounds.extents();
    CHECK(box->volume() == Approx(extent.x() * extent.y() * extent.z()));
    for (const auto& p : box->points) CHECK(bounds.isInside(p));

    for (auto& t : box->triangles) std::swap(t[1], t[2]); // turned inside out
    CHECK(box->volume() == Approx(-extent.x() * extent.y() * extent.z()));

    auto sphere = vxf::builtinMesh("builtin:sphere");
    REQUIRE(sphere);
    const double r = 0.5 * sphere->bounds().extents().x();
    const double exact = 4.0 / 3.0 * M_PI * r * r * r;
    CHECK(sphere->volume() < exact); // a tessellated sphere lies inside the round one
    CHECK(sphere->volume() > 0.95 * exact);

    const vxf::TriangleMesh empty;
    CHECK(empty.volume() == 0.0);
}
