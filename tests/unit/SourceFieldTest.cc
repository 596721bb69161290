#include <vxf/scatter/SourceField.h>

#include <vxf/core/ProceduralMesh.h>
#include <vxf/light/InteriorField.h>
#include <vxf/voxelize/Voxelize.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <functional>

namespace {

constexpr double kSigmaS = 2.0;

/// A sphere of radius 1 at voxel size 0.1 (σs = 2) and the source of a fluence @a phi taken
/// where the passes gather it (the centre, or a skin voxel's surface point: skinPoint), on the
/// medium's topology.
struct ScatteringSphere
{
    explicit ScatteringSphere(const std::function<double(const openvdb::Vec3d&)>& phi)
        : set(vxf::voxelize(vxf::makeSphere(openvdb::Vec3d(0.0), 1.0, 128, 256), options()))
    {
        medium.emplace(set, vxf::test::greyMaterial(0.0, kSigmaS));
        auto fluence = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
        fluence->setTransform(set.transformPtr());
        fluence->tree().topologyUnion(medium->density().tree());
        fluence->tree().voxelizeActiveTiles();
        vxf::Medium::Sampler sampler(*medium);
        for (auto it = fluence->beginValueOn(); it; ++it) {
            openvdb::Vec3d p = it.getCoord().asVec3d(), normal;
            sampler.skinPoint(it.getCoord(), p, normal);
            it.setValue(openvdb::Vec3f(float(phi(set.transform().indexToWorld(p)))));
        }
        source = vxf::sourceFromFluence(*medium, *fluence);
    }
    static vxf::VoxelizeOptions options()
    {
        vxf::VoxelizeOptions o;
        o.voxelSize = 0.1;
        return o;
    }
    double read(const vxf::SourceField& field, const openvdb::Vec3d& x) const
    {
        return vxf::SourceField::Sampler(field).sample(set.transform().worldToIndex(x))[0];
    }
    vxf::VoxelSet set;
    std::optional<vxf::Medium> medium;
    openvdb::Vec3SGrid::Ptr source;
};

} // namespace

TEST_CASE("the scattered light's source follows a field rising inward up to the surface", "[scatter][source]")
{
    // The diffusive profile towards a surface light leaves by, φ ∝ depth + 0.71 mean free paths
    // (here 0.2, two voxels): a voxel outside, the line continued is half the surface value.
    const auto phi = [](const openvdb::Vec3d& x) { return 0.142 + (1.0 - x.length()); };
    const ScatteringSphere sphere(phi);
    // Both reads: the camera's through the layers, the passes' from the lattice they fill.
    for (const auto near : {vxf::SourceField::Near::Layers, vxf::SourceField::Near::Lattice}) {
        const vxf::SourceField field(*sphere.medium, *sphere.source, near);
        for (const openvdb::Vec3d& dir : {openvdb::Vec3d(0.3, -0.8, 0.52).unit(), openvdb::Vec3d(0.71, 0.1, 0.7).unit(),
                 openvdb::Vec3d(0.0, 0.0, 1.0), openvdb::Vec3d(0.0, 0.6, 0.8)}) {
            for (double depth : {0.0, 0.02, 0.05, 0.1, 0.15, 0.2, 0.3, 0.5}) {
                const openvdb::Vec3d x = dir * (1.0 - depth);
                INFO((near == vxf::SourceField::Near::Layers ? "layers" : "lattice") << ", direction " << dir << ", depth " << depth);
                CHECK(sphere.read(field, x) == Approx(kSigmaS * phi(x) / (4.0 * M_PI)).epsilon(0.01));
            }
        }
    }
}
