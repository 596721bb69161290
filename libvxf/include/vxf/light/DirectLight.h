// vxf — the light stage: fluence from the lights (`direct`) and the scattering source.
#pragma once

#include <vxf/core/Interrupter.h>
#include <vxf/light/Transmittance.h>
#include <vxf/pipeline/Scene.h>

#include <string>
#include <vector>

namespace vxf {

struct DirectLightOptions
{
    MarchOptions march;
    /// Evaluate active tiles of `density` once at their centre (coarse, the tree's own
    /// resolution) instead of voxel by voxel. Only for media so thick that the deep interior
    /// never shows; thinner media show the tiles as blocks.
    bool coarseTiles = false;
};

struct DirectLightReport
{
    struct PerLight
    {
        std::string name;
        bool skipped = false;
        std::string why;              ///< reason it was skipped
        openvdb::Vec3d fluenceSum{0.0}; ///< Σ over active voxels of its φ0 (energy check)
    };
    std::vector<PerLight> lights;
};

/// Fluence at an index-space point from one light, attenuated by the medium:
/// point I·T(x,p)·f(r), spot the same × cone factor, directional E·T to the boundary,
/// area Σ L·cosθ·(A/N)·f(r)·T over stratified samples, environment Σ (4π/N)·L·T over
/// spherical Fibonacci directions. f(r) is the falloff: 1/r², 1/r or 1. Volume lights add
/// no fluence (they are a source; see computeDirectLight). Never NaN: a voxel at a point
/// light's position gets the value of a point half a voxel away.
openvdb::Vec3d lightFluence(const Light& light, Medium::Sampler& sampler, const Medium& medium,
    const openvdb::Coord& voxel, const MarchOptions& options);

/// The light stage. Adds to @a set:
/// - `direct` (Vec3f): φ0 = Σ lights, at every active voxel of `density` (active tiles are
///   voxelized, or with coarseTiles evaluated once at their centre), and one voxel beyond
///   (so trilinear lookups at the surface blend real values);
/// - `scatter_source` (Vec3f): J0 = σs·φ0/(4π) + the emission of volume lights, same topology
///   (0 outside the medium, where σs is 0).
/// Lights with zero power are skipped and reported. Parallel over leaf nodes (TBB);
/// each voxel is computed on its own, so results do not depend on the number of threads.
/// Throws vxf::UsageError for light settings it cannot honour (environment maps, for now).
DirectLightReport computeDirectLight(VoxelSet& set, const Medium& medium, const std::vector<Light>& lights,
    const DirectLightOptions& options = {}, Interrupter* interrupter = nullptr);

} // namespace vxf
