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
/// the light stage and show in the render.
PipelineReport runPipeline(const Scene& scene, const std::string& outDir, Interrupter* interrupter = nullptr);

} // namespace vxf
