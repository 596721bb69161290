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

    // The change φ_{l+½} − φ_l: 1 everywhere.
    const std::vector<openvdb::Vec3f> next(lattice.voxelCount(), openvdb::Vec3f(1.5f)), phi(lattice.voxelCount(), openvdb::Vec3f(0.5f));
    const auto solved = correction.solve(next, phi, 0.0, 1e-6, 2000);
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

TEST_CASE("a diffusion cell's mean is the mean of its voxels", "[scatter][diffusion]")
{
    const vxf::Material m = vxf::test::albedoMaterial(30.0, 0.9);
    const vxf::VoxelSet set = vxf::test::uniformSphere(m, 1.0, 16);
    const vxf::Medium medium(set, m);
    const vxf::detail::SweepLattice lattice(medium, *set.get<openvdb::Vec3SGrid>("scatter_source"));
    const vxf::detail::DiffusionCorrection correction(lattice, 2);
    CHECK(correction.cellMeans({}).empty());
    // x + 2 at each voxel: a cell of 2^3 voxels inside averages its two x's, x0 + 0.5 + 2.
    std::vector<openvdb::Vec3f> values(lattice.voxelCount(), openvdb::Vec3f(0.0f));
    for (int x = -24; x < 24; ++x) {
        for (int y = -24; y < 24; ++y) {
            for (int z = -24; z < 24; ++z) {
                const auto v = lattice.indexOf(openvdb::Coord(x, y, z));
                if (v >= 0) values[std::size_t(v)] = openvdb::Vec3f(float(x + 2), 1.0f, 0.0f);
            }
        }
    }
    const std::vector<openvdb::Vec3d> means = correction.cellMeans(values);
    REQUIRE(means.size() == correction.size());
    std::size_t inside = 0;
    for (const openvdb::Vec3d& m : means) {
        CHECK(m[1] == Approx(1.0));
        CHECK(m[2] == 0.0);
        const double fraction = m[0] - 2.5 - std::floor(m[0] - 2.5);
        if (std::abs(fraction) < 1e-9) ++inside; // x0 even: a whole cell's mean is x0 + 2.5
    }
    CHECK(inside > correction.size() / 2);
}
