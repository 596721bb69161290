// `vxf render S.json --volume V.vdb -o IMAGE.exr [--png PREVIEW.png] [--width W] … [--half]`: the scene, the output and the
// options but --volume and --half are the render operator's parameters (pipeline/Operators.cc), declared there once.
#include "CliSupport.h"
#include "Commands.h"
#include "OperatorOptions.h"

#include <vxf/core/GridRoles.h>
#include <vxf/io/ImageFile.h>
#include <vxf/io/VoxelSetFile.h>
#include <vxf/transport/Medium.h>
#include <vxf/pipeline/Operators.h>
#include <vxf/pipeline/SceneMedium.h>
#include <vxf/render/Render.h>

#include <fmt/format.h>

#include <iostream>
#include <string>

namespace vxf::cli {

namespace {

class RenderCommand : public Command
{
public:
    explicit RenderCommand(CLI::App& parent)
    {
        mApp = parent.add_subcommand("render",
            "Render a lit voxel set with the scene's camera: rays hit the scene's meshes (Embree; or the `surface` level "
            "set) and gather the volume (view mode: along the camera ray; gather mode: the thesis's final gather), plus "
            "the surface term (Lambert + specular) of objects with a reflecting surface. OpenEXR layers: R G B A, "
            "surface, direct, scatter, depth, normal, samples (camera rays per pixel); optional sRGB PNG preview.");
        mApp->add_option("--volume", mVolume, "Voxel set from vxf scatter (or vxf light)")->required();
        mParams = std::make_unique<OperatorOptions>(
            *mApp, findOperator("render"), true, std::map<std::string, std::string>{{"scene", "scene"}, {"image", "-o,--output"}});
        mApp->get_option("--output")->check(OutputFile);
        mApp->get_option("--png")->check(OutputFile);
        mApp->add_flag("--half", mHalf, "16-bit half EXR channels");
    }

    void run() override
    {
        TerminalProgress progress;
        const auto start = std::chrono::steady_clock::now();
        const ops::Args args = mParams->args();
        const Scene scene = stageScene(args);
        std::vector<NamedFile> inputs = sceneFiles(scene);
        inputs.push_back({"--volume", mVolume});
        refuseOverwrites(inputs, {{"-o", args.text("image")}, {"--png", args.has("png") ? args.text("png") : std::string()}});
        const RenderOptions options = renderOptions(args, scene.settings);
        // Refused before the read when the bytes the file declares for its grids will not fit.
        if (const auto footprints = declaredFootprints(mVolume, renderGrids(options)); !footprints.empty())
            requireMemory("render", renderMemory(footprints, options));
        const VoxelSet set = readVoxelSet(mVolume, renderInputRead(options)); // its grids alone
        Material material;
        if (set.metadata().getMetadata<openvdb::StringMetadata>(kMaterialMetaKey)) {
            material = recordedMaterial(set);
        } else {
            material = sceneMaterial(scene);
        }
        const Medium medium(set, material);
        const RenderedImage image = renderScene(set, medium, scene, options, args.flag("level_set"), &progress);
        const std::string output = args.text("image"), png = args.has("png") ? args.text("png") : std::string();
        writeExr(output, image, mHalf);
        if (!png.empty()) writePng(png, image, args.number("exposure"));
        const std::string adaptive = image.refinedPixels == 0 ? std::string() : ", " + refinedSummary(image, options);
        std::cout << fmt::format("rendered {} ({}x{}, {} samples per pixel{}, {} mode) -> {}{} in {:.3f} s\n", mVolume, options.width,
            options.height, options.samples, adaptive, options.gather ? "gather" : "view", output, png.empty() ? "" : " + " + png,
            secondsSince(start));
    }

private:
    std::string mVolume;
    std::unique_ptr<OperatorOptions> mParams; ///< the render operator's parameters (pipeline/Operators.cc)
    bool mHalf = false;
};

} // namespace

std::unique_ptr<Command> makeRenderCommand(CLI::App& parent) { return std::make_unique<RenderCommand>(parent); }

} // namespace vxf::cli
