// `vxf scatter IN.vdb -o OUT.vdb [--passes N] [--directions D] … [--scene S.json] [--half] [-q]`: the options
// after the output are the scatter operator's parameters (pipeline/Operators.cc), declared there once.
#include "CliSupport.h"
#include "Commands.h"
#include "OperatorOptions.h"

#include <vxf/core/GridRoles.h>
#include <vxf/io/VoxelSetFile.h>
#include <vxf/transport/Medium.h>
#include <vxf/transport/Phase.h>
#include <vxf/pipeline/Operators.h>
#include <vxf/pipeline/SceneMedium.h>
#include <vxf/scatter/Scatter.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <iostream>
#include <optional>

namespace vxf::cli {

namespace {

class ScatterCommand : public Command
{
public:
    explicit ScatterCommand(CLI::App& parent)
    {
        const ops::Operator& op = findOperator("scatter");
        mApp =
            parent.add_subcommand("scatter", "Scatter the light through the medium: " + op.summary.substr(op.summary.find(':') + 2) + ".");
        mApp->add_option("input", mInput, "Voxel set from vxf light (density, direct, scatter_source)")->required();
        mApp->add_option("-o,--output", mOutput, "Output .vdb")->required()->check(OutputFile);
        mParams = std::make_unique<OperatorOptions>(*mApp, op, true);
        mApp->add_option("--scene", mScene, "Take the material from this scene instead of the file's vxf:material");
        mApp->add_flag("--half", mWrite.half, "Store floats as 16-bit halves");
        mApp->add_flag("-q,--quiet", mQuiet, "No report");
    }

    void run() override
    {
        TerminalProgress progress;
        const auto start = std::chrono::steady_clock::now();
        const ops::Args args = mParams->args();
        std::optional<Scene> scene;
        if (!mScene.empty()) scene = loadScene(mScene);
        std::vector<NamedFile> inputs = scene ? sceneFiles(*scene) : std::vector<NamedFile>{};
        inputs.push_back({"the input", mInput});
        refuseOverwrites(inputs, {{"-o", mOutput}});
        // Refused before the read when the file's own count says the volume will not fit (with a
        // band, what the sweeps hold is known once its tiles are made: scatter() checks then).
        const bool banded = args.number("band") > 0.0;
        if (const std::uint64_t voxels = banded ? 0 : declaredVoxels(mInput, grids::kDensity)) {
            requireMemory("scatter", scatterMemory(double(voxels)));
        }
        VoxelSet set = readVoxelSet(mInput, scatterInputRead()); // `direct` after the solve
        const Material material = scene ? sceneMaterial(*scene) : recordedMaterial(set);
        const ScatterOptions options = scatterOptions(args, material);
        const ScatterReport report = scatter(set, scatterMedium(set, material, options), options, &progress);
        readGridsInto(set, mInput, {grids::kDirect}, scatterInputRead());
        putIllumination(set);
        nlohmann::json params = args.json();
        params.update({{"command", "scatter"}, {"input", mInput},
            {"kernel", options.pass.kernel == ScatterKernel::Sweep ? "sweep" : "gather"}, {"passes_run", report.passes.size()}});
        set.setProvenance("scatter", params.dump());
        recordMaterial(set, material);
        writeVoxelSet(mOutput, set, mWrite);
        if (mQuiet) return;
        std::cout << fmt::format("scattered {} -> {}: {} passes ({})\n", mInput, mOutput, report.passes.size(), report.stopReason);
        if (options.band > 0.0) {
            std::cout << fmt::format("  band {}: {} voxels at full resolution, {} voxels in {} 8^3 and {} 128^3 tiles\n", options.band,
                report.band.fineVoxels, report.band.coarseVoxels, report.band.leafTiles, report.band.internalTiles);
        }
        if (report.accelerated) {
            const bool sweeps = options.pass.kernel == ScatterKernel::Sweep;
            if (sweeps) {
                std::cout << fmt::format("  {} voxels swept per direction ({} directions), {} diffusion unknowns (cells of {}^3 voxels), "
                                         "setup {:.3f} s\n",
                    report.sweptVoxels, options.pass.directions, report.diffusionUnknowns, report.diffusionCoarsening, report.setupSeconds);
            } else {
                std::cout << fmt::format("  {} voxels in the lattice per direction ({} directions), each gather corrected by accelerated "
                                         "sweeps, setup {:.3f} s\n",
                    report.sweptVoxels, options.pass.directions, report.setupSeconds);
            }
            std::cout << fmt::format("  {}  energy of the sum (over voxels, r g b)             change  rate    {}   seconds  ({}, "
                                     "ns/voxel/direction)\n",
                sweeps ? "sweep" : " pass", sweeps ? "diffusion CG" : "corr. sweeps", sweeps ? "sweep" : "gather");
            for (const auto& p : report.passes) {
                const double ns = 1e9 * p.sweepSeconds / std::max(1.0, double(report.sweptVoxels) * options.pass.directions);
                std::cout << fmt::format("  {:>4}   {:>12.5g} {:>12.5g} {:>12.5g}   {:>7.1e} {:>7.4f} {:>8}   {:>7.3f}  ({:.3f}, {:.1f})\n",
                    p.index, p.energy[0], p.energy[1], p.energy[2], p.change, p.ratio, sweeps ? p.diffusionIterations : p.correctionSweeps,
                    p.seconds, p.sweepSeconds, ns);
            }
            std::cout << fmt::format("  seconds total {:.3f}\n", secondsSince(start));
            return;
        }
        std::cout << "  pass   energy (sum of fluence over voxels, r g b)        ratio   seconds\n";
        for (const auto& p : report.passes) {
            std::cout << fmt::format("  {:>4}   {:>12.5g} {:>12.5g} {:>12.5g}   {:>7.4f}   {:>7.3f}{}\n", p.index, p.energy[0], p.energy[1],
                p.energy[2], p.ratio, p.seconds, p.coarse ? "   (coarse)" : "");
        }
        std::cout << fmt::format("  seconds total {:.3f}\n", secondsSince(start));
    }

private:
    std::string mInput, mOutput, mScene;
    std::unique_ptr<OperatorOptions> mParams; ///< the scatter operator's parameters (pipeline/Operators.cc)
    VoxelSetWriteOptions mWrite;
    bool mQuiet = false;
};

} // namespace

std::unique_ptr<Command> makeScatterCommand(CLI::App& parent) { return std::make_unique<ScatterCommand>(parent); }

} // namespace vxf::cli
