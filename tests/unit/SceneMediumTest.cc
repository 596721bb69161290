#include <vxf/pipeline/SceneMedium.h>

#include <vxf/io/VoxelSetFile.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

namespace {

vxf::Scene twoSpheres(const std::string& second)
{
    return vxf::parseScene(R"({
      "objects": [
        {"name": "red", "mesh": "builtin:sphere", "transform": {"translate": [-1.5, 0, 0]},
         "material": {"sigma_a": [1, 0, 0], "sigma_s": [2, 2, 2]}},
        {"name": "blue", "mesh": "builtin:sphere", "transform": {"translate": [)" + second + R"(, 0, 0]},
         "material": {"sigma_a": [0, 0, 3], "sigma_s": [4, 4, 4]}},
        {"name": "wall", "mesh": "builtin:box", "role": "occluder", "transform": {"translate": [0, 5, 0]}}
      ],
      "lights": [],
      "camera": {"position": [0, -5, 0], "look_at": [0, 0, 0]}
    })", "two.json");
}

openvdb::Vec3f at(const vxf::VoxelSet& set, const char* grid, const openvdb::Vec3d& world)
{
    auto g = set.get<openvdb::Vec3SGrid>(grid);
    return g->tree().getValue(openvdb::Coord::round(g->transform().worldToIndex(world)));
}

} // namespace

TEST_CASE("several media share one lattice, each keeping its material; overlaps add", "[scene][voxelize]")
{
    vxf::VoxelizeOptions options;
    options.dim = 64;
    const vxf::Scene apart = twoSpheres("1.5");
    CHECK(vxf::mediaCount(apart) == 2);
    const vxf::VoxelSet set = vxf::voxelizeMedia(apart, options);
    // dim counts voxels along the joint bounds: x spans [-2.5, 2.5].
    CHECK(set.transform().voxelSize()[0] == Approx(5.0 / 64.0));
    CHECK(at(set, "sigma_a", {-1.5, 0, 0}) == openvdb::Vec3f(1, 0, 0));
    CHECK(at(set, "sigma_s", {-1.5, 0, 0}) == openvdb::Vec3f(2, 2, 2));
    CHECK(at(set, "sigma_a", {1.5, 0, 0}) == openvdb::Vec3f(0, 0, 3));
    CHECK(at(set, "sigma_s", {1.5, 0.3, 0}) == openvdb::Vec3f(4, 4, 4));
    CHECK(at(set, "sigma_a", {0, 0, 0}) == openvdb::Vec3f(0, 0, 0)); // between them: nothing
    auto surface = set.get<openvdb::FloatGrid>("surface");
    const auto inside = [&](const openvdb::Vec3d& w) {
        return surface->tree().getValue(openvdb::Coord::round(surface->transform().worldToIndex(w))) < 0.0f;
    };
    CHECK(inside({-1.5, 0, 0}));
    CHECK(inside({1.5, 0, 0}));
    CHECK_FALSE(inside({0, 0, 0}));
    CHECK_FALSE(inside({0, 5, 0})); // occluders are not medium
    // The scene's planning material is the per-channel maximum.
    const vxf::Material planning = vxf::sceneMaterial(apart);
    CHECK(planning.sigmaA == openvdb::Vec3d(1, 0, 3));
    CHECK(planning.sigmaS == openvdb::Vec3d(4, 4, 4));

    // Overlapping spheres: the coefficients of superposed media add; density stays ≤ 1.
    const vxf::VoxelSet overlap = vxf::voxelizeMedia(twoSpheres("-1.0"), options);
    CHECK(at(overlap, "sigma_a", {-1.25, 0, 0}) == openvdb::Vec3f(1, 0, 3));
    auto density = overlap.get<openvdb::FloatGrid>("density");
    float highest = 0.0f;
    for (auto it = density->cbeginValueOn(); it; ++it) highest = std::max(highest, *it);
    CHECK(highest == 1.0f);
}

TEST_CASE("a material's per-voxel coefficient grids are read and resampled onto the lattice", "[scene][voxelize]")
{
    vxf::test::TempDir dir;
    // A coarser grid of constant absorption, on another transform.
    vxf::VoxelSet coefficients(openvdb::math::Transform::createLinearTransform(0.25));
    auto absorb = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    absorb->setName("absorb");
    absorb->setTransform(coefficients.transformPtr());
    absorb->tree().fill(openvdb::CoordBBox(openvdb::Coord(-8), openvdb::Coord(8)), openvdb::Vec3f(0.5f, 1.5f, 2.5f), true);
    coefficients.put(absorb);
    auto label = openvdb::FloatGrid::create();
    label->setName("not_a_vector");
    label->setTransform(coefficients.transformPtr());
    coefficients.put(label);
    const std::string file = dir.path("coefficients.vdb");
    vxf::writeVoxelSet(file, coefficients);

    const auto scene = [&](const std::string& grid) {
        return vxf::parseScene(R"({"objects": [{"mesh": "builtin:sphere", "material": {"sigma_a": 1, "sigma_s": 1,
            "grids": {"file": ")" + file + R"(", "sigma_a": ")" + grid + R"("}}}], "lights": [],
            "camera": {"position": [0, -5, 0], "look_at": [0, 0, 0]}})", dir.path("s.json"));
    };
    vxf::VoxelizeOptions options;
    options.dim = 40;
    const vxf::VoxelSet set = vxf::voxelizeMedia(scene("absorb"), options);
    REQUIRE(set.find("sigma_a"));
    CHECK(set.find("sigma_a")->transform() == set.transform());
    const openvdb::Vec3f inside = at(set, "sigma_a", {0.1, 0.2, -0.3});
    CHECK(inside[0] == Approx(0.5f));
    CHECK(inside[2] == Approx(2.5f));
    CHECK_FALSE(set.find("sigma_s")); // not given: density × the material's sigma_s

    CHECK_THROWS_WITH(vxf::voxelizeMedia(scene("missing"), options),
        Catch::Contains("coefficients.vdb") && Catch::Contains("no grid named 'missing'"));
    CHECK_THROWS_WITH(vxf::voxelizeMedia(scene("not_a_vector"), options), Catch::Contains("needs vec3s"));
}
