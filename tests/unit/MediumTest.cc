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
