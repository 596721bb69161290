// vxf — the subcommands of the `vxf` tool.
#pragma once

#include "CliSupport.h"

#include <vxf/pipeline/RunPipeline.h>

#include <CLI/CLI.hpp>

#include <memory>
#include <vector>

namespace vxf::cli {

/// The scene's own file, then the files it reads beside itself (sceneInputFiles), each named by
/// the object or light that reads it: what a command's outputs must not be (refuseOverwrites).
/// (Here, not in CliSupport: the converters link that, and need no scene.)
inline std::vector<NamedFile> sceneFiles(const Scene& scene)
{
    std::vector<NamedFile> files{{"the scene", scene.path}};
    for (const SceneInputFile& f : sceneInputFiles(scene)) files.push_back({f.owner + "'s " + f.kind, f.path});
    return files;
}

/// A subcommand: registers its options on construction, runs after a successful parse.
class Command
{
public:
    virtual ~Command() = default;
    virtual void run() = 0;
    bool selected() const { return mApp && mApp->parsed(); }

protected:
    CLI::App* mApp = nullptr;
};

std::unique_ptr<Command> makeVoxelizeCommand(CLI::App& parent);
std::unique_ptr<Command> makeInfoCommand(CLI::App& parent);
std::unique_ptr<Command> makeDemoCommand(CLI::App& parent);
std::unique_ptr<Command> makeLightCommand(CLI::App& parent);
std::unique_ptr<Command> makeScatterCommand(CLI::App& parent);
std::unique_ptr<Command> makeRenderCommand(CLI::App& parent);
std::unique_ptr<Command> makeRunCommand(CLI::App& parent);
std::unique_ptr<Command> makeFarmCommand(CLI::App& parent);
std::unique_ptr<Command> makeBakeCommand(CLI::App& parent);
std::unique_ptr<Command> makeOpCommand(CLI::App& parent);
std::unique_ptr<Command> makeGraphCommand(CLI::App& parent);
std::unique_ptr<Command> makeViewCommand(CLI::App& parent);

} // namespace vxf::cli

#include <vxf/io/MeshFile.h>
#include <vxf/io/VoxelSetFile.h>
#include <vxf/voxelize/Voxelize.h>
#include <vxf/pipeline/SceneFile.h>
#include <vxf/render/Render.h>

#include <string>

namespace vxf::cli {

/// What `vxf voxelize` does, shared with `vxf demo`.
struct VoxelizeRequest
{
    std::string mesh; ///< path, or a built-in name such as builtin:candle
    std::string output; ///< .vdb path
    VoxelizeOptions voxelize;
    MeshReadOptions meshRead;
    VoxelSetWriteOptions write;
    bool quiet = false; ///< no summary
};

/// The embedded default scene (examples/candle.json, compiled in).
const std::string& demoSceneText();

/// Read (or build) the mesh, voxelize, write the voxel set with provenance, print warnings
/// and the summary.
void voxelizeToFile(const VoxelizeRequest& request);

} // namespace vxf::cli
