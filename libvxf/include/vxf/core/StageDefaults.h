// vxf — the stages' default settings, declared once. The stage options (VoxelizeOptions,
// DirectLightOptions, ScatterOptions, RenderOptions), a scene's settings (SceneSettings), the
// stage operators of a graph and the stage commands' options and help (generated from those
// operators, pipeline/Operators.h) all take their defaults from here.
#pragma once

namespace vxf::defaults {

// voxelize
inline constexpr int kDim = 128; ///< voxels along the mesh's longest side
inline constexpr double kBand = 3.0; ///< narrow band half width, voxels, each side of the surface

// light
inline constexpr double kLightCutoff = 1e-4; ///< the light stage's marches stop below this transmittance

// scatter
inline constexpr int kPasses = 16; ///< at most this many passes
inline constexpr int kDirections = 64; ///< directions per voxel (and per sweep)
inline constexpr double kStep = 1.0; ///< march step, voxels (scatter gathers, light marches, camera rays)
inline constexpr double kTolerance = 1e-3; ///< stop when the rest of the series is known to this fraction of the sum
inline constexpr double kScatterCutoff = 1e-3; ///< a gather stops below this transmittance and adds the light beyond
inline constexpr int kCoarseFactor = 4; ///< passes after fine_passes run on a lattice this much coarser

// render
inline constexpr int kWidth = 640, kHeight = 360;
inline constexpr int kSamples = 4; ///< camera rays per pixel
inline constexpr double kNoiseLevel = 0.02; ///< adaptive sampling: the relative standard error a pixel may keep
inline constexpr int kGatherDirections = 64; ///< gather mode: directions per hit
inline constexpr double kRenderCutoff = 1e-4; ///< camera marches stop below this transmittance

} // namespace vxf::defaults
