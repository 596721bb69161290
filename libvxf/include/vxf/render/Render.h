// vxf — the renderer: camera rays hit the surface, then gather the volume's glow.
#pragma once

#include <vxf/core/Interrupter.h>
#include <vxf/light/Medium.h>
#include <vxf/pipeline/Scene.h>

#include <vector>

namespace vxf {

struct RenderOptions
{
    int width = 640, height = 360;
    int samples = 4;            ///< camera rays per pixel (stratified, deterministic jitter)
    bool gather = false;        ///< false: "view" mode (physical); true: the thesis's final gather
    int gatherDirections = 64;  ///< cosine-weighted directions per hit in gather mode
    openvdb::Vec3d background{0.0};
    double step = 1.0;          ///< march step, voxels
    double cutoff = 1e-4;       ///< stop marching below this transmittance
};

/// Image layers, row-major from the top-left pixel.
struct RenderedImage
{
    int width = 0, height = 0;
    std::vector<openvdb::Vec3f> combined, direct, scatter, normal;
    std::vector<float> alpha, depth; ///< depth: distance along the camera ray to the surface (0 where it misses)
};

/// Render options from a scene's settings.
RenderOptions renderOptionsFrom(const SceneSettings& settings);

/// Render the voxel set @a set as seen by @a camera. Camera rays hit the `surface` level set
/// (OpenVDB's LevelSetRayIntersector, so a .vdb alone renders). In view mode a ray that hits
/// marches on through the medium along the same direction (index-matched boundary):
/// L = ∫ T·J dt + T_exit·background, with J = σs·φ/(4π) + emission per layer (φ = `direct`
/// for the direct layer, `scatter` for the scatter layer, their sum for combined; each step
/// integrated analytically). In gather mode L is the average of such marches over a
/// cosine-weighted hemisphere of directions into the volume, dropping those that leave it at
/// once. Missing rays see the background with alpha 0. Parallel over rows; deterministic.
RenderedImage render(const VoxelSet& set, const Medium& medium, const Camera& camera, const RenderOptions& options,
    Interrupter* interrupter = nullptr);

} // namespace vxf
