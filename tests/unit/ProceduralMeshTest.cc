#include <vxf/core/ProceduralMesh.h>

#include <catch2/catch.hpp>

#include <map>

namespace {
/// Every undirected edge used by exactly two triangles, once in each direction.
bool closedAndConsistent(const vxf::TriangleMesh& mesh)
{
    std::map<std::pair<unsigned, unsigned>, int> directed;
    for (const auto& t : mesh.triangles) {
        for (int i = 0; i < 3; ++i) ++directed[{t[i], t[(i + 1) % 3]}];
    }
    for (const auto& [edge, count] : directed) {
        if (count != 1) return false;
        auto twin = directed.find({edge.second, edge.first});
        if (twin == directed.end() || twin->second != 1) return false;
    }
    return true;
}
} // namespace

TEST_CASE("procedural meshes are closed, consistent and outward", "[core][mesh]")
{
    const auto box = vxf::makeBox(openvdb::Vec3d(-1, -2, -3), openvdb::Vec3d(1, 2, 3));
    CHECK(box.triangles.size() == 12);
    CHECK(closedAndConsistent(box));
    CHECK(box.volume() == Approx(2 * 4 * 6).epsilon(1e-12));

    const auto sphere = vxf::makeSphere(openvdb::Vec3d(5, 0, 0), 2.0, 64, 128);
    CHECK(closedAndConsistent(sphere));
    // A polyhedron inscribed in the sphere: slightly smaller than 4/3 pi r^3.
    const double exact = 4.0 / 3.0 * M_PI * 8.0;
    CHECK(sphere.volume() < exact);
    CHECK(sphere.volume() == Approx(exact).epsilon(2e-3));
    CHECK(sphere.bounds().getCenter().x() == Approx(5.0));

    const auto candle = vxf::makeCandle();
    CHECK(closedAndConsistent(candle));
    CHECK(candle.volume() > 0.9 * M_PI * 3.0 * 0.95);
    CHECK(candle.volume() < M_PI * 3.0);

    // The flame r(u) = k√u(1 − u)^1.2 holds π k² B(2, 3.4) = π k² / (3.4 · 4.4).
    const auto flame = vxf::makeFlame();
    CHECK(closedAndConsistent(flame));
    const openvdb::BBoxd bounds = flame.bounds();
    CHECK(bounds.min().z() == 0.0);
    CHECK(bounds.max().z() == 1.0);
    CHECK(bounds.max().x() == Approx(0.22).epsilon(0.01));
    const double k = 0.22 / (std::sqrt(0.5 / 1.7) * std::pow(1.2 / 1.7, 1.2));
    CHECK(flame.volume() == Approx(M_PI * k * k / (3.4 * 4.4)).epsilon(0.03));
}

TEST_CASE("built-in meshes are found by name", "[core][mesh]")
{
    for (const auto& name : vxf::builtinMeshNames()) {
        INFO(name);
        auto mesh = vxf::builtinMesh(name);
        REQUIRE(mesh);
        CHECK(mesh->volume() > 0.0);
    }
    CHECK_FALSE(vxf::builtinMesh("builtin:teapot"));
    CHECK_FALSE(vxf::builtinMesh("candle"));
}
