// vxf — a volume light's emission: a grid of radiance per unit length (a fire's flame, a glow).
#pragma once

#include <vxf/core/Scene.h>

#include <openvdb/openvdb.h>

#include <optional>

namespace vxf {

/// The emission of a `"type": "volume"` light: its file's grid (float, grey, or vec3s), radiance
/// per unit length times the light's colour × intensity, sampled trilinearly at world points on
/// the grid's own transform (a flame or temperature grid of a simulation, any voxels). The light
/// stage adds it to J0, so the passes scatter it; the render adds it along camera rays, so it is
/// seen. Read-only after construction; give each thread its own Sampler.
class VolumeEmission
{
public:
    /// Reads @a light's grid; throws vxf::Error naming the light, the file and the grid when the
    /// file cannot be read, has no such grid, or the grid is neither float nor vec3s.
    explicit VolumeEmission(const Light& light);

    /// Per-thread lookups through a cached accessor (the render samples every camera step).
    class Sampler
    {
    public:
        explicit Sampler(const VolumeEmission& emission);
        /// Radiance per unit length emitted at world point @a world (0 outside the grid's values).
        openvdb::Vec3d at(const openvdb::Vec3d& world);

    private:
        const VolumeEmission& mEmission;
        std::optional<openvdb::FloatGrid::ConstAccessor> mFloat;
        std::optional<openvdb::Vec3SGrid::ConstAccessor> mVec3;
    };

private:
    openvdb::FloatGrid::ConstPtr mFloat;
    openvdb::Vec3SGrid::ConstPtr mVec3;
    openvdb::Vec3d mPower;
    double mKelvin = 0.0; ///< Light::blackbodyKelvin: a temperature grid (float), sampled then made light
};

} // namespace vxf
