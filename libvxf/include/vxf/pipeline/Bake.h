// vxf — `vxf bake`: the light vxf solved, handed to another renderer as the grids an
// emission–absorption volume shader reads.
#pragma once

#include <vxf/core/Interrupter.h>
#include <vxf/core/Scene.h>
#include <vxf/core/VoxelSet.h>

#include <nlohmann/json.hpp>

#include <string>

namespace vxf {

/// Which scattering the baked emission carries.
enum class BakedScattering {
    /// All of it: emission σs·(φ0 + φ_ms)/4π, isotropic, over a medium that only absorbs (σt):
    /// an emission–absorption shader reproduces vxf's image (render direct "grid") in any
    /// renderer, whatever its bounce settings.
    All,
    /// Multiple scattering only, σs·φ_ms/4π: the renderer adds single scattering from the same
    /// lights, with the phase, through a scattering medium. Needs a renderer that attenuates
    /// emission by the whole σt; Cycles at volume bounces 0 attenuates it by σa alone (measured:
    /// docs/accuracy-notes.md, "Baked light in Cycles").
    Multiple,
    /// None: the volumes' own emission alone (flames, blackbody), for a renderer that scatters
    /// all of the light itself (a reference: bench/interchange/cycles).
    None,
};

/// What bakeScene made: the baked set and a manifest of what a renderer needs besides its grids.
struct BakedVolume
{
    /// `density` (the medium's, float, where the scene places it: σ = density × the manifest's
    /// coefficients) and `emission` (vec3s, radiance per unit length): σs·φ/4π of vxf's multiple
    /// scattering (the `scatter` grid, edits and all) plus the volume lights' and objects' own
    /// emission, on the medium's voxels.
    VoxelSet set;
    /// The medium's coefficients per unit density (sigma_a, sigma_s, RGB, 1/world unit), its phase
    /// g, and the scene's lights, camera, render settings and opaque objects in world units, for a
    /// renderer's scene (scripts/blender-load-bake builds Blender's from it).
    nlohmann::json manifest;
};

/// How to bake.
struct BakeOptions
{
    BakedScattering scattering = BakedScattering::All;
    /// Baked voxels a side to each of the medium's (1 to kBakeMaxSupersampling), or 0:
    /// bakeSupersampling's choice. A renderer reads a voxel grid's boundary as a ramp a voxel
    /// wide, where vxf's mesh medium ends at its surface: finer voxels hold the surface closer.
    int supersample = 0;
};

/// The supersampling a mesh medium is baked at by default (a volume object's: 1, its own voxels).
inline constexpr int kBakeSurfaceSupersampling = 2;
inline constexpr int kBakeMaxSupersampling = 4;

/// The supersampling of a bake of @a set (the scatter stage's): @a requested, or for 0
/// kBakeSurfaceSupersampling where the set has a `surface` (a mesh medium), else 1.
int bakeSupersampling(const VoxelSet& set, int requested);

/// Run @a scene's pipeline (cached in @a outDir/cache, as vxf run) up to the scatter stage and
/// bake it, as @a scattering says: all the scattered light as emission over an absorbing medium,
/// or only the multiple scattering, the renderer adding its own single scattering from the same
/// lights. For an isotropic medium either gives vxf's image. With a phase g ≠ 0 vxf solved the
/// multiple scattering in the transport's reduced medium (Phase.h) and the emission is that
/// light's isotropic part, an approximation the manifest names. Throws vxf::Error as runPipeline does.
BakedVolume bakeScene(const Scene& scene, const std::string& outDir, const BakeOptions& options = {}, Interrupter* interrupter = nullptr);

} // namespace vxf
