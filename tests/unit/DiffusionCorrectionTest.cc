// The sweeps' diffusion correction (src/scatter/DiffusionCorrection.h): deep in a homogeneous
// medium the correction of a uniform change solves sigma_a delta = sigma_s change.
#include "scatter/DiffusionCorrection.h"

#include "TestSupport.h"

#include <catch2/catch.hpp>

TEST_CASE("a uniform change deep inside is corrected by sigma_s / sigma_a, the rest of the series", "[scatter][diffusion]")
{
    const double sigmaT = 30.0, albedo = 0.9;
    const vxf::Material m = vxf::test::albedoMaterial(sigmaT, albedo);
    const vxf::VoxelSet set = vxf::test::uniformSphere(m, 1.0, 16);
    const auto& source = *set.get<openvdb::Vec3SGrid>("scatter_source");
    const vxf::Medium medium(set, m);
    const vxf::detail::SweepLattice lattice(medium, source);
    vxf::detail::DiffusionCorrection correction(lattice, 1);
    CHECK(correction.size() > 0);
    CHECK(correction.coarsening() == 1);

    const std::vector<openvdb::Vec3f> change(lattice.voxelCount(), openvdb::Vec3f(1.0f));
    const auto solved = correction.solve(change, 0.0, 1e-6, 2000);
    CHECK(solved.residual <= 1e-6);
    std::vector<openvdb::Vec3f> delta(lattice.voxelCount(), openvdb::Vec3f(0.0f));
    correction.addTo(delta);
    // The diffusion length 1/sqrt(3 sigma_t sigma_a) is 0.06 of the radius: the centre sees no edge.
    const std::size_t centre = std::size_t(lattice.indexOf(openvdb::Coord(0)));
    CHECK(delta[centre][0] == Approx(albedo / (1.0 - albedo)).epsilon(0.01));
    // Near the surface light leaks out: less.
    const std::size_t rim = std::size_t(lattice.indexOf(openvdb::Coord(0, 0, 15)));
    CHECK(delta[rim][0] < 0.9 * delta[centre][0]);
}
