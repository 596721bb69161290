// vxf — the light stage: fluence from the lights (`direct`) and the scattering source.
#pragma once

#include <vxf/core/MemoryBudget.h>
#include <vxf/core/Interrupter.h>
#include <vxf/core/RayScene.h>
#include <vxf/light/LightSampler.h>
#include <vxf/transport/Transmittance.h>
#include <vxf/core/Scene.h>

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
    /// The adaptive band (world units; 0: none): the 8³ leaves of the deep interior beyond it
    /// (BandInterior) written as tiles of their voxels' means, as the scatter stage's band
    /// coarsens its source (lit at full resolution all the same: the light stage's sweeps take
    /// no coarse cells). A thick medium's grids then hold its band's voxels, not its volume's.
    double band = 0.0;
    /// Directional and environment lights by optical-depth sweeps over the medium's leaves (one
    /// per direction, SweepLattice::opticalDepthAlong), their transmittance at each voxel centre,
    /// instead of a march per voxel and direction. Light entering the leaves from outside them
    /// brings the depth it had where it left the medium upwind (other parts of the medium
    /// shadow across vacuum: the sweep's own depth there, or a march); the rim (centres outside
    /// the surface, whose light is taken at the surface) is marched along the directions that
    /// graze the surface there (LightSweeps.h: kRimSweptCosine) until clear of the surface (a
    /// voxel inside it, two outside: LightSweeps.cc, clearOfSurface), and takes the sweep's depth
    /// beyond; one leaving the surface outward crosses the vacuum to the next of the medium's
    /// meshes in one go (kVacuumMargin).
    /// Point and spot lights by one sweep around the light (SweepLattice::opticalDepthFrom, a
    /// short characteristic per voxel toward the light): the voxels within 3 inside the surface
    /// (2 outside it) are marched (swept whole, the thick bunny at dim 64 came out 6.1% off the
    /// reference against 3.9% marched: the light falls steeply there, over the surface's
    /// curvature), handing the rest of the way to the sweep once clear of the surface (past a
    /// shadow's edge in vacuum, to the next mesh ahead in one go); the deeper ones blended from
    /// them. Area lights (many points) are marched either way.
    /// Off: every light marched (the reference; docs/reports/performance.md times both on the
    /// bunny with a point light and a 16-direction sky: about 20x at dim 256).
    bool sweep = true;
    /// Light the similarity relation's isotropic medium (Medium::isotropic()) rather than the
    /// transport's: for a scatter that will carry no angular moment (the gather kernel, plain
    /// or kept passes), whose forward phase is then the similarity relation's throughout, as
    /// vxf run arranges (lightScene).
    bool similarity = false;
    /// Meshes that block the light entirely (the scene's occluders); null: none.
    const RayScene* occluders = nullptr;
    /// The meshes the medium's level set was made from: shadow rays take their crossings of
    /// the surface there (Medium::Sampler::snapCrossingsTo, missed crossings ignored), and
    /// cross the vacuum up to them in one go; null: on the level set.
    const RayScene* boundary = nullptr;
};

struct DirectLightReport
{
    struct PerLight
    {
        std::string name;
        bool skipped = false;
        std::string why; ///< reason it was skipped
        openvdb::Vec3d fluenceSum{0.0}; ///< Σ over active voxels of its φ0 (energy check)
    };
    std::vector<PerLight> lights;
    /// What the user should know of the medium (a density with no positive value: the image
    /// will show surfaces only).
    std::vector<std::string> warnings;
};

/// T·V for one light sample seen from world point @a xWorld: the medium's transmittance along
/// the sample's path (to its point, or to the medium's bounds for light from outside) times
/// 0 when an occluder mesh lies in between (@a occluders may be null).
openvdb::Vec3d sampleTransmittance(const LightSample& sample, Medium::Sampler& sampler, const Medium& medium, const openvdb::Vec3d& xWorld,
    const MarchOptions& options, const RayScene* occluders = nullptr);

/// Fluence at a voxel from one light: Σ over its samples (LightSampler) of the sample's
/// fluence × sampleTransmittance, taken at Medium::Sampler::mediumPoint: the voxel's centre, or
/// for a rim voxel (centre outside the surface, within half a voxel) the nearest surface
/// point. The rim's medium lies inside; near the terminator and on the shadowed side its
/// centre outside sees the light pass by the limb unattenuated while the surface beneath it
/// is in shadow, and that light went into the scatter passes' source as if it reached the
/// medium. Thick sphere (bench/accuracy/sphere_probe, dim 64 / 96): the side light reaches
/// only through the medium went from +12.4% / +6.1% to +7.9% / +3.9% against Mitsuba, the
/// whole image 2.41% / 1.82% → 2.30% / 1.78%; thick bunny dim 96 rung 2.376% → 2.334%.
/// Volume lights add no fluence (they are a source; see computeDirectLight). Never NaN: a
/// voxel at a point light's position gets the value of a point half a voxel away. With
/// @a flux, adds the light's grey first moment there, Σ grey(fluence)·(direction of travel).
openvdb::Vec3d lightFluence(const LightSampler& light, Medium::Sampler& sampler, const Medium& medium, const openvdb::Coord& voxel,
    const MarchOptions& options, const RayScene* occluders = nullptr, openvdb::Vec3d* flux = nullptr);

/// The light stage's peak: the fixed part, the dense copies its marches read (the density and
/// the surface, as GridLookup makes them: counted as kLightDenseBytesPerVoxel an active voxel, up
/// to two copies' limit) and kLightBytesPerVoxel an active voxel of the medium's density (tiles'
/// voxels counted): what each added voxel took in bench/scale (docs/reports/scale.md: the
/// bunny's dims 256 to 512 41 bytes, the smoke's 256³ to 384³ 70 before its depths were one
/// float), rounded up. The bunny at dim 256: 448 MiB estimated, 391 measured; at dim 1024 with
/// the band 14.7 GiB against 6.6 (the band's tiles are not known before the light is made);
/// the larger figure of dim 256 alone (110 bytes, its dense copies in it) had refused dim 1024
/// on a machine of 22 GiB (docs/accuracy-notes.md (aj)). computeDirectLight checks it against
/// the memory budget before it allocates, `vxf light` from the file's count before it reads.
inline constexpr double kLightBytesPerVoxel = 70.0;
inline constexpr double kLightDenseBytesPerVoxel = 36.0;
/// The light stage's peak for a density of @a voxels active voxels: what computeDirectLight
/// checks, and `vxf light` from the file's count before it reads.
MemoryEstimate lightMemory(double voxels);

/// The light stage. Adds to @a set:
/// - `direct` (Vec3f): φ0 = Σ lights, at every active voxel of `density` (active tiles are
///   voxelized, or with coarseTiles evaluated once at their centre), and one voxel beyond
///   (so trilinear lookups at the surface blend real values);
/// - `scatter_source` (Vec3f): J0 = σs·φ0/(4π) + the emission of volume lights, same topology
///   (0 outside the medium, where σs is 0);
/// - with an anisotropic rest of the phase (medium.material().phaseG ≠ 0),
///   `scatter_source_anisotropy` (Vec3f, Phase.h): J0's mean direction a, J0(ω) = J0·R(a, ω);
///   without, a set's old one is removed.
/// Lights with zero power are skipped and reported. Parallel over leaf nodes (TBB);
/// each voxel is computed on its own, so results do not depend on the number of threads.
/// Throws vxf::InputError for an unreadable volume light or environment map.
DirectLightReport computeDirectLight(VoxelSet& set, const Medium& medium, const std::vector<Light>& lights,
    const DirectLightOptions& options = {}, Interrupter* interrupter = nullptr);

} // namespace vxf
