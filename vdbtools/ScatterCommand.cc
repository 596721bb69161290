// `vxf scatter IN.vdb -o OUT.vdb [--passes N] [--directions D] [--step H] [--cutoff C] [--tolerance E] [--keep-passes] [--band W]
// [--from-pass K] [--fine-passes N [--coarse-factor F]] [--kernel gather|sweep] [--no-accelerate]`
#include "CliSupport.h"
#include "Commands.h"

#include <vxf/transport/Medium.h>
#include <vxf/transport/Phase.h>
#include <vxf/pipeline/SceneMedium.h>
#include <vxf/scatter/Scatter.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <iostream>

namespace vxf::cli {

namespace {

class ScatterCommand : public Command
{
public:
    explicit ScatterCommand(CLI::App& parent)
    {
        mApp = parent.add_subcommand("scatter",
            "Scatter the light through the medium in passes (source iteration): `scatter` (sum of the passes), "
            "`illumination` (direct + scatter), `scatter_pass_K` on request. Reads `scatter_source` (or a kept pass) from "
            "the file, so edited grids are honoured.");
        mApp->add_option("input", mInput, "Voxel set from vxf light (density, direct, scatter_source)")->required();
        mApp->add_option("-o,--output", mOutput, "Output .vdb")->required()->check(OutputFile);
        mApp->add_option("--passes", mOptions.passes, "At most this many passes (default 16)")->check(CLI::Range(0, 10000));
        mApp->add_option("--directions", mOptions.pass.directions, "Directions per voxel (default 64)")->check(CLI::Range(1, 65536));
        mApp->add_option("--step", mOptions.pass.step, "March step in voxels (default 1)")->check(CLI::Range(0.01, 64.0));
        mApp->add_option("--cutoff", mOptions.pass.cutoff,
                "A march stops where the transmittance falls below this and adds the light beyond it as the source "
                "held over an unbounded medium (default 1e-3; 1e-2 saves a third of the time for about 0.2% error on thick media)")
            ->check(AboveZero)
            ->check(CLI::Range(0.0, 0.5));
        mApp->add_option("--tolerance", mOptions.tolerance,
                "Stop when the rest of the series, estimated as phi_K r/(1-r), is known to within this fraction of the sum (the passes "
                "have settled into their slowest mode), and add it; accelerated, when the sum's estimated error (its last change times "
                "r/(1-r)) is below it (default 1e-3; 0: never, accelerated 1e-6)")
            ->check(CLI::Range(0.0, 1.0));
        mApp->add_flag("--extrapolate", mOptions.extrapolateTail,
            "After the last pass add the geometric tail phi_K r/(1-r), r = phi_K/phi_(K-1) per voxel");
        mApp->add_option("--band", mOptions.band,
                "Adaptive narrow band, world units: full resolution within W of the surface, the tree's 8^3 and 128^3 "
                "tiles deeper (default 0: full resolution everywhere)")
            ->check(ZeroOrMore);
        mApp->add_option("--fine-passes", mOptions.finePasses,
                "Run the passes after the first N on a coarser lattice: high orders are smooth; their sum returns by "
                "a fine gather and correcting coarse cycles (two fine gathers each) (default 0: all passes at full "
                "resolution)")
            ->check(CLI::Range(0, 10000));
        mApp->add_option("--coarse-factor", mOptions.coarseFactor, "How much coarser that lattice is: 2, 4 or 8 (default 4)")
            ->check(CLI::IsMember({2, 4, 8}));
        mApp->add_option("--kernel", mKernel,
                "How a pass carries light: gather (a ray march per voxel and direction, the thesis's) or sweep "
                "(discrete ordinates: one upwind sweep over the tree per direction, O(1) per voxel and direction) "
                "(default gather; sweep for a forward-scattering phase, g > 0, whose anisotropy only the accelerated "
                "sweeps carry: the gather and plain passes take the similarity relation's isotropic medium)")
            ->check(CLI::IsMember({"gather", "sweep"}));
        mApp->add_flag(
            "--no-accelerate", [this](std::int64_t) { mOptions.accelerate = false; },
            "Plain source iteration, one scattering order per pass. By default either kernel solves the whole sum "
            "with acceleration, where a pass (a sweep of every direction, or a gather) corrects the whole sum and is "
            "no longer one scattering order: each sweep by a diffusion correction, each gather by the sweeps' own "
            "accelerated solve of its change; --keep-passes, --from-pass and --fine-passes need the orders and imply this");
        mApp->add_flag("--keep-passes", mOptions.keepPasses, "Keep each pass as scatter_pass_K");
        mApp->add_option("--from-pass", mOptions.fromPass, "Continue from scatter_pass_K (as edited) instead of scatter_source")
            ->check(CLI::Range(1, 10000));
        mApp->add_option("--scene", mScene, "Take the material from this scene instead of the file's vxf:material");
        mApp->add_flag(
            "--fixed-directions", [this](std::int64_t) { mOptions.pass.rotatePerVoxel = false; },
            "Use the same direction set at every voxel (banding instead of noise)");
        mApp->add_flag("--half", mWrite.half, "Store floats as 16-bit halves");
        mApp->add_flag("-q,--quiet", mQuiet, "No report");
    }

    void run() override
    {
        TerminalProgress progress;
        const auto start = std::chrono::steady_clock::now();
        VoxelSet set = readVoxelSet(mInput);
        const Material material = mScene.empty() ? recordedMaterial(set) : sceneMaterial(loadScene(mScene));
        const Medium medium(set, material);
        if (mKernel.empty()) mKernel = transportScaling(material.phaseG).restG() != 0.0 ? "sweep" : "gather";
        mOptions.pass.kernel = scatterKernelNamed(mKernel);
        const ScatterReport report = scatter(set, medium, mOptions, &progress);
        nlohmann::json params = {{"command", "scatter"}, {"input", mInput}, {"passes", mOptions.passes},
            {"directions", mOptions.pass.directions}, {"step", mOptions.pass.step}, {"cutoff", mOptions.pass.cutoff},
            {"tolerance", mOptions.tolerance}, {"keep_passes", mOptions.keepPasses}, {"band", mOptions.band},
            {"extrapolate", mOptions.extrapolateTail}, {"from_pass", mOptions.fromPass}, {"fine_passes", mOptions.finePasses},
            {"coarse_factor", mOptions.coarseFactor}, {"rotate_per_voxel", mOptions.pass.rotatePerVoxel}, {"kernel", mKernel},
            {"accelerate", mOptions.accelerate}, {"passes_run", report.passes.size()}};
        set.setProvenance("scatter", params.dump());
        recordMaterial(set, material);
        writeVoxelSet(mOutput, set, mWrite);
        if (mQuiet) return;
        std::cout << fmt::format("scattered {} -> {}: {} passes ({})\n", mInput, mOutput, report.passes.size(), report.stopReason);
        if (mOptions.band > 0.0) {
            std::cout << fmt::format("  band {}: {} voxels at full resolution, {} voxels in {} 8^3 and {} 128^3 tiles\n", mOptions.band,
                report.band.fineVoxels, report.band.coarseVoxels, report.band.leafTiles, report.band.internalTiles);
        }
        if (report.accelerated) {
            const bool sweeps = mOptions.pass.kernel == ScatterKernel::Sweep;
            if (sweeps) {
                std::cout << fmt::format("  {} voxels swept per direction ({} directions), {} diffusion unknowns (cells of {}^3 voxels), "
                                         "setup {:.3f} s\n",
                    report.sweptVoxels, mOptions.pass.directions, report.diffusionUnknowns, report.diffusionCoarsening,
                    report.setupSeconds);
            } else {
                std::cout << fmt::format("  {} voxels in the lattice per direction ({} directions), each gather corrected by accelerated "
                                         "sweeps, setup {:.3f} s\n",
                    report.sweptVoxels, mOptions.pass.directions, report.setupSeconds);
            }
            std::cout << fmt::format("  {}  energy of the sum (over voxels, r g b)             change  rate    {}   seconds  ({}, "
                                     "ns/voxel/direction)\n",
                sweeps ? "sweep" : " pass", sweeps ? "diffusion CG" : "corr. sweeps", sweeps ? "sweep" : "gather");
            for (const auto& p : report.passes) {
                const double ns = 1e9 * p.sweepSeconds / std::max(1.0, double(report.sweptVoxels) * mOptions.pass.directions);
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
    std::string mInput, mOutput, mScene, mKernel; ///< empty: by the phase (see --kernel)
    ScatterOptions mOptions;
    VoxelSetWriteOptions mWrite;
    bool mQuiet = false;
};

} // namespace

std::unique_ptr<Command> makeScatterCommand(CLI::App& parent) { return std::make_unique<ScatterCommand>(parent); }

} // namespace vxf::cli
