// `vxf demo`: the main job on the embedded default scene (no downloads): a candle whose
// flame is a point light makes the wax glow.
#include "CliSupport.h"
#include "Commands.h"

#include <vxf/core/GridStats.h>
#include <vxf/core/ProceduralMesh.h>
#include <vxf/io/ImageFile.h>
#include <vxf/light/DirectLight.h>
#include <vxf/scatter/Scatter.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

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
            "voxelize, light, scatter, render to OUT/demo.exr, OUT/demo.png and OUT/demo.vdb.");
        mApp->add_option("--out", mOut, "Output folder (default: out)");
        mApp->add_option("--dim", mDim, "Voxels along the candle's height (default: the scene's)")->check(CLI::Range(8, 4096));
        mApp->add_option("--width", mWidth, "Image width (default: the scene's)")->check(CLI::Range(1, 32768));
        mApp->add_option("--height", mHeight, "Image height (default: the scene's)")->check(CLI::Range(1, 32768));
    }

    void run() override
    {
        TerminalProgress progress;
        const auto start = std::chrono::steady_clock::now();
        std::filesystem::create_directories(mOut);
        const Scene scene = parseScene(demoSceneText(), "builtin:candle-scene");
        const SceneObject& object = scene.objects.front();
        const Material& material = *object.material;

        auto t = std::chrono::steady_clock::now();
        VoxelizeOptions voxelizeOptions;
        voxelizeOptions.dim = mDim > 0 ? mDim : scene.settings.dim;
        voxelizeOptions.bandWidth = float(scene.settings.band);
        VoxelSet set = voxelize(*builtinMesh(object.mesh), voxelizeOptions, &progress);
        const double voxelizeSeconds = secondsSince(t);

        t = std::chrono::steady_clock::now();
        const Medium medium(set, material);
        DirectLightOptions lightOptions;
        lightOptions.march.step = scene.settings.step;
        computeDirectLight(set, medium, scene.lights, lightOptions, &progress);
        const double lightSeconds = secondsSince(t);

        t = std::chrono::steady_clock::now();
        ScatterOptions scatterOptions;
        scatterOptions.passes = scene.settings.passes;
        scatterOptions.tolerance = scene.settings.tolerance;
        scatterOptions.pass.directions = scene.settings.directions;
        scatterOptions.pass.step = scene.settings.step;
        scatterOptions.extrapolateTail = scene.settings.extrapolate;
        const ScatterReport scattered = scatter(set, medium, scatterOptions, &progress);
        const double scatterSeconds = secondsSince(t);

        t = std::chrono::steady_clock::now();
        RenderOptions renderOptions = renderOptionsFrom(scene.settings);
        if (mWidth) renderOptions.width = mWidth;
        if (mHeight) renderOptions.height = mHeight;
        const RenderedImage image = render(set, medium, scene.camera, renderOptions, &progress);
        const double renderSeconds = secondsSince(t);

        const std::filesystem::path out(mOut);
        set.setProvenance("scatter", nlohmann::json{{"command", "demo"}, {"dim", voxelizeOptions.dim},
                                                    {"passes_run", scattered.passes.size()}}.dump());
        recordMaterial(set, material);
        writeVoxelSet((out / "demo.vdb").string(), set);
        writeExr((out / "demo.exr").string(), image);
        writePng((out / "demo.png").string(), image);

        std::cout << fmt::format("demo: a wax candle lit by its flame (embedded scene, {} voxels along its height)\n",
            voxelizeOptions.dim);
        std::cout << fmt::format("  voxelize  {:>7.2f} s   {} active voxels\n", voxelizeSeconds,
            gridStats(*set.find("density")).activeVoxels);
        std::cout << fmt::format("  light     {:>7.2f} s   {} lights\n", lightSeconds, scene.lights.size());
        std::cout << fmt::format("  scatter   {:>7.2f} s   {} passes ({})\n", scatterSeconds, scattered.passes.size(),
            scattered.stopReason);
        std::cout << fmt::format("  render    {:>7.2f} s   {}x{}, {} samples per pixel\n", renderSeconds, renderOptions.width,
            renderOptions.height, renderOptions.samples);
        std::cout << fmt::format("  wrote {}, {}, {} in {:.2f} s\n", (out / "demo.exr").string(), (out / "demo.png").string(),
            (out / "demo.vdb").string(), secondsSince(start));
    }

private:
    std::string mOut = "out";
    int mDim = 0, mWidth = 0, mHeight = 0;
};

} // namespace

std::unique_ptr<Command> makeDemoCommand(CLI::App& parent) { return std::make_unique<DemoCommand>(parent); }

} // namespace vxf::cli
