// `vxf bake S.json -o OUT.vdb`: the light vxf solved, as grids another renderer's volume shader
// reads (`density`, `emission`) and a manifest of the scene around them (OUT.json).
#include "CliSupport.h"
#include "Commands.h"

#include <vxf/io/AtomicFile.h>
#include <vxf/io/VoxelSetFile.h>
#include <vxf/pipeline/Bake.h>
#include <vxf/pipeline/SceneFile.h>

#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>

namespace vxf::cli {

namespace {

class BakeCommand : public Command
{
public:
    explicit BakeCommand(CLI::App& parent)
    {
        mApp = parent.add_subcommand("bake",
            "Hand vxf's light to another renderer (Cycles, Karma, Arnold): run the scene up to the scatter stage (cached in "
            "OUT/cache as vxf run) and write a .vdb of `density` (the medium, placed in the world) and `emission` (vec3s, "
            "radiance per unit length: vxf's scattered light, edits and all, plus the volumes' own emission; --scattering "
            "says which orders), and beside it a manifest (.json) of the coefficients per unit density, the phase, the "
            "lights and the camera. scripts/blender-load-bake builds that scene in Blender.");
        mApp->add_option("scene", mScene, "Scene file")->required();
        mApp->add_option("-o,--output", mOutput, "The baked .vdb (its manifest: the same name, .json)")->required()->check(OutputFile);
        mApp->add_option("--out", mOut, "Folder of the stage cache (default: out)");
        mApp->add_option("--frame", mFrame, "The frame of an animated scene");
        mApp->add_option("--scattering", mScattering,
                "all: every order of scattering as emission over a medium that only absorbs (an emission-absorption shader "
                "reproduces vxf's image in any renderer; the default); multiple: multiple scattering only, the renderer adding "
                "single scattering from the same lights (Cycles at volume bounces 0 does not attenuate emission by the scattering "
                "part of the medium: use all there); none: the volumes' own emission alone, for a renderer that scatters all "
                "the light itself")
            ->check(CLI::IsMember({"all", "multiple", "none"}));
        mApp->add_option("--supersample", mOptions.supersample,
                fmt::format("Baked voxels a side to each of the medium's, 1 to {}: a renderer reads a grid's edge as a ramp a voxel "
                            "wide where a mesh medium ends at its surface (default: {} for a mesh medium, 1 for a volume)",
                    kBakeMaxSupersampling, kBakeSurfaceSupersampling))
            ->check(CLI::Range(1, kBakeMaxSupersampling));
    }

    void run() override
    {
        const auto start = std::chrono::steady_clock::now();
        TerminalProgress progress;
        const std::string manifestPath = std::filesystem::path(mOutput).replace_extension(".json").string();
        std::error_code error;
        if (std::filesystem::equivalent(mScene, manifestPath, error)) {
            throw UsageError(fmt::format("the bake's manifest {} would replace the scene {}: give the bake another name (-o {})",
                manifestPath, mScene,
                (std::filesystem::path(mOutput).parent_path() / (std::filesystem::path(mOutput).stem().string() + "-baked.vdb")).string()));
        }
        const Scene scene = loadScene(mScene, mFrame);
        refuseOverwrites(sceneFiles(scene), {{"-o", mOutput}, {"the manifest", manifestPath}});
        mOptions.scattering = mScattering == "multiple" ? BakedScattering::Multiple
            : mScattering == "none"                     ? BakedScattering::None
                                                        : BakedScattering::All;
        BakedVolume baked = bakeScene(scene, mOut, mOptions, &progress);
        baked.manifest["vdb"] = std::filesystem::path(mOutput).filename().string();
        writeVoxelSet(mOutput, baked.set);
        writeAtomically(manifestPath, [&](const std::string& tmp) {
            std::ofstream file(tmp);
            file << baked.manifest.dump(2) << "\n";
            if (!file) throw Error(fmt::format("{}: cannot write", manifestPath));
        });
        std::cout << fmt::format("wrote {} (density, emission) and {} in {:.2f} s\n", mOutput, manifestPath, secondsSince(start));
    }

private:
    std::string mScene, mOutput, mOut = "out", mScattering = "all";
    std::optional<int> mFrame;
    BakeOptions mOptions;
};

} // namespace

std::unique_ptr<Command> makeBakeCommand(CLI::App& parent) { return std::make_unique<BakeCommand>(parent); }

} // namespace vxf::cli
