// `vxf run S.json [--out DIR]`: the whole pipeline, doing only what the scene needs.
#include "CliSupport.h"
#include "Commands.h"

#include <vxf/pipeline/RunPipeline.h>
#include <vxf/pipeline/SceneFile.h>
#include <vxf/pipeline/SceneGeometry.h>

#include <fmt/format.h>

#include <iostream>
#include <set>

namespace vxf::cli {

namespace {

class RunCommand : public Command
{
public:
    explicit RunCommand(CLI::App& parent)
    {
        mApp = parent.add_subcommand("run",
            "Run voxelize -> light -> scatter -> render for a scene, simulating only what it calls for: stage outputs "
            "are cached by a hash of their inputs (OUT/cache), so changing only the camera re-renders only.");
        mApp->add_option("scene", mScene, "Scene file")->required();
        mApp->add_option("--out", mOut, "Output folder (default: out)");
    }

    void run() override
    {
        TerminalProgress progress;
        const auto start = std::chrono::steady_clock::now();
        const Scene scene = loadScene(mScene);
        const PipelineReport report = runPipeline(scene, mOut, &progress);
        // What repairing the meshes did, once per file, as `vxf voxelize` says it.
        std::set<std::string> told;
        for (const auto& object : scene.objects) {
            if (object.isVolume() || !told.insert(object.mesh).second) continue;
            for (const auto& warning : objectMeshWarnings(object)) warn(fmt::format("{}: {}", object.mesh, warning));
        }
        for (const auto& warning : report.warnings) warn(warning);
        for (const auto& stage : report.stages) {
            std::cout << fmt::format("  {:<9} {:<7} {:>7.2f} s  {}\n", stage.stage, stage.action, stage.seconds, stage.why);
        }
        if (!report.image.empty()) std::cout << fmt::format("wrote {} and {}", report.image, report.preview);
        std::cout << fmt::format(" in {:.2f} s\n", secondsSince(start));
    }

private:
    std::string mScene, mOut = "out";
};

} // namespace

std::unique_ptr<Command> makeRunCommand(CLI::App& parent) { return std::make_unique<RunCommand>(parent); }

} // namespace vxf::cli
