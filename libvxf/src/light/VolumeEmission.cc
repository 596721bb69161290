#include <vxf/light/VolumeEmission.h>

#include <vxf/core/Error.h>
#include <vxf/light/Blackbody.h>
#include <vxf/io/VoxelPlacement.h>
#include <vxf/io/VoxelSetFile.h>

#include <fmt/format.h>
#include <openvdb/tools/Interpolation.h>

namespace vxf {

VolumeEmission::VolumeEmission(const Light& light)
    : mPower(light.power())
    , mKelvin(light.blackbodyKelvin)
{
    // Not the file's other grids; a NaN or infinite emission refused here, naming this file (it
    // would spread through the scatter's sweeps).
    VoxelSetReadOptions finite;
    finite.finite = [](const std::string&) { return true; };
    const VoxelSet source = readGrids(light.file, {light.grid}, finite);
    const openvdb::GridBase::Ptr grid = source.find(light.grid);
    if (!grid) {
        std::string names;
        for (const std::string& name : voxelGridNames(light.file)) names += (names.empty() ? "" : ", ") + name;
        throw Error(fmt::format(
            "light '{}': no grid '{}' in {} (the file has: {})", light.name, light.grid, light.file, names.empty() ? "none" : names));
    }
    // Placed and moved as its object is (SceneMedium's volume object: the same product of transforms).
    openvdb::math::Transform::Ptr moved =
        placedTransform(grid->transform(), resolvePlacement(light.placement, light.file, source.metadata()).placement);
    if (light.gridToWorld != openvdb::Mat4d::identity()) moved->postMult(light.gridToWorld);
    grid->setTransform(moved);
    mFloat = openvdb::gridConstPtrCast<openvdb::FloatGrid>(grid);
    mVec3 = openvdb::gridConstPtrCast<openvdb::Vec3SGrid>(grid);
    if (mKelvin > 0.0 && !mFloat) {
        throw Error(fmt::format("light '{}': a blackbody's grid '{}' in {} must be a float temperature, not {}", light.name, light.grid,
            light.file, grid->valueType()));
    }
    if (!mFloat && !mVec3) {
        throw Error(fmt::format(
            "light '{}': grid '{}' in {} must be float or vec3s, not {}", light.name, light.grid, light.file, grid->valueType()));
    }
}

VolumeEmission::Sampler::Sampler(const VolumeEmission& emission)
    : mEmission(emission)
{
    if (emission.mFloat) mFloat.emplace(emission.mFloat->getConstAccessor());
    if (emission.mVec3) mVec3.emplace(emission.mVec3->getConstAccessor());
}

openvdb::Vec3d VolumeEmission::Sampler::at(const openvdb::Vec3d& world)
{
    openvdb::Vec3d e(0.0);
    if (mFloat) {
        const double value = openvdb::tools::BoxSampler::sample(*mFloat, mEmission.mFloat->transform().worldToIndex(world));
        // A temperature is interpolated, then made light (as Cycles does): T⁴ of the mean, not the mean of T⁴.
        e = mEmission.mKelvin > 0.0 ? blackbodyEmission(value * mEmission.mKelvin) : openvdb::Vec3d(value);
    } else {
        e = openvdb::Vec3d(openvdb::tools::BoxSampler::sample(*mVec3, mEmission.mVec3->transform().worldToIndex(world)));
    }
    for (int c = 0; c < 3; ++c) e[c] *= mEmission.mPower[c];
    return e;
}

} // namespace vxf
