#include <vxf/pipeline/SceneMedium.h>

#include <vxf/core/Error.h>
#include <vxf/io/VoxelSetFile.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/LevelSetUtil.h>

#include <cmath>
#include <string>
#include <tuple>

namespace {

vxf::Scene twoSpheres(const std::string& second)
{
    return vxf::parseScene(R"({
      "objects": [
        {"name": "red", "mesh": "builtin:sphere", "transform": {"translate": [-1.5, 0, 0]},
         "material": {"sigma_a": [1, 0, 0], "sigma_s": [2, 2, 2]}},
        {"name": "blue", "mesh": "builtin:sphere", "transform": {"translate": [)" +
            second + R"(, 0, 0]},
         "material": {"sigma_a": [0, 0, 3], "sigma_s": [4, 4, 4]}},
        {"name": "wall", "mesh": "builtin:box", "role": "occluder", "transform": {"translate": [0, 5, 0]}}
      ],
      "lights": [],
      "camera": {"position": [0, -5, 0], "look_at": [0, 0, 0]}
    })",
        "two.json");
}

openvdb::Vec3f at(const vxf::VoxelSet& set, const char* grid, const openvdb::Vec3d& world)
{
    auto g = set.get<openvdb::Vec3SGrid>(grid);
    return g->tree().getValue(openvdb::Coord::round(g->transform().worldToIndex(world)));
}

} // namespace

TEST_CASE("several media share one lattice, each keeping its material, overlaps add", "[scene][voxelize]")
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
            "grids": {"file": ")" +
                file + R"(", "sigma_a": ")" + grid + R"("}}}], "lights": [],
            "camera": {"position": [0, -5, 0], "look_at": [0, 0, 0]}})",
            dir.path("s.json"));
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

    CHECK_THROWS_WITH(
        vxf::voxelizeMedia(scene("missing"), options), Catch::Contains("coefficients.vdb") && Catch::Contains("no grid named 'missing'"));
    CHECK_THROWS_WITH(vxf::voxelizeMedia(scene("not_a_vector"), options), Catch::Contains("needs vec3s"));
}

TEST_CASE("a volume object's grid is the medium, on its own voxels, level sets and missing grids are refused", "[scene][voxelize][volume]")
{
    // A fog sphere (OpenVDB's level set sphere made a fog volume) as a simulation would write
    // it, beside a temperature grid; the same sphere as a level set in another file.
    vxf::test::TempDir dir;
    auto sdf = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(1.0f, openvdb::Vec3f(0.0f), 0.1f);
    auto fog = sdf->deepCopy();
    openvdb::tools::sdfToFogVolume(*fog);
    fog->setName("density");
    auto temperature = fog->deepCopy();
    temperature->setName("temperature");
    openvdb::io::File(dir.path("smoke.vdb")).write({fog, temperature});
    sdf->setName("density");
    openvdb::io::File(dir.path("sphere.vdb")).write({sdf});

    const auto scene = [&](const std::string& object) {
        return vxf::parseScene(R"({"objects": [)" + object + R"(], "lights": [],
          "camera": {"position": [0, -5, 0], "look_at": [0, 0, 0]}})",
            dir.path("scene.json"));
    };
    const std::string material = R"("material": {"sigma_a": [1, 1, 1], "sigma_s": [2, 2, 2]})";
    const vxf::VoxelizeOptions options; // no voxel size or dim: the grid's own voxels

    const vxf::VoxelSet set = vxf::voxelizeMedia(scene(R"({"volume": "smoke.vdb", )" + material + "}"), options);
    CHECK_FALSE(set.find("surface"));
    const auto density = set.get<openvdb::FloatGrid>("density");
    CHECK(density->getGridClass() == openvdb::GRID_FOG_VOLUME);
    CHECK(density->voxelSize()[0] == Approx(0.1));
    CHECK(density->activeVoxelCount() == fog->activeVoxelCount());
    const auto world = [](const openvdb::FloatGrid& g, const openvdb::Vec3d& x) {
        return openvdb::tools::BoxSampler::sample(g.tree(), g.transform().worldToIndex(x));
    };
    CHECK(world(*density, {0.0, 0.0, 0.0}) == Approx(1.0f));
    CHECK(world(*density, {0.0, 0.0, 1.2}) == 0.0f);

    // Moved by the object's transform: translated as it is, turned by resampling.
    const vxf::VoxelSet moved =
        vxf::voxelizeMedia(scene(R"({"volume": "smoke.vdb", "transform": {"translate": [3, 0, 0]}, )" + material + "}"), options);
    CHECK(world(*moved.get<openvdb::FloatGrid>("density"), {3.0, 0.0, 0.0}) == Approx(1.0f));
    CHECK(world(*moved.get<openvdb::FloatGrid>("density"), {0.0, 0.0, 0.0}) == 0.0f);
    const vxf::VoxelSet turned = vxf::voxelizeMedia(
        scene(R"({"volume": "smoke.vdb", "grid": "temperature", "transform": {"rotate": [0, 0, 30], "scale": 2}, )" + material + "}"),
        options);
    const auto t = turned.get<openvdb::FloatGrid>("density");
    CHECK(t->voxelSize()[0] == Approx(0.2));
    CHECK(world(*t, {0.0, 0.0, 0.0}) == Approx(1.0f));
    CHECK(world(*t, {0.0, 0.8, 0.0}) == Approx(1.0f)); // inside the sphere, now of radius 2
    CHECK(world(*t, {0.0, 1.5, 0.0}) == Approx(0.25f / 0.3f).epsilon(0.05)); // in its fog ramp: −φ/(3 voxels of 0.1)
    CHECK(world(*t, {0.0, 0.0, 2.3}) == 0.0f);

    const auto refused = [&](const std::string& object) {
        try {
            vxf::voxelizeMedia(scene(object), options);
        } catch (const vxf::Error& e) {
            return std::string(e.what());
        }
        return std::string("(accepted)");
    };
    const std::string missing = refused(R"({"volume": "smoke.vdb", "grid": "heat", )" + material + "}");
    CHECK_THAT(missing, Catch::Contains("smoke.vdb") && Catch::Contains("no grid named 'heat'") && Catch::Contains("density, temperature"));
    CHECK_THAT(refused(R"({"volume": "sphere.vdb", )" + material + "}"), Catch::Contains("sphere.vdb") && Catch::Contains("level set"));
    CHECK_THAT(refused(R"({"volume": "nothing.vdb", )" + material + "}"), Catch::Contains("nothing.vdb"));
    CHECK_THAT(refused(R"({"volume": "smoke.vdb", )" + material + R"(}, {"mesh": "builtin:sphere", )" + material + "}"),
        Catch::Contains("only medium"));
}

TEST_CASE(
    "a volume object asked for a voxel size or dim is coarsened by halvings, its mass kept, never refined", "[scene][voxelize][volume]")
{
    // A fog sphere of radius 1 on voxels of 0.05 (about 40 across), off the origin.
    vxf::test::TempDir dir;
    auto fog = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(1.0f, openvdb::Vec3f(0.3f, -0.2f, 0.1f), 0.05f);
    openvdb::tools::sdfToFogVolume(*fog);
    fog->setName("density");
    openvdb::io::File(dir.path("smoke.vdb")).write({fog});
    const vxf::Scene scene = vxf::parseScene(R"({"objects": [{"volume": "smoke.vdb",
          "material": {"sigma_a": [1, 1, 1], "sigma_s": [2, 2, 2]}}], "lights": [],
          "camera": {"position": [0, -5, 0], "look_at": [0, 0, 0]}})",
        dir.path("scene.json"));
    CHECK(scene.settings.dim == 0); // no default dim applies to a volume
    const auto moments = [](const openvdb::FloatGrid& g) { // mass Σ density·dx³ and its centroid
        double mass = 0.0;
        openvdb::Vec3d moment(0.0);
        const double cell = std::pow(g.voxelSize()[0], 3);
        for (auto it = g.cbeginValueOn(); it; ++it) {
            const double m = double(*it) * cell * double(it.getVoxelCount());
            mass += m;
            moment += m * g.indexToWorld(it.getBoundingBox().getCenter());
        }
        return std::pair{mass, moment / mass};
    };
    const auto [mass, centroid] = moments(*fog);
    CHECK(mass == Approx(4.0 / 3.0 * M_PI * std::pow(0.925, 3)).epsilon(0.02)); // its fog ramps to 1 over 3 voxels inside

    const auto solved = [&](double voxelSize, int dim, std::string* note) {
        vxf::VoxelizeOptions options;
        options.voxelSize = voxelSize;
        options.dim = dim;
        return vxf::voxelizeMedia(scene, options, nullptr, note).get<openvdb::FloatGrid>("density");
    };
    std::string note;
    for (const auto& [voxelSize, dim, expected] : {std::tuple{0.1, 0, 0.1}, {0.0, 20, 0.1}, {0.0, 12, 0.2}, {0.17, 0, 0.2}}) {
        INFO("voxel_size " << voxelSize << ", dim " << dim);
        const auto coarse = solved(voxelSize, dim, &note);
        CHECK(coarse->voxelSize()[0] == Approx(expected));
        CHECK(coarse->getGridClass() == openvdb::GRID_FOG_VOLUME);
        const auto [m, c] = moments(*coarse);
        CHECK(m == Approx(mass).epsilon(1e-4)); // full weighting keeps the mass
        CHECK((c - centroid).length() < 1e-3 * expected); // and where it is
        CHECK(openvdb::tools::BoxSampler::sample(coarse->tree(), coarse->worldToIndex({0.3, -0.2, 0.1})) == Approx(1.0f));
        CHECK_THAT(note, Catch::Contains("coarsened " + std::to_string(int(std::lround(expected / 0.05))) + "x"));
    }
    // Asked finer than (or about) its own: its own voxels, and the note says a volume is not refined.
    const auto own = solved(0.03, 0, &note);
    CHECK(own->voxelSize()[0] == Approx(0.05));
    CHECK(own->activeVoxelCount() == fog->activeVoxelCount());
    CHECK_THAT(note, Catch::Contains("never refined"));
}
