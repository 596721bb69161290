// `vxf demo`: the main job on the embedded default scene (no downloads): a candle whose
// flame is a point light makes the wax glow. It is `vxf run` on examples/candle.json,
// compiled in.
#include "CliSupport.h"
#include "Commands.h"

#include <vxf/pipeline/RunPipeline.h>

#include <fmt/format.h>

#include <filesystem>
#include <iostream>

namespace vxf::cli {

namespace {

class DemoCommand : public Command
{
public:
    explicit DemoCommand(CLI::App& parent)
    {
        mApp = parent.add_subcommand("demo",
            "Run the main job on the embedded default scene (examples/candle.json: a wax candle lit by its flame): "
            "voxelize, light, scatter, render to OUT/demo.exr and OUT/demo.png, keeping the voxel set as OUT/demo.vdb. "
            "Stages are cached in OUT/cache as for `vxf run`.");
        mApp->add_option("--out", mOut, "Output folder (default: out)");
        mApp->add_option("--dim", mDim, "Voxels along the candle's height (default: the scene's)")->check(CLI::Range(8, 4096));
        mApp->add_option("--width", mWidth, "Image width (default: the scene's)")->check(CLI::Range(1, 32768));
        mApp->add_option("--height", mHeight, "Image height (default: the scene's)")->check(CLI::Range(1, 32768));
    }

    void run() override
    {
        TerminalProgress progress;
        const auto start = std::chrono::steady_clock::now();
        // The scene's "path" names the outputs (demo.exr, demo.png); its mesh is built in.
        Scene scene = parseScene(demoSceneText(), "demo.json");
        if (mDim) scene.settings.dim = mDim;
        if (mWidth) scene.settings.width = mWidth;
        if (mHeight) scene.settings.height = mHeight;
        const PipelineReport report = runPipeline(scene, mOut, &progress);
        const std::string volume = (std::filesystem::path(mOut) / "demo.vdb").string();
        std::filesystem::copy_file(report.volume, volume, std::filesystem::copy_options::overwrite_existing);

        std::cout << fmt::format("demo: a wax candle lit by its flame (embedded scene, {} voxels along its height)\n", scene.settings.dim);
        for (const auto& stage : report.stages) {
            std::cout << fmt::format("  {:<9} {:<7} {:>7.2f} s  {}\n", stage.stage, stage.action, stage.seconds, stage.why);
        }
        std::cout << fmt::format("  wrote {}, {}, {} in {:.2f} s\n", report.image, report.preview, volume, secondsSince(start));
    }

private:
    std::string mOut = "out";
    int mDim = 0, mWidth = 0, mHeight = 0;
};

} // namespace

std::unique_ptr<Command> makeDemoCommand(CLI::App& parent) { return std::make_unique<DemoCommand>(parent); }

} // namespace vxf::cli
