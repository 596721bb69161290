// `vxf light IN.vdb --scene S.json -o OUT.vdb [--step H] [--cutoff C] [--march] [--half] [-q]`: --scene and the options
// after it are the light operator's parameters (pipeline/Operators.cc), declared there once.
#include "CliSupport.h"
#include "Commands.h"
#include "OperatorOptions.h"

#include <vxf/core/GridRoles.h>
#include <vxf/core/GridStats.h>
#include <vxf/io/VoxelPlacement.h>
#include <vxf/io/VoxelSetFile.h>
#include <vxf/light/DirectLight.h>
#include <vxf/pipeline/LightScene.h>
#include <vxf/pipeline/Operators.h>
#include <vxf/pipeline/SceneMedium.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <iostream>

namespace vxf::cli {

namespace {

class LightCommand : public Command
{
public:
    explicit LightCommand(CLI::App& parent)
    {
        mApp = parent.add_subcommand("light",
            "Light a voxel set: `direct` (fluence from the scene's lights through the medium, Beer-Lambert) and "
            "`scatter_source` (sigma_s direct / 4 pi + volume-light emission).");
        mApp->add_option("input", mInput, "Voxel set with `density` (from vxf voxelize)")->required();
        mApp->add_option("-o,--output", mOutput, "Output .vdb (all input grids + direct + scatter_source)")->required()->check(OutputFile);
        mParams = std::make_unique<OperatorOptions>(*mApp, findOperator("light"), true);
        mApp->add_flag("--half", mWrite.half, "Store floats as 16-bit halves");
        mApp->add_flag("-q,--quiet", mQuiet, "No summary");
    }

    void run() override
    {
        TerminalProgress progress;
        const auto start = std::chrono::steady_clock::now();
        const ops::Args args = mParams->args();
        mScene = args.text("scene");
        const Scene scene = stageScene(args);
        std::vector<NamedFile> inputs = sceneFiles(scene);
        inputs.push_back({"the input", mInput});
        refuseOverwrites(inputs, {{"-o", mOutput}});
        const DirectLightOptions options = lightOptions(args, scene.settings);
        // Refused before the read when the file's own count says the volume will not fit.
        if (const std::uint64_t voxels = declaredVoxels(mInput, inputDensity(scene))) requireMemory("light", lightMemory(double(voxels)));
        VoxelSet set = placedInput(scene, &progress);
        const DirectLightReport report = lightScene(set, scene, options, &progress);
        nlohmann::json params = args.json();
        params.update({{"command", "light"}, {"input", mInput}, {"step", options.march.step}});
        set.setProvenance("light", params.dump());
        writeVoxelSet(mOutput, set, mWrite);
        if (mQuiet) return;
        std::cout << fmt::format("lit {} -> {} ({} active voxels)\n", mInput, mOutput, gridStats(*set.find("direct")).activeVoxels);
        for (const auto& warning : report.warnings) warn(warning);
        for (const auto& light : report.lights) {
            if (light.skipped) {
                std::cout << fmt::format("  {:<16} skipped: {}\n", light.name, light.why);
            } else if (!light.why.empty()) {
                std::cout << fmt::format("  {:<16} {}\n", light.name, light.why);
            } else {
                std::cout << fmt::format("  {:<16} sum of fluence over voxels ({:.4g}, {:.4g}, {:.4g})\n", light.name, light.fluenceSum[0],
                    light.fluenceSum[1], light.fluenceSum[2]);
            }
        }
        std::cout << fmt::format("  seconds       {:.3f}\n", secondsSince(start));
    }

private:
    /// The input's density grid: the scene's volume object's own grid where the input is its file.
    std::string inputDensity(const Scene& scene) const
    {
        std::error_code error;
        for (const SceneObject& o : scene.objects) {
            if (o.role == SceneObject::Role::Medium && o.isVolume() && std::filesystem::equivalent(o.volume, mInput, error)) return o.grid;
        }
        return grids::kDensity;
    }

    /// The input set where the scene's medium lies. A volume object's own file is placed as
    /// vxf run places it (moved by the object's transform, its voxels where their writer puts
    /// them: io/VoxelPlacement.h; coarsened when the scene's `voxelize` asks); a set vxf run voxelized from the
    /// scene already is; any other set is lit where its file places it, with a warning when the
    /// scene's medium has a transform that therefore does not apply.
    VoxelSet placedInput(const Scene& scene, Interrupter* interrupter) const
    {
        const SceneObject* moved = nullptr;
        for (const SceneObject& o : scene.objects) {
            if (o.role == SceneObject::Role::Medium && o.objectToWorld != openvdb::Mat4d::identity()) moved = &o;
        }
        std::error_code error;
        const SceneObject* volume = nullptr; // the scene's volume object whose file is the input
        for (const SceneObject& o : scene.objects) {
            if (o.isVolume() && std::filesystem::equivalent(o.volume, mInput, error)) volume = &o;
        }
        // Moved, or asked for other voxels (the scene's voxelize): placed and coarsened as vxf
        // run does, the file read once.
        const VoxelizeOptions solve = sceneVoxelizeOptions(scene.settings);
        if (volume && (volume == moved || solve.dim > 0 || solve.voxelSize > 0.0)) return voxelizeMedia(scene, solve, interrupter);
        VoxelSet set = readVoxelSet(mInput);
        if (volume && resolvePlacement(volume->placement, volume->volume, set.metadata()).placement == VoxelPlacement::Cell) {
            return voxelizeMedia(scene, solve, interrupter); // its voxels moved half a voxel, as vxf run places them
        }
        if (!moved) return set;
        const std::string params = set.paramsJson();
        const bool fromRun = set.stage() == "voxelize" && params.find("\"media\"") != std::string::npos;
        if (!fromRun) {
            warn(fmt::format("object '{}' of {} has a transform, which {} does not carry: it is lit where its file places it "
                             "(vxf run, or voxelizing the scene's object, places it)",
                moved->name, mScene, mInput));
        }
        return set;
    }

    std::string mInput, mScene, mOutput;
    std::unique_ptr<OperatorOptions> mParams; ///< the light operator's parameters (pipeline/Operators.cc)
    VoxelSetWriteOptions mWrite;
    bool mQuiet = false;
};

} // namespace

std::unique_ptr<Command> makeLightCommand(CLI::App& parent) { return std::make_unique<LightCommand>(parent); }

} // namespace vxf::cli
