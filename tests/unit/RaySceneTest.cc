#include <vxf/core/ProceduralMesh.h>
#include <vxf/core/RayScene.h>

#include <catch2/catch.hpp>

TEST_CASE("Embree ray scene: closest hits with outward normals and ids, occlusion within a segment", "[rayscene]")
{
    vxf::RayScene scene;
    CHECK(scene.empty());
    scene.add(vxf::makeBox(openvdb::Vec3d(-1.0), openvdb::Vec3d(1.0)), 7);
    vxf::TriangleMesh far = vxf::makeBox(openvdb::Vec3d(4.0, -1.0, -1.0), openvdb::Vec3d(5.0, 1.0, 1.0));
    scene.add(far, 9);
    scene.commit();
    CHECK_FALSE(scene.empty());

    const auto front = scene.intersect(openvdb::Vec3d(-3, 0.1, 0.2), openvdb::Vec3d(1, 0, 0));
    REQUIRE(front);
    CHECK(front->distance == Approx(2.0));
    CHECK(front->id == 7);
    CHECK_FALSE(front->backFace);
    CHECK((front->normal - openvdb::Vec3d(-1, 0, 0)).length() < 1e-6);

    // From inside: the back face, normal still facing the ray's origin.
    const auto inside = scene.intersect(openvdb::Vec3d(0.0, 0.1, 0.2), openvdb::Vec3d(1, 0, 0));
    REQUIRE(inside);
    CHECK(inside->distance == Approx(1.0));
    CHECK(inside->backFace);
    CHECK((inside->normal - openvdb::Vec3d(-1, 0, 0)).length() < 1e-6);

    // Past the first box, the second one.
    const auto next = scene.intersect(openvdb::Vec3d(-3, 0.1, 0.2), openvdb::Vec3d(1, 0, 0), 4.5);
    REQUIRE(next);
    CHECK(next->id == 9);
    CHECK(next->distance == Approx(7.0));

    CHECK_FALSE(scene.intersect(openvdb::Vec3d(-3, 5, 0), openvdb::Vec3d(1, 0, 0)));
    CHECK(scene.occluded(openvdb::Vec3d(-3, 0, 0), openvdb::Vec3d(1, 0, 0), 0.0, 2.5));
    CHECK_FALSE(scene.occluded(openvdb::Vec3d(-3, 0, 0), openvdb::Vec3d(1, 0, 0), 0.0, 1.5));
}

TEST_CASE("Embree ray scene keeps precision 1e5 units from the origin", "[rayscene][stability]")
{
    const openvdb::Vec3d offset(1e5, -1e5, 1e5);
    vxf::TriangleMesh box = vxf::makeBox(openvdb::Vec3d(-0.01), openvdb::Vec3d(0.01));
    for (auto& p : box.points) p += offset;
    vxf::RayScene scene;
    scene.add(box, 0);
    scene.commit();
    const auto hit = scene.intersect(offset + openvdb::Vec3d(0, 0, 1), openvdb::Vec3d(0, 0, -1));
    REQUIRE(hit);
    CHECK(hit->distance == Approx(0.99).epsilon(1e-5));
}
