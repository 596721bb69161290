#include <vxf/voxelize/Voxelize.h>

#include <vxf/core/ProceduralMesh.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/LevelSetMeasure.h>
#include <tbb/global_control.h>

namespace {

vxf::VoxelizeOptions withDim(int dim)
{
    vxf::VoxelizeOptions options;
    options.dim = dim;
    return options;
}

double signedDistanceAt(const openvdb::FloatGrid& grid, const openvdb::Vec3d& world)
{
    return openvdb::tools::BoxSampler::sample(grid.tree(), grid.transform().worldToIndex(world));
}

} // namespace

TEST_CASE("voxelizing a sphere: enclosed volume and signed distances", "[voxelize]")
{
    const auto mesh = vxf::makeSphere(openvdb::Vec3d(0.0), 1.0, 128, 256);
    const vxf::VoxelSet set = vxf::voxelize(mesh, withDim(128));
    auto surface = set.get<openvdb::FloatGrid>("surface");
    const double dx = set.transform().voxelSize()[0];
    CHECK(dx == Approx(2.0 / 128.0));
    CHECK(surface->getGridClass() == openvdb::GRID_LEVEL_SET);
    CHECK(surface->background() == Approx(3.0 * dx));

    // Enclosed volume against the exact volume of the polyhedron (and of the sphere).
    const double volume = openvdb::tools::levelSetVolume(*surface);
    CHECK(volume == Approx(mesh.volume()).epsilon(0.01));
    CHECK(volume == Approx(4.0 / 3.0 * M_PI).epsilon(0.01));

    // Signed distance |p| - r at known points, to a tenth of a voxel.
    for (double offset : {-2.5, -1.0, -0.25, 0.0, 0.5, 2.0}) {
        for (const openvdb::Vec3d direction : {openvdb::Vec3d(1, 0, 0), openvdb::Vec3d(0, -1, 0), openvdb::Vec3d(1, 1, 1).unitSafe(),
                 openvdb::Vec3d(-0.3, 0.8, -0.52).unitSafe()}) {
            const double r = 1.0 + offset * dx;
            INFO("offset " << offset << " voxels, direction " << direction);
            CHECK(signedDistanceAt(*surface, direction * r) == Approx(offset * dx).margin(0.1 * dx));
        }
    }
    // Outside the band: the background, with the right sign.
    CHECK(surface->tree().getValue(openvdb::Coord(0)) == Approx(-3.0 * dx));
    CHECK(surface->tree().getValue(openvdb::Coord(100, 0, 0)) == Approx(3.0 * dx));
}

TEST_CASE("voxelizing a box: volume, faces and interior tiles", "[voxelize]")
{
    // Faces off the voxel lattice so the sampling is not trivially aligned.
    const auto mesh = vxf::makeBox(openvdb::Vec3d(-1.013, -0.77, -0.5), openvdb::Vec3d(1.1, 0.9, 0.61));
    const vxf::VoxelSet set = vxf::voxelize(mesh, withDim(128));
    auto surface = set.get<openvdb::FloatGrid>("surface");
    auto density = set.get<openvdb::FloatGrid>("density");
    const double dx = set.transform().voxelSize()[0];
    CHECK(openvdb::tools::levelSetVolume(*surface) == Approx(mesh.volume()).epsilon(0.01));
    CHECK(signedDistanceAt(*surface, openvdb::Vec3d(1.1 - 1.5 * dx, 0.1, 0.0)) == Approx(-1.5 * dx).margin(0.05 * dx));
    CHECK(signedDistanceAt(*surface, openvdb::Vec3d(0.2, 0.9 + 2.0 * dx, 0.0)) == Approx(2.0 * dx).margin(0.05 * dx));

    // density: a fog volume, 1 inside kept as active tiles (never a dense interior), 0 outside.
    CHECK(density->getGridClass() == openvdb::GRID_FOG_VOLUME);
    CHECK(density->background() == 0.0f);
    CHECK(density->tree().activeTileCount() > 0);
    const auto centre = set.transform().worldToIndexCellCentered(openvdb::Vec3d(0.0));
    CHECK(density->tree().getValue(centre) == 1.0f);
    CHECK(density->tree().isValueOn(centre));
    CHECK(density->tree().getValueDepth(centre) < int(openvdb::FloatTree::DEPTH) - 1); // a tile, not a leaf voxel
    const auto outside = set.transform().worldToIndexCellCentered(openvdb::Vec3d(1.5, 0.0, 0.0));
    CHECK(density->tree().getValue(outside) == 0.0f);
    CHECK_FALSE(density->tree().isValueOn(outside));
    // Smooth ramp across the inner band: in [0, 1], increasing inward.
    float previous = -1.0f;
    for (int i = 0; i <= 4; ++i) {
        const float d = float(
            openvdb::tools::BoxSampler::sample(density->tree(), set.transform().worldToIndex(openvdb::Vec3d(1.1 - i * dx, 0.1, 0.0))));
        CHECK(d >= 0.0f);
        CHECK(d <= 1.0f);
        CHECK(d >= previous);
        previous = d;
    }
    CHECK(previous == 1.0f);
    // Fewer stored voxels than the dense box.
    CHECK(density->tree().activeLeafVoxelCount() < density->activeVoxelCount() / 2);
}

TEST_CASE("voxelization does not depend on the number of threads", "[voxelize]")
{
    const auto mesh = vxf::makeCandle(64);
    vxf::VoxelSet one, two;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        one = vxf::voxelize(mesh, withDim(96));
    }
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
        two = vxf::voxelize(mesh, withDim(96));
    }
    for (const char* name : {"surface", "density"}) {
        std::string why;
        INFO(name);
        CHECK(vxf::test::identicalGrids(*one.find(name), *two.find(name), &why));
        INFO(why);
    }
}

TEST_CASE("a mesh 1e5 units from the origin keeps its detail", "[voxelize][stability]")
{
    const openvdb::Vec3d centre(1.0e5, -2.0e5, 3.0e5);
    const auto mesh = vxf::makeSphere(centre, 1.0, 64, 128);
    vxf::VoxelizeOptions options;
    options.voxelSize = 1.0 / 64.0;
    const vxf::VoxelSet set = vxf::voxelize(mesh, options);
    auto surface = set.get<openvdb::FloatGrid>("surface");
    CHECK(openvdb::tools::levelSetVolume(*surface) == Approx(mesh.volume()).epsilon(0.01));
    const double dx = options.voxelSize;
    CHECK(signedDistanceAt(*surface, centre + openvdb::Vec3d(1.0 + 1.5 * dx, 0, 0)) == Approx(1.5 * dx).margin(0.1 * dx));
    // Voxel centres stay on the world lattice dx·Z^3.
    const openvdb::Vec3d world = set.transform().indexToWorld(openvdb::Coord(0));
    for (int a = 0; a < 3; ++a) CHECK(world[a] / dx == Approx(std::round(world[a] / dx)).margin(1e-6));
    bool finite = true;
    for (auto it = surface->cbeginValueOn(); it; ++it) finite = finite && std::isfinite(*it);
    CHECK(finite);
}

TEST_CASE("voxelize rejects bad options with their names", "[voxelize]")
{
    const auto mesh = vxf::makeBox(openvdb::Vec3d(0), openvdb::Vec3d(1));
    vxf::VoxelizeOptions both;
    both.dim = 10;
    both.voxelSize = 0.1;
    CHECK_THROWS_AS(vxf::voxelize(mesh, both), vxf::UsageError);
    CHECK_THROWS_WITH(vxf::voxelize(mesh, vxf::VoxelizeOptions{}), Catch::Contains("voxel_size or dim"));
    vxf::VoxelizeOptions narrow = withDim(10);
    narrow.bandWidth = 0.5f;
    CHECK_THROWS_WITH(vxf::voxelize(mesh, narrow), Catch::Contains("band must be at least 1"));
    vxf::VoxelizeOptions tiny;
    tiny.voxelSize = 1e-9;
    CHECK_THROWS_WITH(vxf::voxelize(mesh, tiny), Catch::Contains("more than 2^20"));
    CHECK_THROWS_WITH(vxf::voxelize(vxf::TriangleMesh{}, withDim(10)), Catch::Contains("no triangles"));
}

TEST_CASE("voxelize refuses, before allocating, what would exceed its bounds", "[voxelize][stability]")
{
    // A unit box at dim 20000: 6 / (5e-5)² = 2.4e9 surface voxels × a band 6 wide, 1.4e10 voxels.
    const auto box = vxf::makeBox(openvdb::Vec3d(0), openvdb::Vec3d(1));
    // At 56 bytes each, 780 GB: more than this machine has (the default budget).
    CHECK_THROWS_WITH(vxf::voxelize(box, withDim(20000)),
        Catch::Contains("1.44e+10 narrow-band voxels × 56 bytes") && Catch::Contains("more than the memory budget of"));
    vxf::VoxelizeOptions wide = withDim(64);
    wide.bandWidth = 1e6f; // a band as wide as this fills everything around the mesh
    CHECK_THROWS_WITH(vxf::voxelize(box, wide), Catch::Contains("narrow-band voxels"));
    // Voxels too small for OpenVDB's transforms: a clear error, not its ArithmeticError.
    const auto small = vxf::makeBox(openvdb::Vec3d(0), openvdb::Vec3d(1e-3));
    CHECK_THROWS_WITH(vxf::voxelize(small, withDim(1000)), Catch::Contains("dim 1000 makes voxels of 1e-06, below 1.5e-05"));
    vxf::VoxelizeOptions tiny;
    tiny.voxelSize = 1e-6;
    CHECK_THROWS_WITH(vxf::voxelize(small, tiny), Catch::Contains("voxel_size 1e-06 is below 1.5e-05"));
    // Within the bounds: dim 64 runs.
    CHECK(vxf::voxelize(box, withDim(64)).find("density") != nullptr);
}
