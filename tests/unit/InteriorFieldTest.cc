#include <vxf/light/InteriorField.h>

#include <vxf/core/ProceduralMesh.h>
#include <vxf/voxelize/Voxelize.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>
#include <openvdb/tools/Morphology.h>

#include <cmath>
#include <functional>

namespace {

constexpr double kSigmaS = 2.0;

/// A sphere of radius 1 at voxel size 0.1 (σs = 2), with a fluence grid on the light stage's
/// topology (the medium's voxels and one more all round) holding @a phi at voxel centres.
struct LitSphere
{
    explicit LitSphere(const std::function<double(const openvdb::Vec3d&)>& phi, bool withSurface = true, double dx = 0.1)
        : set(vxf::voxelize(vxf::makeSphere(openvdb::Vec3d(0.0), 1.0, 128, 256), options(dx)))
    {
        if (!withSurface) set.remove("surface");
        medium.emplace(set, vxf::test::greyMaterial(0.0, kSigmaS));
        fluence = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
        fluence->setTransform(set.transformPtr());
        fluence->tree().topologyUnion(medium->density().tree());
        openvdb::tools::dilateActiveValues(fluence->tree(), 1, openvdb::tools::NN_FACE_EDGE_VERTEX);
        fluence->tree().voxelizeActiveTiles();
        for (auto it = fluence->beginValueOn(); it; ++it) {
            it.setValue(openvdb::Vec3f(float(phi(set.transform().indexToWorld(it.getCoord())))));
        }
    }
    static vxf::VoxelizeOptions options(double dx)
    {
        vxf::VoxelizeOptions o;
        o.voxelSize = dx;
        return o;
    }
    /// J the field reads at world point @a x.
    double read(const vxf::InteriorField& field, const openvdb::Vec3d& x) const
    {
        return vxf::InteriorField::Sampler(field).sample(set.transform().worldToIndex(x))[0];
    }
    vxf::VoxelSet set;
    std::optional<vxf::Medium> medium;
    openvdb::Vec3SGrid::Ptr fluence;
};

} // namespace

TEST_CASE("single scattering read from the grid follows a steep fall-off up to the surface", "[light][interior]")
{
    // φ = e^{−depth/ℓ} with ℓ = 1.5 voxels, what light entering a thick medium does. Read as
    // the voxels' σs·φ divided by their interpolated volume fraction, it came out 10-20% dark
    // within a voxel of the surface.
    const double ell = 0.15;
    const auto phi = [ell](const openvdb::Vec3d& x) { return std::exp(-(1.0 - x.length()) / ell); };
    const LitSphere sphere(phi);
    const vxf::InteriorField field(*sphere.medium, *sphere.fluence);
    for (const openvdb::Vec3d& dir :
        {openvdb::Vec3d(0.3, -0.8, 0.52).unit(), openvdb::Vec3d(0.71, 0.1, 0.7).unit(), openvdb::Vec3d(0.0, 0.0, 1.0)}) {
        for (double depth : {0.0, 0.02, 0.05, 0.1, 0.15, 0.2, 0.3}) {
            const openvdb::Vec3d x = dir * (1.0 - depth);
            INFO("direction " << dir << ", depth " << depth);
            CHECK(sphere.read(field, x) == Approx(kSigmaS * phi(x) / (4.0 * M_PI)).epsilon(0.03));
        }
    }
}

TEST_CASE("single scattering read from the grid stays finite and bounded where the light is zero", "[light][interior][stability]")
{
    // Half the sphere in an occluder's shadow (φ = 0 for z < 0): cells with a zero corner read
    // linearly, never NaN, never above the largest J, never below zero.
    const auto phi = [](const openvdb::Vec3d& x) { return x.z() < 0.0 ? 0.0 : std::exp(-(1.0 - x.length()) / 0.15); };
    const LitSphere sphere(phi);
    const vxf::InteriorField field(*sphere.medium, *sphere.fluence);
    const double most = kSigmaS / (4.0 * M_PI);
    for (double z = -0.3; z <= 0.3; z += 0.013) {
        for (double depth : {0.0, 0.04, 0.2}) {
            const openvdb::Vec3d x = openvdb::Vec3d(std::sqrt(1.0 - z * z), 0.0, z) * (1.0 - depth);
            const double j = sphere.read(field, x);
            INFO("z " << z << ", depth " << depth << ": " << j);
            CHECK(std::isfinite(j));
            CHECK(j >= 0.0);
            CHECK(j <= most * 1.05);
            if (z < -0.2) CHECK(j == 0.0);
        }
    }
}

TEST_CASE("without a surface the grid is read trilinearly as it is", "[light][interior]")
{
    const auto phi = [](const openvdb::Vec3d& x) { return 1.0 + x.x(); };
    const LitSphere sphere(phi, /*withSurface=*/false);
    REQUIRE(sphere.medium->surface() == nullptr);
    const vxf::InteriorField field(*sphere.medium, *sphere.fluence);
    // Deep inside, density 1: J = σs·φ/4π, linear in x, read exactly.
    for (const openvdb::Vec3d& x : {openvdb::Vec3d(0.013, 0.2, -0.1), openvdb::Vec3d(-0.37, 0.05, 0.33)}) {
        CHECK(sphere.read(field, x) == Approx(kSigmaS * phi(x) / (4.0 * M_PI)).epsilon(1e-5));
    }
}
