#include <vxf/scatter/SweepPass.h>

#include <vxf/light/Medium.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>
#include <tbb/global_control.h>

#include <cmath>

namespace {

openvdb::Vec3f centreValue(const openvdb::Vec3SGrid& grid) { return grid.tree().getValue(openvdb::Coord(0)); }

openvdb::Vec3SGrid::Ptr sweepSphere(double sigmaT, double albedo, int cells, int directions, vxf::VoxelSet* keep = nullptr)
{
    const vxf::Material m = vxf::test::albedoMaterial(sigmaT, albedo);
    vxf::VoxelSet set = vxf::test::uniformSphere(m, 1.0, cells);
    const vxf::Medium medium(set, m);
    vxf::ScatterPassOptions options;
    options.kernel = vxf::ScatterKernel::Sweep;
    options.directions = directions;
    auto phi = vxf::sweepPass(medium, *set.get<openvdb::Vec3SGrid>("scatter_source"), options);
    if (keep) *keep = set;
    return phi;
}

} // namespace

TEST_CASE("a sweep holds 4 pi J / sigma_t deep in a large homogeneous medium", "[sweep]")
{
    // sigma_t R = 20: the centre does not see the boundary; a constant J is the scheme's fixed point.
    const double sigmaT = 20.0, albedo = 0.5;
    auto phi = sweepSphere(sigmaT, albedo, 16, 16);
    const double j = sigmaT * albedo / (4.0 * M_PI); // scatter_source = sigma_s phi0 / 4 pi, phi0 = 1
    CHECK(centreValue(*phi).x() == Approx(4.0 * M_PI * j / sigmaT).epsilon(1e-4));
    CHECK(phi->getName() == "fluence");
}

TEST_CASE("a sweep's fluence at a sphere's centre is 4 pi J (1 - exp(-sigma_t R)) / sigma_t", "[sweep]")
{
    for (const double sigmaT : {0.5, 2.0, 5.0}) {
        INFO("sigma_t R = " << sigmaT);
        auto phi = sweepSphere(sigmaT, 0.5, 16, 64);
        const double j = sigmaT * 0.5 / (4.0 * M_PI);
        CHECK(centreValue(*phi).x() == Approx(4.0 * M_PI * j * -std::expm1(-sigmaT) / sigmaT).epsilon(0.02));
    }
}

TEST_CASE("a sweep keeps the source's topology, tiles holding the mean of their voxels", "[sweep]")
{
    vxf::VoxelSet set;
    auto phi = sweepSphere(2.0, 0.5, 16, 16, &set);
    const auto& source = *set.get<openvdb::Vec3SGrid>("scatter_source");
    CHECK(phi->activeVoxelCount() == source.activeVoxelCount());
    CHECK(phi->tree().hasSameTopology(source.tree()));
    // Light falls off toward the surface: the centre is brighter than a voxel at the rim.
    CHECK(centreValue(*phi).x() > phi->tree().getValue(openvdb::Coord(15, 0, 0)).x());
    CHECK(phi->tree().getValue(openvdb::Coord(15, 0, 0)).x() > 0.0f);
}

TEST_CASE("sweeps do not depend on the thread count", "[sweep][threads]")
{
    openvdb::Vec3SGrid::Ptr one, two;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        one = sweepSphere(3.0, 0.9, 16, 16);
    }
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
        two = sweepSphere(3.0, 0.9, 16, 16);
    }
    std::string why;
    CHECK(vxf::test::identicalGrids(*one, *two, &why));
    INFO(why);
}

TEST_CASE("sweeps stay finite and bounded from sigma_t 1e-6 to 1e6", "[sweep][stability]")
{
    for (const double sigmaT : {1e-6, 1.0, 1e6}) {
        INFO("sigma_t " << sigmaT);
        auto phi = sweepSphere(sigmaT, 0.9, 8, 16);
        const double j = sigmaT * 0.9 / (4.0 * M_PI);
        for (auto it = phi->cbeginValueOn(); it; ++it) {
            const openvdb::Vec3f v = *it;
            REQUIRE(std::isfinite(v.x()));
            REQUIRE(v.x() >= 0.0f);
            // Never more than the infinite medium's 4 pi J / sigma_t, nor the chord's 4 pi J (2R).
            REQUIRE(v.x() <= 1.0001 * std::min(4.0 * M_PI * j / sigmaT, 4.0 * M_PI * j * 2.0));
        }
    }
}

TEST_CASE("sweepDirections turns the whole set by a seeded rotation", "[sweep]")
{
    const auto a = vxf::sweepDirections(16, 0), b = vxf::sweepDirections(16, 7), c = vxf::sweepDirections(16, 7);
    REQUIRE(a.size() == 16);
    CHECK((a[0] - b[0]).length() > 1e-3);
    CHECK(b[3] == c[3]);
    // A rotation keeps the angles between directions.
    CHECK(a[2].dot(a[5]) == Approx(b[2].dot(b[5])).margin(1e-12));
    CHECK(b[4].length() == Approx(1.0));
    // Antipodal pairs, isotropic second moments.
    for (const int n : {8, 16, 32}) {
        const auto d = vxf::sweepDirections(n, 3);
        openvdb::Vec3d first(0.0);
        openvdb::Mat3d second = openvdb::Mat3d::zero();
        for (const auto& v : d) {
            first += v;
            second += openvdb::math::outerProduct(v, v);
        }
        CHECK(first.length() < 1e-12);
        for (int a = 0; a < 3; ++a)
            for (int b2 = 0; b2 < 3; ++b2) CHECK(second(a, b2) == Approx(a == b2 ? n / 3.0 : 0.0).margin(1e-9));
    }
}
