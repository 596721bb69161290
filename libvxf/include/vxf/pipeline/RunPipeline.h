// vxf — `vxf run`: voxelize → light → scatter → render for a scene, doing only what it needs.
#pragma once

#include <vxf/core/Interrupter.h>
#include <vxf/core/Scene.h>

#include <string>
#include <vector>

namespace vxf {

struct StageRecord
{
    std::string stage; ///< voxelize, light, scatter, render
    std::string action; ///< "ran", "reused" or "skipped"
    std::string why; ///< one phrase for a person
    std::string file; ///< the stage's output file
    double seconds = 0.0;
};

struct PipelineReport
{
    std::vector<StageRecord> stages;
    std::string image, preview; ///< written image files ("" when no image was asked for)
    std::string volume; ///< the last voxel set of the chain (in the cache)
    /// Cache entries that could not be read (removed and recomputed), and the light stage's
    /// warnings when it ran (a medium with no positive density).
    std::vector<std::string> warnings;
};

struct PipelineOptions
{
    /// Warm start (a sequence's frames, `vxf run --frames --warm-start`): the scatter cache
    /// entry of the frame before (its PipelineReport::volume). Where this frame's medium lies
    /// on the same voxels, its solve starts from that `scatter` and stops by the same rule, in
    /// fewer sweeps; the entry's name joins this frame's scatter key (a warm result is not a
    /// cold one's, to the tolerance). "": start from zero, every frame alike.
    std::string warmStart;
};

/// Run @a scene's pipeline into @a outDir. Each stage's output is cached in
/// outDir/cache/STAGE-HASH.vdb, HASH covering the stage's inputs and parameters (and the
/// hash of the stage before it, and the mesh file's bytes), so a second run reuses what did
/// not change: changing only the camera re-renders only. Scattering is skipped when the
/// material does not scatter or no requested output needs it; lights with zero power are
/// skipped by the light stage; passes stop at the scene's tolerance. Writes
/// outDir/NAME.exr and NAME.png (NAME: the scene file's stem) when "image" is requested.
/// Skip-or-run decisions and seconds are in the report, one record per stage. A cache entry
/// that cannot be read (truncated by a killed machine, or a grid damaged: its checksum) is
/// removed and recomputed, with a warning in the report. Runs sharing a cache compute each
/// entry once: a run finding another computing an entry waits for its file (a lock per entry).
/// Several media objects are voxelized together (voxelizeMedia); occluders cast shadows in
/// the light stage and show in the render. A scene read at a frame (Scene::frame) writes
/// NAME.0001.exr (the frame padded to 4 digits); its stages are cached as any scene's, so the
/// frames of a still mesh under a moving camera voxelize, light and scatter once.
PipelineReport runPipeline(
    const Scene& scene, const std::string& outDir, Interrupter* interrupter = nullptr, const PipelineOptions& options = {});

/// The image runPipeline writes for @a scene into @a outDir: OUT/NAME.exr, NAME the scene
/// file's stem ("scene" for none), OUT/NAME.0001.exr for a scene read at frame 1.
std::string sceneImagePath(const Scene& scene, const std::string& outDir);

/// A file a scene reads beside itself: who reads it ("object 'ball'", "light 'sky'"), as what
/// ("mesh", "volume", "coefficient grids", "file"), and its path.
struct SceneInputFile
{
    std::string owner, kind, path;
};

/// The files @a scene reads beside itself (meshes, volumes, coefficient grids, lights' maps and
/// grids), builtin: meshes left out.
std::vector<SceneInputFile> sceneInputFiles(const Scene& scene);

/// Every input file @a scene reads exists (its meshes, volumes, coefficient grids, light files):
/// InputError naming the scene, the object or light and the missing file otherwise (a sequence's
/// missing frame is found before any frame is rendered).
void requireSceneInputs(const Scene& scene);

} // namespace vxf
