#include <vxf/core/GridLookup.h>

#include <catch2/catch.hpp>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/LevelSetSphere.h>

#include <cmath>
#include <limits>

TEST_CASE("a dense copy reads what the tree holds, inside and outside its box", "[gridlookup]")
{
    // A level set: active voxels in a narrow band, the inside an inactive −background, the
    // outside +background; a dense copy must return all three as the tree does.
    const auto sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(10.0f, openvdb::Vec3f(3.0f, -2.0f, 1.0f), 1.0f, 3.0f);
    const auto dense = vxf::DenseCopy<openvdb::FloatGrid>::create(*sphere, 2, vxf::kDenseCopyBytes);
    REQUIRE(dense);
    const vxf::GridLookup<openvdb::FloatGrid> fast(*sphere, dense.get()), tree(*sphere, nullptr);
    auto acc = sphere->getConstAccessor();
    int differ = 0;
    for (int i = -20; i <= 25; ++i)
        for (int j = -25; j <= 20; j += 3)
            for (int k = -20; k <= 20; k += 2) {
                const openvdb::Coord c(i, j, k);
                differ += fast.getValue(c) != acc.getValue(c);
                differ += tree.getValue(c) != acc.getValue(c);
            }
    CHECK(differ == 0);
    CHECK(fast.getValue(openvdb::Coord(3, -2, 1)) == Approx(-3.0f)); // deep inside
    CHECK(fast.getValue(openvdb::Coord(1000, 0, 0)) == Approx(3.0f)); // far outside its box
    // Trilinear lookups through OpenVDB's sampler agree.
    const openvdb::Vec3d p(12.3, -2.7, 0.4);
    CHECK(openvdb::tools::BoxSampler::sample(fast, p) == Approx(openvdb::tools::BoxSampler::sample(acc, p)).margin(1e-6));

    // Too large for the budget, or nothing active: no copy (lookups read the tree).
    CHECK_FALSE(vxf::DenseCopy<openvdb::FloatGrid>::create(*sphere, 2, 1000));
    CHECK_FALSE(vxf::DenseCopy<openvdb::FloatGrid>::create(*openvdb::FloatGrid::create(0.0f), 2, vxf::kDenseCopyBytes));
}

TEST_CASE("block reads interpolate as OpenVDB's samplers do, across the dense copy's edge", "[gridlookup]")
{
    // Points whose 2³ and 3³ blocks lie inside the copied box, straddle its edge (the block
    // read falls back to single lookups) and lie beyond it: the same values as BoxSampler and
    // QuadraticSampler on the tree, to the bit.
    const auto sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(6.0f, openvdb::Vec3f(0.0f), 1.0f, 3.0f);
    const auto dense = vxf::DenseCopy<openvdb::FloatGrid>::create(*sphere, 1, vxf::kDenseCopyBytes);
    REQUIRE(dense);
    const vxf::GridLookup<openvdb::FloatGrid> fast(*sphere, dense.get()), tree(*sphere, nullptr);
    auto acc = sphere->getConstAccessor();
    const openvdb::CoordBBox box = sphere->evalActiveVoxelBoundingBox().expandBy(1); // the copied box
    int checked = 0, straddling = 0, differ = 0;
    for (double x = box.min().x() - 2.6; x <= box.max().x() + 2.6; x += 0.37) {
        for (double y = -3.1; y <= 3.1; y += 1.3) {
            const openvdb::Vec3d p(x, y, 0.45 * x - 0.2);
            const openvdb::Coord base = openvdb::Coord::floor(p);
            straddling += box.isInside(base) != box.isInside(base.offsetBy(1));
            for (const auto* lookup : {&fast, &tree}) {
                differ += lookup->sampleTrilinear(p) != openvdb::tools::BoxSampler::sample(acc, p);
                differ += lookup->sampleTriquadratic(p) != openvdb::tools::QuadraticSampler::sample(acc, p);
            }
            ++checked;
        }
    }
    CHECK(checked > 100);
    CHECK(straddling > 0);
    CHECK(differ == 0);
}

TEST_CASE("at a voxel's centre a lookup reads the voxel alone, whatever its neighbours hold", "[gridlookup]")
{
    // The sweep lattice reads every voxel at its centre (through the tree when there is no
    // dense copy): the interpolation's weights are then the voxel's alone. Where the neighbours
    // are finite that is BoxSampler's and QuadraticSampler's value to the bit; a non-finite
    // neighbour, weighted 0, does not turn it into NaN.
    const auto sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(6.0f, openvdb::Vec3f(0.0f), 1.0f, 3.0f);
    const auto dense = vxf::DenseCopy<openvdb::FloatGrid>::create(*sphere, 1, vxf::kDenseCopyBytes);
    REQUIRE(dense);
    const vxf::GridLookup<openvdb::FloatGrid> fast(*sphere, dense.get()), tree(*sphere, nullptr);
    auto acc = sphere->getConstAccessor();
    int differ = 0, checked = 0;
    for (auto it = sphere->cbeginValueOn(); it; ++it) {
        const openvdb::Vec3d centre = it.getCoord().asVec3d();
        for (const auto* lookup : {&fast, &tree}) {
            differ += lookup->sampleTrilinear(centre) != openvdb::tools::BoxSampler::sample(acc, centre);
            differ += lookup->sampleTriquadratic(centre) != openvdb::tools::QuadraticSampler::sample(acc, centre);
            differ += lookup->sampleTrilinear(centre) != *it;
        }
        ++checked;
    }
    CHECK(checked > 500);
    CHECK(differ == 0);

    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->tree().setValue(openvdb::Coord(0, 0, 0), 2.5f);
    grid->tree().setValue(openvdb::Coord(1, 0, 0), std::numeric_limits<float>::infinity());
    grid->tree().setValue(openvdb::Coord(0, 0, -1), std::numeric_limits<float>::quiet_NaN());
    const vxf::GridLookup<openvdb::FloatGrid> lookup(*grid, nullptr);
    CHECK(std::isnan(openvdb::tools::BoxSampler::sample(grid->getConstAccessor(), openvdb::Vec3d(0.0))));
    CHECK(lookup.sampleTrilinear(openvdb::Vec3d(0.0)) == 2.5f);
    CHECK(lookup.sampleTriquadratic(openvdb::Vec3d(0.0)) == 2.5f);
    CHECK_FALSE(std::isfinite(lookup.sampleTrilinear(openvdb::Vec3d(0.5, 0.0, 0.0)))); // between them, as OpenVDB's
}
