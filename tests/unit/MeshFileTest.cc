#include <vxf/io/MeshFile.h>

#include <vxf/core/Error.h>
#include <vxf/core/ProceduralMesh.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>
#include <fmt/format.h>

using vxf::test::spit;
using vxf::test::TempDir;

namespace {

const char* kCubeOff = "OFF\n8 6 0\n"
                       "-1 -1 -1\n1 -1 -1\n-1 1 -1\n1 1 -1\n-1 -1 1\n1 -1 1\n-1 1 1\n1 1 1\n"
                       "4 0 4 6 2\n4 1 3 7 5\n4 0 1 5 4\n4 2 6 7 3\n4 0 2 3 1\n4 4 5 7 6\n";

bool hasWarning(const vxf::MeshReport& report, const std::string& part)
{
    for (const auto& w : report.warnings) {
        if (w.find(part) != std::string::npos) return true;
    }
    return false;
}

} // namespace

TEST_CASE("meshes read in every supported format", "[io][mesh]")
{
    TempDir dir;
    spit(dir.path("cube.off"), kCubeOff);
    spit(dir.path("cube.obj"),
        "# cube\nv -1 -1 -1\nv 1 -1 -1\nv -1 1 -1\nv 1 1 -1\nv -1 -1 1\nv 1 -1 1\nv -1 1 1\nv 1 1 1\n"
        "f 1 5 7 3\nf 2 4 8 6\nf 1 2 6 5\nf 3 7 8 4\nf 1 3 4 2\nf 5 6 8 7\n");
    spit(dir.path("cube.ply"),
        "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 6\nproperty list uchar int vertex_indices\nend_header\n"
        "-1 -1 -1\n1 -1 -1\n-1 1 -1\n1 1 -1\n-1 -1 1\n1 -1 1\n-1 1 1\n1 1 1\n"
        "4 0 4 6 2\n4 1 3 7 5\n4 0 1 5 4\n4 2 6 7 3\n4 0 2 3 1\n4 4 5 7 6\n");
    {
        // ASCII STL: one facet per triangle, vertices repeated (merged on reading).
        const auto box = vxf::makeBox(openvdb::Vec3d(-1), openvdb::Vec3d(1));
        std::string stl = "solid cube\n";
        for (const auto& t : box.triangles) {
            stl += " facet normal 0 0 0\n  outer loop\n";
            for (int c = 0; c < 3; ++c) {
                const auto& p = box.points[t[c]];
                stl += fmt::format("   vertex {} {} {}\n", p[0], p[1], p[2]);
            }
            stl += "  endloop\n endfacet\n";
        }
        spit(dir.path("cube.stl"), stl + "endsolid cube\n");
    }
    for (const char* name : {"cube.off", "cube.obj", "cube.ply", "cube.stl"}) {
        INFO(name);
        vxf::MeshReport report;
        const vxf::TriangleMesh mesh = vxf::readMesh(dir.path(name), {}, &report);
        CHECK(mesh.triangles.size() == 12);
        CHECK(mesh.points.size() == 8);
        CHECK(mesh.volume() == Approx(8.0));
        CHECK(report.warnings.empty());
        CHECK(report.outwardOriented);
    }
}

TEST_CASE("an inside-out mesh is turned outward", "[io][mesh]")
{
    TempDir dir;
    spit(dir.path("inverted.off"),
        "OFF\n8 6 0\n-1 -1 -1\n1 -1 -1\n-1 1 -1\n1 1 -1\n-1 -1 1\n1 -1 1\n-1 1 1\n1 1 1\n"
        "4 2 6 4 0\n4 5 7 3 1\n4 4 5 1 0\n4 3 7 6 2\n4 1 3 2 0\n4 6 7 5 4\n");
    CHECK(vxf::readMesh(dir.path("inverted.off")).volume() == Approx(8.0));
}

TEST_CASE("mesh defects are repaired or reported, never silent", "[io][mesh]")
{
    TempDir dir;
    SECTION("open mesh: holes filled")
    {
        // The cube without its top face.
        spit(dir.path("open.off"),
            "OFF\n8 5 0\n-1 -1 -1\n1 -1 -1\n-1 1 -1\n1 1 -1\n-1 -1 1\n1 -1 1\n-1 1 1\n1 1 1\n"
            "4 0 4 6 2\n4 1 3 7 5\n4 0 1 5 4\n4 2 6 7 3\n4 0 2 3 1\n");
        vxf::MeshReport report;
        const auto mesh = vxf::readMesh(dir.path("open.off"), {}, &report);
        CHECK(report.holes == 1);
        CHECK(report.borderEdges == 4);
        CHECK(report.holesFilled == 1);
        CHECK(hasWarning(report, "the mesh is open: 1 holes (4 border edges); filled 1"));
        CHECK(mesh.volume() == Approx(8.0));

        vxf::MeshReadOptions keepOpen;
        keepOpen.fillHoles = false;
        vxf::MeshReport openReport;
        vxf::readMesh(dir.path("open.off"), keepOpen, &openReport);
        CHECK(hasWarning(openReport, "left open as asked"));
    }
    SECTION("duplicate points, degenerate and duplicate faces")
    {
        spit(dir.path("dirty.off"),
            "OFF\n10 9 0\n-1 -1 -1\n1 -1 -1\n-1 1 -1\n1 1 -1\n-1 -1 1\n1 -1 1\n-1 1 1\n1 1 1\n"
            "1 1 1\n5 5 5\n"
            "4 0 4 6 2\n4 1 3 7 5\n4 0 1 5 4\n4 2 6 7 3\n4 0 2 3 1\n4 4 5 8 6\n"
            "3 0 0 1\n3 0 1 1\n4 0 4 6 2\n");
        vxf::MeshReport report;
        const auto mesh = vxf::readMesh(dir.path("dirty.off"), {}, &report);
        CHECK(report.mergedPoints == 2); // the duplicate of point 7 and the unused point 9
        CHECK(report.removedPolygons == 3);
        CHECK(hasWarning(report, "removed 3 degenerate or duplicate faces"));
        CHECK(mesh.volume() == Approx(8.0));
    }
    SECTION("non-manifold: two cubes sharing one corner")
    {
        std::string off = "OFF\n15 12 0\n-1 -1 -1\n1 -1 -1\n-1 1 -1\n1 1 -1\n-1 -1 1\n1 -1 1\n-1 1 1\n1 1 1\n"
                          "3 1 1\n1 3 1\n3 3 1\n1 1 3\n3 1 3\n1 3 3\n3 3 3\n"
                          "4 0 4 6 2\n4 1 3 7 5\n4 0 1 5 4\n4 2 6 7 3\n4 0 2 3 1\n4 4 5 7 6\n";
        // Second cube: corner 7 is (1,1,1); its other corners are points 8..14.
        const int c[8] = {7, 8, 9, 10, 11, 12, 13, 14};
        const int quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
        for (const auto& q : quads) off += fmt::format("4 {} {} {} {}\n", c[q[0]], c[q[1]], c[q[2]], c[q[3]]);
        spit(dir.path("pinched.off"), off);
        vxf::MeshReport report;
        const auto mesh = vxf::readMesh(dir.path("pinched.off"), {}, &report);
        CHECK(report.splitPoints == 1);
        CHECK(hasWarning(report, "not manifold"));
        CHECK(mesh.volume() == Approx(16.0));
    }
    SECTION("self-intersecting: two overlapping cubes in one file")
    {
        const auto a = vxf::makeBox(openvdb::Vec3d(-1), openvdb::Vec3d(1));
        const auto b = vxf::makeBox(openvdb::Vec3d(0), openvdb::Vec3d(2));
        std::string off = "OFF\n16 24 0\n";
        for (const auto* m : {&a, &b})
            for (const auto& p : m->points) off += fmt::format("{} {} {}\n", p[0], p[1], p[2]);
        for (int m = 0; m < 2; ++m)
            for (const auto& t : (m ? b : a).triangles) off += fmt::format("3 {} {} {}\n", t[0] + 8 * m, t[1] + 8 * m, t[2] + 8 * m);
        spit(dir.path("overlap.off"), off);
        vxf::MeshReport report;
        vxf::readMesh(dir.path("overlap.off"), {}, &report);
        CHECK(report.selfIntersecting);
        CHECK(hasWarning(report, "intersects itself"));

        vxf::MeshReport separate;
        vxf::checkSelfIntersections(a, separate);
        CHECK_FALSE(separate.selfIntersecting);
    }
}

TEST_CASE("unreadable meshes give errors naming the file", "[io][mesh]")
{
    TempDir dir;
    CHECK_THROWS_WITH(vxf::readMesh(dir.path("missing.off")), Catch::EndsWith("missing.off: no such file"));
    spit(dir.path("mesh.xyz"), "1 2 3\n");
    CHECK_THROWS_WITH(vxf::readMesh(dir.path("mesh.xyz")), Catch::Contains("unsupported mesh format '.xyz'"));
    spit(dir.path("garbage.off"), "this is not an OFF file\n");
    CHECK_THROWS_WITH(vxf::readMesh(dir.path("garbage.off")), Catch::Contains("garbage.off: cannot parse mesh"));
    spit(dir.path("flat.off"), "OFF\n3 2 0\n0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n3 0 0 0\n");
    CHECK_THROWS_WITH(vxf::readMesh(dir.path("flat.off")), Catch::Contains("no usable faces"));
}
