// The medium the transport sees (vxf/transport/Medium.h): the material's coefficients over the
// density, scaled by the phase for the transport (delta-M), by the similarity relation for the
// isotropic stages, and as they are for the camera.
#include <vxf/transport/Medium.h>

#include <vxf/core/Error.h>
#include <vxf/transport/Phase.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

TEST_CASE("a medium's coefficients: the transport's, the isotropic stages' and the actual ones", "[transport][medium]")
{
    vxf::Material m = vxf::test::greyMaterial(2.0, 6.0);
    m.phaseG = 0.6;
    const vxf::VoxelSet set = vxf::test::uniformSphere(m, 1.0, 8);
    const vxf::Medium transport(set, m);

    // The transport keeps f = forward of σs in the beam (delta-M) and scatters the rest with g*.
    const vxf::PhaseScaling scaling = vxf::transportScaling(0.6);
    CHECK(transport.material().sigmaS[0] == Approx(6.0 * (1.0 - scaling.forward)));
    CHECK(transport.material().sigmaA[0] == Approx(2.0));
    CHECK(transport.material().phaseG == Approx(scaling.restG()));
    CHECK(transport.phaseG() == Approx(0.6)); // the phase the camera scatters by

    const vxf::Medium isotropic = transport.isotropic(); // σs (1 − g), isotropic
    CHECK(isotropic.material().sigmaS[0] == Approx(6.0 * 0.4));
    CHECK(isotropic.material().phaseG == 0.0);

    const vxf::Medium actual = transport.actual();
    CHECK(actual.material().sigmaS[0] == Approx(6.0));
    CHECK(actual.material().phaseG == Approx(0.6));

    // Inside, σt is the material's times the density (1); outside, nothing.
    vxf::Medium::Sampler sampler(actual);
    CHECK(sampler.sigmaT(openvdb::Vec3d(0.0))[1] == Approx(8.0));
    CHECK(sampler.sigmaS(openvdb::Vec3d(0.0))[2] == Approx(6.0));
    CHECK(sampler.sigmaT(openvdb::Vec3d(30.0, 0.0, 0.0))[0] == 0.0);
    CHECK(actual.voxelSize() == Approx(1.0 / 8.0));
    CHECK_FALSE(actual.activeBounds().empty());

    // No density: named.
    vxf::VoxelSet empty(openvdb::math::Transform::createLinearTransform(0.1));
    CHECK_THROWS_WITH(vxf::Medium(empty, m), Catch::Contains("density"));
}

TEST_CASE("a medium read through its trees gives what its dense copies give", "[transport][medium]")
{
    // Lookups::Trees (the sweep kernel's scatter: no dense copy held through the solve) reads
    // the same values as the dense copies, at voxel centres and between them, and has no
    // bricks for marches to cross.
    const vxf::Material m = vxf::test::greyMaterial(2.0, 6.0);
    vxf::VoxelSet set = vxf::test::uniformSphere(m, 1.0, 8);
    vxf::test::putSphereSurface(set, 0.9, 8);
    const vxf::Medium dense(set, m), trees(set, m, vxf::Medium::Lookups::Trees);
    CHECK(dense.uniformBricks() != nullptr);
    CHECK(trees.uniformBricks() == nullptr);
    REQUIRE(trees.surface() != nullptr);
    vxf::Medium::Sampler a(dense), b(trees);
    int differ = 0, checked = 0, skins = 0;
    for (double x = -9.0; x <= 9.0; x += 0.5) {
        for (double y = -9.0; y <= 9.0; y += 1.25) {
            const openvdb::Vec3d p(x, y, 0.5 * x - 1.0);
            differ += a.sigmaT(p) != b.sigmaT(p);
            differ += a.sigmaS(p) != b.sigmaS(p);
            differ += a.signedDistance(p) != b.signedDistance(p);
            differ += a.interiorScale(p) != b.interiorScale(p);
            const openvdb::Coord c = openvdb::Coord::floor(p);
            openvdb::Vec3d pa, na, pb, nb;
            const bool sa = a.skinPoint(c, pa, na), sb = b.skinPoint(c, pb, nb);
            differ += sa != sb || (sa && (pa != pb || na != nb));
            skins += sa;
            ++checked;
        }
    }
    CHECK(checked > 500);
    CHECK(skins > 10);
    CHECK(differ == 0);
}
