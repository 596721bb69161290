// One gather pass (vxf/scatter/ScatterPass.h): the thesis's march per voxel and direction holds
// 4 pi J / sigma_t deep in a homogeneous medium, and the kernels are named as the CLI names them.
#include <vxf/scatter/ScatterPass.h>

#include <vxf/core/Error.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <cmath>

TEST_CASE("a gather holds 4 pi J / sigma_t deep in a homogeneous medium, and J / sigma_t (1 - e^-tau) toward the edge", "[scatter][gather]")
{
    const double sigmaT = 20.0, albedo = 0.5;
    const vxf::Material m = vxf::test::albedoMaterial(sigmaT, albedo);
    const vxf::VoxelSet set = vxf::test::uniformSphere(m, 1.0, 12);
    const vxf::Medium medium(set, m);
    const auto& source = *set.get<openvdb::Vec3SGrid>("scatter_source");
    vxf::ScatterPassOptions options;
    options.kernel = vxf::ScatterKernel::Gather;
    options.directions = 32;
    options.source = vxf::ScatterPassOptions::SourceRead::FractionWeighted;
    const auto phi = vxf::scatterPass(medium, source, options);
    const double j = source.tree().getValue(openvdb::Coord(0))[0];
    // The centre sees the sphere's edge 20 mean free paths away in every direction.
    CHECK(phi->tree().getValue(openvdb::Coord(0))[0] == Approx(4.0 * M_PI * j / sigmaT).epsilon(2e-3));
    // Every voxel lies between nothing and the deep value. The outermost voxel, centred on the
    // sphere, gets half of it and what the half voxel of its density ramp beyond adds (σt dx 1.7).
    const double deep = 4.0 * M_PI * j / sigmaT;
    for (auto it = phi->cbeginValueOn(); it; ++it) {
        REQUIRE((*it)[0] >= 0.0f);
        REQUIRE((*it)[0] <= deep * 1.01);
    }
    const double rim = phi->tree().getValue(openvdb::Coord(0, 0, 12))[0];
    CHECK(rim > 0.5 * deep);
    CHECK(rim < 0.9 * deep);
    CHECK(phi->tree().getValue(openvdb::Coord(0, 0, 11))[0] > rim); // deeper, brighter
}

TEST_CASE("kernels are named gather and sweep, the default follows the phase", "[scatter][gather]")
{
    CHECK(vxf::scatterKernelNamed("gather") == vxf::ScatterKernel::Gather);
    CHECK(vxf::scatterKernelNamed("sweep") == vxf::ScatterKernel::Sweep);
    CHECK_THROWS_WITH(vxf::scatterKernelNamed("march"), Catch::Contains("march") && Catch::Contains("gather") && Catch::Contains("sweep"));
    CHECK(vxf::defaultScatterKernel(0.0) == "gather");
    CHECK(vxf::defaultScatterKernel(0.6) == "sweep"); // a forward phase's anisotropy only the sweeps carry
    CHECK(vxf::defaultScatterKernel(-0.3) == "gather"); // backward: the similarity relation, isotropic
}
