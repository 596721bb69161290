// Volume lights (vxf/light/VolumeEmission.h): a file's grid as radiance per unit length, times the
// light's power, placed by the light's transform; a missing grid named with the file's grids.
#include <vxf/light/VolumeEmission.h>

#include <vxf/core/Error.h>
#include <vxf/core/VoxelSet.h>
#include <vxf/io/VoxelSetFile.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <limits>

TEST_CASE("a volume light reads its grid times its power where its transform places it", "[light][emission]")
{
    vxf::test::TempDir dir;
    auto flame = openvdb::FloatGrid::create(0.0f);
    flame->setName("flame");
    flame->setTransform(openvdb::math::Transform::createLinearTransform(0.1));
    flame->fill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(9)), 2.0f, true);
    vxf::VoxelSet set(flame->transformPtr());
    set.put(flame);
    vxf::writeVoxelSet(dir.path("fire.vdb"), set);

    vxf::Light light;
    light.type = vxf::Light::Type::Volume;
    light.name = "fire";
    light.file = dir.path("fire.vdb");
    light.grid = "flame";
    light.color = openvdb::Vec3d(1.0, 0.5, 0.25);
    light.intensity = 3.0;
    {
        const vxf::VolumeEmission emission(light);
        vxf::VolumeEmission::Sampler at(emission);
        const openvdb::Vec3d inside = at.at(openvdb::Vec3d(0.45, 0.45, 0.45));
        CHECK(inside[0] == Approx(6.0));
        CHECK(inside[2] == Approx(1.5));
        CHECK(at.at(openvdb::Vec3d(5.0, 5.0, 5.0)) == openvdb::Vec3d(0.0));
    }
    // Moved with its object: 10 to the right.
    light.gridToWorld = openvdb::Mat4d::identity();
    light.gridToWorld.setTranslation(openvdb::Vec3d(10.0, 0.0, 0.0));
    const vxf::VolumeEmission moved(light);
    vxf::VolumeEmission::Sampler movedAt(moved);
    CHECK(movedAt.at(openvdb::Vec3d(0.45, 0.45, 0.45)) == openvdb::Vec3d(0.0));
    CHECK(movedAt.at(openvdb::Vec3d(10.45, 0.45, 0.45))[0] == Approx(6.0));

    light.grid = "temperature";
    CHECK_THROWS_WITH(vxf::VolumeEmission(light), Catch::Contains("light 'fire': no grid 'temperature'") && Catch::Contains("flame"));

    // A NaN in the emission is refused where it is read, naming this file (it would spread
    // through the scatter's sweeps and be found only in the light stage's output).
    flame->tree().setValueOn(openvdb::Coord(3, 4, 5), std::numeric_limits<float>::quiet_NaN());
    vxf::writeVoxelSet(dir.path("fire.vdb"), set);
    light.grid = "flame";
    CHECK_THROWS_WITH(vxf::VolumeEmission(light),
        Catch::Contains(dir.path("fire.vdb") + ": grid 'flame' holds 1 NaN or infinite value (the first at voxel (3, 4, 5))"));
}
