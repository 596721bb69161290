// vxf — the renderer: camera rays hit the surface, then gather the volume's glow.
#pragma once

#include <vxf/core/Interrupter.h>
#include <vxf/core/MemoryBudget.h>
#include <vxf/core/StageDefaults.h>
#include <vxf/core/RayScene.h>
#include <vxf/transport/Medium.h>
#include <vxf/core/RenderedImage.h>
#include <vxf/core/Scene.h>
#include <vxf/io/VoxelSetFile.h>

#include <set>
#include <string>
#include <vector>

namespace vxf {

struct RenderOptions
{
    int width = defaults::kWidth, height = defaults::kHeight;
    int samples = defaults::kSamples; ///< camera rays per pixel (stratified, deterministic jitter)
    /// Adaptive sampling: a pixel whose first `samples` rays disagree (some hit and some miss,
    /// they hit different objects, or the standard error of their mean luminance is above
    /// noiseLevel of the mean), or met something else than a neighbour's first rays (a
    /// silhouette clipping the pixel between its first rays), gets more, up to maxSamples in
    /// all. Silhouettes and a noisy light get the rays; smooth interiors keep `samples`.
    /// ≤ samples: off.
    int maxSamples = 0;
    double noiseLevel = defaults::kNoiseLevel;
    bool gather = false; ///< false: "view" mode (physical); true: the thesis's final gather
    int gatherDirections = defaults::kGatherDirections; ///< cosine-weighted directions per hit in gather mode
    bool surface = true; ///< add the surface term of objects whose surface reflects
    /// Single scattering marched to the lights at every step of a camera ray (shadow rays
    /// through the medium and occluders), instead of interpolated from the `direct` grid:
    /// exact where the direct light falls off within a voxel (dense media, coarse voxels),
    /// at the cost of one shadow march per light and step (a light of many samples gives one,
    /// chosen at random and weighted by their count); ignores edits of `direct`. With a forward
    /// phase, through the transport's scaled medium, the phase itself toward the camera
    /// (MarcherInputs::scaled: delta-M's single-scattering correction).
    bool directFromLights = false;
    openvdb::Vec3d background{0.0};
    double step = defaults::kStep; ///< march step, voxels
    double cutoff = defaults::kRenderCutoff; ///< stop marching below this transmittance
};

/// "P% of the pixels refined to M samples", or empty when adaptive sampling refined none.
std::string refinedSummary(const RenderedImage& image, const RenderOptions& options);

/// Render options from a scene's settings.
RenderOptions renderOptionsFrom(const SceneSettings& settings);

/// The meshes camera and shadow rays meet (ids: indices in Scene::objects), or none.
struct RenderMeshes
{
    const RayScene* visible = nullptr; ///< every object; null: camera rays hit the `surface` level set
    const RayScene* occluders = nullptr; ///< the occluders only (shadows of the surface term); may be null
    const RayScene* media = nullptr; ///< the media only: where camera and shadow rays cross the surface (may be null)
};

/// The render stage's peak from the grids it reads (renderGrids) and its image: each grid's
/// tree held, with the copies its lookups make (the continued interior field, the source's
/// layers), kRenderBytesPerGridByte of its bytes; the surface level set kRenderBytesPerSurfaceByte
/// of its own (the source's layers and the band's voxels near the surface grow with it); the
/// dense copies where they are made (GridFootprint); and the image's layers, sample tables and
/// EXR, kRenderBytesPerPixel a pixel. Fitted to bench/scale's bunny at dims 256 and 512, full
/// and banded (docs/accuracy-notes.md (aj)): within 1-9% above what each took, where counting
/// the density's active voxels (120 bytes each) had taken a banded volume for a full one.
/// render checks it against the memory budget before it allocates, and `vxf render` from the
/// file's metadata before it reads (a 32768² image is refused at once).
inline constexpr double kRenderBytesPerGridByte = 3.5;
inline constexpr double kRenderBytesPerSurfaceByte = 12.0;
inline constexpr double kRenderBytesPerPixel = 160.0;
/// The render's peak for the footprints of the grids it reads (@a read) at @a options' image size.
MemoryEstimate renderMemory(const std::vector<GridFootprint>& read, const RenderOptions& options);

/// The grids render() reads from its set with @a options: the medium's (Medium::gridsRead),
/// `scatter`, its anisotropy and the source's, and `direct` unless the lights are marched. A
/// stage reading its volume from a file reads these alone (`vxf render`, `vxf run`): a solved
/// set's `scatter_source` and `illumination`, and a DCC file's other grids, stay on disk.
std::set<std::string> renderGrids(const RenderOptions& options);
/// A read of those grids alone (readVoxelSet's options).
VoxelSetReadOptions renderInputRead(const RenderOptions& options);

/// Render the voxel set @a set with @a scene's camera, lights and object shading.
/// Camera rays hit the scene's meshes through Embree (@a meshes.visible), or with no meshes
/// the `surface` level set (OpenVDB's LevelSetRayIntersector, so a .vdb alone renders; its
/// shading is that of the scene's medium object, if any).
/// - Surface term (options.surface, objects whose SurfaceShading reflects): Lambert +
///   normalized Blinn-Phong from the scene's lights, each sample shadowed by occluders and
///   attenuated by the medium (sampleTransmittance), from just off the surface.
/// - Volume term at a medium's surface, view mode: the ray marches on through the medium
///   along the same direction (index-matched boundary): L = ∫ T·J dt + T_exit·L_behind, with
///   J = σs·φ/(4π) per layer: the direct layer's from the `direct` grid read as an
///   InteriorField (continued beyond the surface, log-trilinear), or with
///   options.directFromLights the lights' fluence marched per step; the scatter layer's σs·φ
///   of `scatter` interpolated as one per-voxel quantity, as the scatter passes do; combined,
///   their sum. σt constant over each step and J quadratic through its start, middle and end,
///   integrated exactly (emissionWeights); with a `surface` level set the medium ends sharply
///   at it (Medium::Sampler::interiorScale). L_behind is the first
///   occluder or emitter behind (its surface term) or the background, and the march stops
///   there. Gather mode: the average of such marches over a cosine-weighted hemisphere of
///   directions into the volume, dropping those that leave it at once.
/// Volume lights (VolumeEmission) are seen along every march, in the direct layer, through the
/// medium's own σt, where the medium is.
/// A camera inside the medium (inside its `surface`, or where σt > 0 without one) meets no
/// surface first: every ray marches from the camera as above (gather mode too), alpha 1.
/// Occluders and emitters show their surface term only: their SurfaceShading::emission plus,
/// where the surface reflects, the lit term above (the `surface` layer holds both; emission
/// shows without options.surface too). Missing rays see the background with alpha 0.
/// Parallel over rows; every pixel computed alone, so deterministic for any thread count.
RenderedImage render(const VoxelSet& set, const Medium& medium, const Scene& scene, const RenderOptions& options,
    const RenderMeshes& meshes = {}, Interrupter* interrupter = nullptr);

} // namespace vxf
