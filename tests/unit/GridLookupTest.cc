#include <vxf/core/GridLookup.h>

#include <catch2/catch.hpp>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/LevelSetSphere.h>

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
