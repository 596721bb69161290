// vxf — a scene's objects, materials, lights, camera and settings: the types every stage reads
// (the scene file's reader is vxf/pipeline/SceneFile.h; its schema schemas/scene.schema.json).
#pragma once

#include <vxf/core/Quality.h>
#include <vxf/core/StageDefaults.h>

#include <openvdb/Types.h>

#include <optional>
#include <string>
#include <vector>

namespace vxf {

/// Participating medium coefficients per world unit (linear RGB), resolved from either
/// sigma_a + sigma_s or albedo + mean free path.
struct Material
{
    openvdb::Vec3d sigmaA{0.0}, sigmaS{0.0};
    std::string gridsFile; ///< optional .vdb with per-voxel coefficient grids ("" if none)
    std::string sigmaAGrid, sigmaSGrid; ///< their names in gridsFile ("" if not given)
    /// Henyey-Greenstein asymmetry of the phase function, in [−kMaxPhaseG, kMaxPhaseG]: 0
    /// isotropic, > 0 forward (smoke, clouds, skin), < 0 backward. Medium takes the transport's
    /// coefficients reduced by it (vxf/transport/Phase.h); the camera's single scattering the phase.
    double phaseG = 0.0;

    openvdb::Vec3d sigmaT() const { return sigmaA + sigmaS; }
    /// sigma_s / sigma_t per channel (0 where sigma_t is 0).
    openvdb::Vec3d albedo() const;
    /// Whether any channel scatters (scattering passes are needed at all).
    bool scatters() const { return sigmaS[0] > 0.0 || sigmaS[1] > 0.0 || sigmaS[2] > 0.0; }
};

/// How an object's surface reflects the lights (the render's surface term).
struct SurfaceShading
{
    openvdb::Vec3d diffuse{0.0}; ///< Lambert albedo
    openvdb::Vec3d specular{0.0}; ///< normalized Blinn-Phong: specular·(e+8)/(8π)·(n·h)^e
    double shininess = 64.0; ///< e
    openvdb::Vec3d emission{0.0}; ///< radiance emitted toward the camera (occluders and emitters)
    bool reflects() const { return diffuse != openvdb::Vec3d(0.0) || specular != openvdb::Vec3d(0.0); }
};

/// Where a volume file's voxel (i, j, k) lies. OpenVDB and Houdini centre it on the grid's
/// transform of (i, j, k); Blender and Cycles spread it over the cell from (i, j, k) to
/// (i+1, j+1, k+1) (measured: Cycles renders a block of voxels 0..9 centred on 5, not 4.5, in
/// voxel units), half a voxel further along each axis. Auto: as the file's writer does
/// (io/VoxelPlacement.h).
enum class VoxelPlacement { Auto, Centre, Cell };

struct SceneObject
{
    /// Medium: its interior is the participating medium. Occluder: opaque, casts shadows.
    /// Emitter: opaque to camera rays and seen by its emission, but casts no shadows (a light
    /// of the scene stands for what it emits: a flame around a point light, a bulb).
    enum class Role { Medium, Occluder, Emitter };
    std::string name;
    std::string mesh; ///< resolved path (relative to the scene file) or builtin:NAME; "" for a volume
    /// A medium given as a grid instead of a mesh (smoke, clouds, fog volumes from Houdini,
    /// Blender or vdb_tool): the resolved path of a .vdb whose float grid @c grid is its
    /// density, σ = density × the material's coefficients, on the grid's own voxels; "" for a mesh.
    std::string volume;
    std::string grid = "density";
    VoxelPlacement placement = VoxelPlacement::Auto; ///< a volume object's voxels (its emission's too)
    bool isVolume() const { return !volume.empty(); }
    openvdb::Mat4d objectToWorld; ///< scale, then rotate x, y, z (degrees), then translate
    Role role = Role::Medium;
    std::optional<Material> material; ///< present for media
    SurfaceShading surface; ///< diffuse 0.5 by default for occluders, 0 for media and emitters
};

/// The strongest light a scene may hold (intensity × its largest colour channel, in the light's
/// own units): 18 orders of magnitude below float's 3.4e38, for what the stages multiply a light
/// by (1/r² near a point light, σs, the passes' sums).
inline constexpr double kMaxLightPower = 1e20;

struct Light
{
    enum class Type { Point, Spot, Directional, Area, Volume, Environment };
    enum class Falloff { InverseSquare, Linear, None };
    enum class Shape { Rectangle, Disk, Sphere };
    Type type = Type::Point;
    std::string name;
    openvdb::Vec3d color{1.0};
    double intensity = 1.0;
    Falloff falloff = Falloff::InverseSquare;
    openvdb::Vec3d position{0.0};
    openvdb::Vec3d direction{0.0, 0.0, -1.0}; ///< unit length; where the light shines
    double coneAngleDegrees = 0.0, coneSoftnessDegrees = 0.0;
    Shape shape = Shape::Rectangle;
    double width = 1.0, height = 1.0, radius = 0.5;
    int samples = 16;
    std::string file, grid; ///< volume light grid / environment map (resolved path)
    /// Volume light: where its grid is placed, after the grid's own transform (a volume object's
    /// emission moves with the object: its objectToWorld; a `volume` light of the scene: identity).
    openvdb::Mat4d gridToWorld = openvdb::Mat4d::identity();
    VoxelPlacement placement = VoxelPlacement::Auto; ///< volume light: where its grid's voxels lie
    /// Volume light: > 0 makes its float grid a temperature, Kelvin = value × this (Blender's
    /// Principled Volume Temperature), emitting blackbody light (light/Blackbody.h) × colour ×
    /// intensity; 0: the grid's values are the radiance per unit length.
    double blackbodyKelvin = 0.0;

    /// Radiant colour: color × intensity.
    openvdb::Vec3d power() const { return color * intensity; }
};

struct Camera
{
    bool orthographic = false;
    openvdb::Vec3d position{0.0, 0.0, 5.0}, lookAt{0.0}, up{0.0, 0.0, 1.0};
    double fovDegrees = 40.0;
    double width = 2.0; ///< orthographic view width
};

struct SceneSettings
{
    int dim = defaults::kDim;
    double voxelSize = 0.0; ///< when > 0 it wins over dim
    double band = defaults::kBand;
    int passes = defaults::kPasses, directions = defaults::kDirections;
    double step = defaults::kStep, tolerance = defaults::kTolerance;
    double cutoff = defaults::kScatterCutoff; ///< scatter marches stop below this transmittance (ScatterPassOptions::cutoff)
    bool extrapolate = false;
    double scatterBand = 0.0; ///< 0: full resolution everywhere
    int finePasses = 0, coarseFactor = defaults::kCoarseFactor; ///< passes after finePasses on a coarser lattice (0: none)
    std::string kernel = "gather"; ///< the scatter kernel by name (scatterKernelNamed)
    bool accelerate = true; ///< diffusion-accelerated sweeps or gathers (ScatterOptions::accelerate)
    int width = defaults::kWidth, height = defaults::kHeight, samples = defaults::kSamples, gatherDirections = defaults::kGatherDirections;
    int maxSamples = 0; ///< adaptive sampling up to this many rays per pixel (≤ samples: off)
    double noiseLevel = defaults::kNoiseLevel; ///< refine pixels whose mean luminance has a larger relative standard error
    bool gather = false, surface = true;
    bool directFromLights = false; ///< render "direct": "lights" (single scattering marched per step)
    openvdb::Vec3d background{0.0};
    std::vector<std::string> outputs{"image"};
    /// Set when the scene (or `vxf run --error`) asked for an error: the setting chosen for it,
    /// already written into the fields above where the scene left them unset.
    std::optional<QualityChoice> quality;
};

struct Scene
{
    std::string path; ///< the file it was read from
    /// The frame it was read at (an animated scene: `vxf run --frames`); images are then
    /// named NAME.0001.exr. None for a still scene read as one.
    std::optional<int> frame;
    std::vector<SceneObject> objects;
    std::vector<Light> lights;
    Camera camera;
    SceneSettings settings;
};

} // namespace vxf
