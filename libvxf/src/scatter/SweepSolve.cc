#include <vxf/scatter/SweepSolve.h>

#include <vxf/core/GridRoles.h>
#include "DiffusionCorrection.h"
#include "PassSource.h"

#include <vxf/core/Error.h>
#include <vxf/light/InteriorField.h>
#include <vxf/transport/Phase.h>
#include <vxf/scatter/SweepPass.h>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <utility>

namespace vxf {

namespace {

double secondsSince(std::chrono::steady_clock::time_point start)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// The diffusion correction's relative residual: it only needs to be about as good as the
/// sweeps' convergence rate (about 0.2) makes the next change small (docs/accuracy-notes.md,
/// "Behind the code: SweepSolve").
constexpr double kDiffusionTolerance = 1e-2;

/// The share of the diffusion correction added once it has stalled (the changes stopped
/// falling: in media of a few mean free paths per voxel near albedo 1 the whole correction
/// stalls, and dropping it stops on a false rate). Stalling before sweep kDampAfter (voxels of
/// tens of mean free paths) it is dropped at once (docs/accuracy-notes.md, "Behind the code:
/// SweepSolve").
constexpr double kDampedCorrection = 0.5;
constexpr int kDampAfter = 5;

/// A correction that more than doubles the change it should damp amplifies the error instead:
/// in voxels many mean free paths thick the diffusion correction (and the gathers' sweeps) can
/// overshoot by a factor of tens, the iterates alternating in sign and growing while the change
/// relative to the sum stays near 1 (docs/accuracy-notes.md, "Behind the code: SweepSolve: a
/// correction that amplifies"). The correction is then dropped at once and the iteration
/// restarts from zero: what it built is lost.
constexpr double kDivergentGrowth = 2.0;

/// The gather's correction (transport synthetic acceleration): each gather's change is
/// corrected by the sweeps' own accelerated solve of its scattered light, to this fraction of
/// that solve's sum. The correction's error carries into the gathers' rate, which the sweeps'
/// own difference from the gather already holds at 0.08-0.3: a tighter tolerance buys nothing.
/// At most kSweepCorrectionSweeps sweeps; once the correction's own diffusion correction was
/// dropped (voxels many mean free paths thick, where plain sweeps converge at about the albedo)
/// it runs without and stops after kPlainCorrectionSweeps (docs/accuracy-notes.md, "Behind the
/// code: SweepSolve").
constexpr double kSweepCorrectionTolerance = 1e-2;
constexpr int kSweepCorrectionSweeps = 12;
constexpr int kPlainCorrectionSweeps = 4;

/// The second iteration's change over the first is no convergence rate when the first made the
/// whole estimate (an accelerated solve from zero: it "converged" while off by more than its
/// tolerance, docs/accuracy-notes.md, "Behind the code: SweepSolve"). Accelerated, a second iteration
/// stops only when its change is below this fraction of the tolerance (the sums of a medium that
/// barely scatters); otherwise a third measures the rate.
constexpr double kSecondIterationStop = 0.1;

/// Anderson mixing of depth one (Walker and Ni 2011) for the corrected gathers, whose fixed-point
/// map G (a gather, then its correction) contracts at a rate the sweeps' difference from the
/// gather sets, and may overshoot: where the sweeps' sum lies above the gather's the changes
/// alternate in sign and grow (docs/accuracy-notes.md, "Behind the code: SweepSolve"); mixing
/// brings them back to a steady rate. φ_{l+1} = G_l − γ(G_l − G_{l−1}),
/// γ per channel minimising |f_l − γ(f_l − f_{l−1})|₂, f = G(φ) − φ: interpolation (0 < γ < 1)
/// where the changes alternate, extrapolation (γ < 0) where they shrink slowly; γ is kept
/// within [−2, 0.9] (at most twice the last step beyond it, at least a tenth of the new
/// iterate). Sums in a fixed order: the result does not depend on the thread count.
class AndersonMixing
{
public:
    /// @a next = G(@a phi) in, φ_{l+1} out.
    void mix(const std::vector<openvdb::Vec3f>& phi, std::vector<openvdb::Vec3f>& next)
    {
        const std::size_t count = next.size();
        std::vector<openvdb::Vec3f> f(count);
        for (std::size_t v = 0; v < count; ++v) f[v] = next[v] - phi[v];
        std::vector<openvdb::Vec3f> g = next;
        if (!mF.empty()) {
            openvdb::Vec3d along(0.0), length(0.0);
            for (std::size_t v = 0; v < count; ++v) {
                for (int ch = 0; ch < 3; ++ch) {
                    const double d = double(f[v][ch]) - double(mF[v][ch]);
                    along[ch] += double(f[v][ch]) * d;
                    length[ch] += d * d;
                }
            }
            openvdb::Vec3f gamma(0.0f);
            for (int ch = 0; ch < 3; ++ch) gamma[ch] = length[ch] > 0.0 ? float(std::clamp(along[ch] / length[ch], -2.0, 0.9)) : 0.0f;
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count), [&](const tbb::blocked_range<std::size_t>& r) {
                for (std::size_t v = r.begin(); v != r.end(); ++v) {
                    for (int ch = 0; ch < 3; ++ch) next[v][ch] -= gamma[ch] * (next[v][ch] - mG[v][ch]);
                }
            });
        }
        mG.swap(g);
        mF.swap(f);
    }

private:
    std::vector<openvdb::Vec3f> mG, mF; // the last G(φ) and f
};

/// Σ @a f(v) · (the voxels v stands for: a coarse cell's count) over the lattice, per channel: in
/// parallel over fixed chunks, their sums added in order (the same for every thread count).
template <typename F>
openvdb::Vec3d latticeSum(const detail::SweepLattice& lattice, std::size_t count, F&& f)
{
    constexpr std::size_t kChunk = std::size_t(1) << 16;
    std::vector<openvdb::Vec3d> chunks((count + kChunk - 1) / kChunk, openvdb::Vec3d(0.0));
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t c = r.begin(); c != r.end(); ++c) {
            openvdb::Vec3d sum(0.0);
            for (std::size_t v = c * kChunk; v < std::min(count, (c + 1) * kChunk); ++v) sum += f(v) * lattice.voxelsAt(v);
            chunks[c] = sum;
        }
    });
    openvdb::Vec3d sum(0.0);
    for (const openvdb::Vec3d& chunk : chunks) sum += chunk;
    return sum;
}

openvdb::Vec3d absolute(const openvdb::Vec3f& v) { return openvdb::Vec3d(std::abs(v[0]), std::abs(v[1]), std::abs(v[2])); }

/// Σ |v| per channel over the medium's voxels (a coarse cell's value for each of its voxels).
openvdb::Vec3d l1(const detail::SweepLattice& lattice, const std::vector<openvdb::Vec3f>& values)
{
    return latticeSum(lattice, values.size(), [&](std::size_t v) { return absolute(values[v]); });
}

/// |@a next − @a phi|₁ per channel, as l1.
openvdb::Vec3d l1Change(
    const detail::SweepLattice& lattice, const std::vector<openvdb::Vec3f>& next, const std::vector<openvdb::Vec3f>& phi)
{
    return latticeSum(lattice, next.size(), [&](std::size_t v) { return absolute(next[v] - phi[v]); });
}

/// The accelerated (or plain) iteration of sweepSolve: the lattice and its arrays, one
/// iteration (the transport of a gather or a sweep, its correction, the change it made) and the
/// decisions to stop, halve or drop the correction.
class SweepSolver
{
public:
    SweepSolver(const Medium& medium_, const openvdb::Vec3SGrid& source_, const SweepSolveOptions& options_, SweepSolveReport& report_,
        Interrupter* interrupter_, SweepMoments* moments_)
        : medium(medium_)
        , source(source_)
        , options(options_)
        , report(report_)
        , interrupter(interrupter_)
        , moments(moments_)
        , restG(medium_.material().phaseG)
        , gather(options_.kernel == ScatterKernel::Gather)
        , lattice(checkedLattice(medium_, source_, gather, restG, options_.coarseTiles))
        , count(lattice.voxelCount())
        , accelerate(options_.accelerate)
        , iterations(gather ? "gathers" : "sweeps")
        , iteration(gather ? "gather" : "sweep")
        , correctionName(gather ? "the sweeps' correction" : "the diffusion correction")
    {
        report.voxels = count;
        if (options.accelerate && !gather) {
            diffusion.emplace(lattice,
                options.diffusionCoarsening > 0 ? options.diffusionCoarsening : detail::DiffusionCorrection::coarseningFor(lattice), restG);
            report.diffusionUnknowns = diffusion->size();
            report.diffusionCoarsening = diffusion->coarsening();
            lattice.releaseSigmaT(); // the matrices are built
        }
        report.accelerated = options.accelerate;
        report.setupSeconds = secondsSince(setupStart);

        // J0: the grid as it is, read where the sweep needs it (no per-voxel copy), or continued
        // (readPassSource); the gather reads the grid itself.
        if (!gather && options.source == ScatterPassOptions::SourceRead::Continued) {
            j0 = detail::readPassSource(lattice, medium, source);
        } else if (!gather) {
            j0View.emplace(lattice, source);
        }
        directions = sweepDirections(std::max(options.directions, 1), options.rotationSeed);
        weight = 4.0 * M_PI / double(directions.size());
        if (restG != 0.0) {
            moment.emplace();
            moment->rest = RestPhase(transportScaling(medium.phaseG()));
            for (const openvdb::Vec3d& d : directions) {
                moment->worldDirections.push_back(medium.transform().baseMap()->applyJacobian(d).unit());
            }
            // The direction set's opposite pairs (sweepDirections: ω, −ω in turn), one of each, for
            // the rest's quadrature correction (none for a set of no such pairs): its β·ω a
            // direction's cubic form in a (no β held per voxel).
            const std::vector<openvdb::Vec3d>& world = moment->worldDirections;
            bool paired = world.size() % 2 == 0;
            for (std::size_t i = 0; paired && i < world.size(); i += 2) paired = (world[i] + world[i + 1]).length() < 1e-9;
            std::vector<openvdb::Vec3d> pairFirsts;
            for (std::size_t i = 0; paired && i < world.size(); i += 2) pairFirsts.push_back(world[i]);
            for (std::size_t d = 0; d < world.size() && !pairFirsts.empty(); ++d) {
                moment->corrections.emplace_back(moment->rest, world[d], pairFirsts);
            }
            if (moments && moments->source) a0View.emplace(lattice, *moments->source);
        }
        phi.assign(count, openvdb::Vec3f(0.0f));
        if (options.initial) {
            phi = lattice.read(*options.initial);
            for (openvdb::Vec3f& v : phi) {
                for (int ch = 0; ch < 3; ++ch) v[ch] = std::isfinite(v[ch]) && v[ch] > 0.0f ? v[ch] : 0.0f;
            }
        }
        gatherOptions = options.gather;
        gatherOptions.kernel = ScatterKernel::Gather;
    }

    openvdb::Vec3SGrid::Ptr solve()
    {
        for (int l = 1; l <= std::max(options.maxSweeps, 1); ++l) {
            if (iterate(l)) break;
        }
        return result();
    }

private:
    static detail::SweepLattice checkedLattice(
        const Medium& medium, const openvdb::Vec3SGrid& source, bool gather, double restG, bool coarseTiles)
    {
        if (gather && restG != 0.0) throw UsageError("the accelerated gather carries no anisotropic phase: solve Medium::isotropic()");
        using Lattice = detail::SweepLattice;
        return Lattice(medium, source, Lattice::Coefficients::PerVoxel,
            coarseTiles && !gather ? Lattice::Tiles::Coarse : Lattice::Tiles::Voxelized); // (the gathers read voxels)
    }

    /// Iteration @a l; true when the solve stops after it.
    bool iterate(int l)
    {
        const auto start = std::chrono::steady_clock::now();
        SweepSolveReport::Iteration it;
        if (gather) {
            gatherStep(l, it);
        } else {
            sweepStep(it);
        }
        corrected = false;
        it.index = l;
        if (accelerate) correct(it);
        if (accelerate && gather) mixing.mix(phi, next);
        // How far this sweep moved the sum, per channel relative to it, and how much more (or
        // less) than the sweep before it did.
        const openvdb::Vec3d moved = l1Change(lattice, next, phi);
        const openvdb::Vec3d size = l1(lattice, next);
        it.change = 0.0;
        for (int ch = 0; ch < 3; ++ch) {
            if (size[ch] > 0.0) it.change = std::max(it.change, moved[ch] / size[ch]);
        }
        const double movedLargest = std::max({moved[0], moved[1], moved[2]});
        const double growth = previousAbsolute > 0.0 ? movedLargest / previousAbsolute : 0.0;
        previousAbsolute = movedLargest;
        lastGrowth = growth;
        phi.swap(next);
        it.energy = latticeSum(lattice, count, [&](std::size_t v) { return openvdb::Vec3d(phi[v]); });
        it.ratio = previousChange > 0.0 ? it.change / previousChange : 0.0;
        previousChange = it.change;
        it.error = it.ratio > 0.0 && it.ratio < 1.0 ? it.change * it.ratio / (1.0 - it.ratio) : it.change;
        it.seconds = secondsSince(start);
        report.iterations.push_back(it);
        if (interrupter && interrupter->wasInterrupted(int(100 * l / std::max(options.maxSweeps, 1)))) throw Interrupted();
        if (std::max({size[0], size[1], size[2]}) == 0.0) {
            report.stopReason = "the source is zero";
            report.converged = true;
            return true;
        }
        if (accelerate && growth > kDivergentGrowth) {
            restartWithoutCorrection(l, growth);
            return false;
        }
        const bool rateKnown = l >= 3 || (l == 2 && !options.accelerate); // (kSecondIterationStop)
        if (l == 2 && options.accelerate && it.change <= kSecondIterationStop * options.tolerance) {
            report.converged = true;
            report.stopReason = fmt::format("converged in 2 {} (the change {:.2g} of the sum)", iterations, it.change);
            return true;
        }
        if (rateKnown && it.ratio < 1.0 && it.error <= options.tolerance) {
            report.converged = true;
            report.stopReason = correctionNote +
                fmt::format("converged in {} {} (estimated error {:.2g} of the sum, rate {:.3f})", l, iterations, it.error, it.ratio);
            return true;
        }
        if (l >= 3 && it.ratio >= 1.0 && it.change <= options.tolerance) {
            // The changes stopped falling below the tolerance: the floor the diffusion solve's
            // own residual (1e-2 of each change) leaves, not a divergence.
            report.converged = true;
            report.stopReason = correctionNote +
                fmt::format("converged in {} {} (the change {:.2g} of the sum, below the tolerance, "
                            "stopped falling)",
                    l, iterations, it.change);
            return true;
        }
        if (accelerate && l >= 3 && it.ratio >= 1.0) {
            // The correction overshoots what it should damp (in voxels thicker than a mean free
            // path diffusion is not the sweeps' discretisation). Having helped for a while, it
            // is halved; failing from the start (voxels many mean free paths thick), or again,
            // it is dropped: plain source iteration from here.
            if (damping == 1.0 && l >= kDampAfter) {
                damping = kDampedCorrection;
                correctionNote = fmt::format("{} stalled at {} {} (rate {:.3f}) and was halved; ", correctionName, iteration, l, it.ratio);
            } else {
                accelerate = false;
                report.accelerated = false;
                correctionNote += fmt::format("{} diverged at {} {} (rate {:.3f}) and was dropped; ",
                    correctionNote.empty() ? correctionName : "it", iteration, l, it.ratio);
            }
        }
        return false;
    }

    /// The correction amplified the error (kDivergentGrowth) at iteration @a l: dropped, and the
    /// plain iteration restarted from φ = 0 (every array that carried the amplified iterate
    /// cleared).
    void restartWithoutCorrection(int l, double growth)
    {
        accelerate = false;
        restarted = true;
        report.accelerated = false;
        correctionNote += fmt::format("{} diverged at {} {} (the change grew {:.3g}x) and was dropped, the {} restarted from zero; ",
            correctionNote.empty() ? correctionName : "it", iteration, l, growth, iterations);
        std::fill(phi.begin(), phi.end(), openvdb::Vec3f(0.0f));
        std::fill(flux.begin(), flux.end(), openvdb::Vec3f(0.0f));
        previousCellFlux.clear();
        mixing = AndersonMixing();
        corrected = false;
        damping = 1.0;
        previousChange = 0.0;
        previousAbsolute = 0.0;
        previousMoved = 0.0;
    }

    /// After a restart without the correction, stopped before converging: the plain iteration's
    /// changes are the series' terms, each the one before times the rate r (the slowest mode's,
    /// near the albedo in a thick medium), so the rest of the series, the last change × r/(1−r)
    /// per voxel, is added (as the plain passes' tolerance adds it, Scatter.h). Nothing when the
    /// changes did not fall (r ≥ 1: no rate to trust).
    void addTail()
    {
        if (!(lastGrowth > 0.0 && lastGrowth < 1.0)) return;
        const float factor = float(lastGrowth / (1.0 - lastGrowth));
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t v = r.begin(); v != r.end(); ++v) phi[v] += (phi[v] - next[v]) * factor; // (next: the iterate before)
        });
        report.stopReason += fmt::format("; the rest of the series, the last change x r/(1-r) with r = {:.4f}, added", lastGrowth);
    }

    /// φ_{l+½} = K J0 + K(Sφ_l): J0 read fraction-weighted, Sφ_l continued (SourceField).
    void gatherStep(int l, SweepSolveReport::Iteration& it)
    {
        const auto transportStart = std::chrono::steady_clock::now();
        if (firstFlight.empty()) {
            gatherOptions.source = ScatterPassOptions::SourceRead::FractionWeighted;
            firstFlight = lattice.read(*scatterPass(medium, source, gatherOptions, interrupter));
            gatherOptions.source = ScatterPassOptions::SourceRead::Continued;
        }
        next = firstFlight;
        if (l > 1) {
            const auto scattered =
                lattice.read(*scatterPass(medium, *sourceFromFluence(medium, *lattice.write(phi, source)), gatherOptions, interrupter));
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count), [&](const tbb::blocked_range<std::size_t>& r) {
                for (std::size_t v = r.begin(); v != r.end(); ++v) next[v] += scattered[v];
            });
        }
        it.sweepSeconds = secondsSince(transportStart);
    }

    /// J = J0 + σs·φ/4π, then φ_{l+½} = K J.
    void sweepStep(SweepSolveReport::Iteration& it)
    {
        const detail::SweepLattice::Coefficient sigmaS = lattice.sigmaS();
        const auto sourceAt = [&](std::size_t v) {
            openvdb::Vec3f j;
            const openvdb::Vec3f own = ownSource(v);
            for (int ch = 0; ch < 3; ++ch) j[ch] = own[ch] + sigmaS[v][ch] * phi[v][ch] * float(1.0 / (4.0 * M_PI));
            return j;
        };
        if (moment) {
            // One mean direction for the sum: its parts' a weighted by their grey J, the
            // scattered light's a = F/φ.
            a.resize(count);
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count), [&](const tbb::blocked_range<std::size_t>& r) {
                for (std::size_t v = r.begin(); v != r.end(); ++v) {
                    const double total = greyOf(openvdb::Vec3d(sourceAt(v))), own = greyOf(openvdb::Vec3d(ownSource(v)));
                    const double phiGrey = greyOf(openvdb::Vec3d(phi[v]));
                    openvdb::Vec3d sum = own * openvdb::Vec3d(ownAnisotropy(v));
                    if (phiGrey > 0.0 && !flux.empty()) sum += (total - own) * clampedToUnit(openvdb::Vec3d(flux[v]) / phiGrey);
                    a[v] = total > 0.0 ? openvdb::Vec3f(sum / total) : openvdb::Vec3f(0.0f);
                }
            });
            moment->sourceAnisotropy = &a;
            if (accelerate && diffusion) previousCellFlux = diffusion->cellMeans(flux); // (ΔF a cell's mean, as the correction reads it)
            flux.assign(count, openvdb::Vec3f(0.0f));
            moment->flux = &flux;
        }
        // J made from its parts, no per-voxel J beside it; per voxel, not padded: 11 bytes a
        // voxel less (the thick bunny's peak at dim 256 536 → 486 MB) for a leaf's block gathered
        // once a batch of directions (a few percent of the kernel; free with a moment, whose
        // J·RestPhase makes the block per direction anyway).
        using Layout = detail::SweepLattice::SweepSource::Layout;
        sweepSource = lattice.sweepSource(sourceAt, Layout::PerVoxel, std::move(sweepSource));
        next.assign(count, openvdb::Vec3f(0.0f));
        const auto sweepStart = std::chrono::steady_clock::now();
        lattice.sweep(sweepSource, directions, weight, next, &skin, nullptr, moment ? &*moment : nullptr);
        it.sweepSeconds = secondsSince(sweepStart);
    }

    /// The correction of φ_{l+½} toward the sum: the sweeps' own solve of the gather's change, or
    /// the diffusion correction of the sweep's.
    void correct(SweepSolveReport::Iteration& it)
    {
        if (gather) {
            std::vector<openvdb::Vec3f> change(count);
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count), [&](const tbb::blocked_range<std::size_t>& r) {
                for (std::size_t v = r.begin(); v != r.end(); ++v) change[v] = next[v] - phi[v];
            });
            // δ = (I − K_s S)⁻¹ K_s S (φ_{l+½} − φ_l): the error the gather leaves, as the
            // sweeps would leave it, by their own accelerated solve of the change's scattered
            // light (its skin voxels hold the light on the surface: read at their centres).
            SweepSolveOptions correction;
            correction.kernel = ScatterKernel::Sweep;
            correction.directions = options.directions;
            correction.rotationSeed = options.rotationSeed;
            correction.diffusionCoarsening = options.diffusionCoarsening;
            correction.tolerance = kSweepCorrectionTolerance;
            correction.maxSweeps = correctionAccelerates ? kSweepCorrectionSweeps : kPlainCorrectionSweeps;
            correction.accelerate = correctionAccelerates;
            correction.source = ScatterPassOptions::SourceRead::Continued;
            SweepSolveReport solved;
            const auto delta = lattice.read(
                *sweepSolve(medium, *sourceFromFluence(medium, *lattice.write(change, source)), correction, solved, interrupter));
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count), [&](const tbb::blocked_range<std::size_t>& r) {
                for (std::size_t v = r.begin(); v != r.end(); ++v) next[v] += delta[v] * float(damping);
            });
            it.correctionSweeps = int(solved.iterations.size());
            correctionAccelerates = correctionAccelerates && solved.accelerated;
        } else {
            // Start from the last correction scaled as the change shrank: near albedo 1 the
            // error left is the slowest mode, its shape the same from sweep to sweep.
            // The change φ_{l+½} − φ_l is read as next − phi where it is needed (no array of it).
            const openvdb::Vec3d moved = l1Change(lattice, next, phi);
            const double largest = std::max({moved[0], moved[1], moved[2]});
            const double scale = previousChange > 0.0 ? std::min(1.0, largest / std::max(previousMoved, 1e-300)) : 0.0;
            previousMoved = largest;
            // With a phase, the first moment's change too, a cell's mean (along the lattice's axes).
            std::vector<openvdb::Vec3d> cellFluxChange;
            if (moment) {
                const openvdb::math::MapBase& map = *medium.transform().baseMap();
                const double dx = medium.voxelSize();
                cellFluxChange = diffusion->cellMeans(flux);
                for (std::size_t c = 0; c < cellFluxChange.size(); ++c) {
                    const openvdb::Vec3d d = previousCellFlux.empty() ? cellFluxChange[c] : cellFluxChange[c] - previousCellFlux[c];
                    cellFluxChange[c] = map.applyInverseJacobian(d) * dx;
                }
            }
            const auto solved =
                diffusion->solve(next, phi, scale, kDiffusionTolerance, 1000, cellFluxChange.empty() ? nullptr : &cellFluxChange);
            corrected = true;
            it.diffusionIterations = solved.iterations;
            it.diffusionResidual = solved.residual;
            diffusion->addTo(next, damping);
        }
    }

    openvdb::Vec3SGrid::Ptr result()
    {
        if (!report.converged) {
            report.stopReason = correctionNote +
                fmt::format("stopped after {} {}, estimated error {:.2g} of the sum", report.iterations.size(), iterations,
                    report.iterations.empty() ? 0.0 : report.iterations.back().error);
            if (restarted) addTail();
        }
        // The solve's arrays go before the grids are made (φ itself becomes the output's values).
        sweepSource = {};
        std::vector<openvdb::Vec3f>().swap(next);
        std::vector<openvdb::Vec3d>().swap(previousCellFlux);
        // The skin voxels hold the fluence on the surface, as the gathers give it.
        std::vector<openvdb::Vec3f> shift;
        if (corrected) {
            shift.assign(count, openvdb::Vec3f(0.0f));
            diffusion->addTo(shift, damping);
        }
        if (moment && moments) {
            // a = F/φ at the centres (the skin's too: the correction is isotropic, F the last sweep's).
            a.resize(count);
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count), [&](const tbb::blocked_range<std::size_t>& r) {
                for (std::size_t v = r.begin(); v != r.end(); ++v) {
                    const double phiGrey = greyOf(openvdb::Vec3d(phi[v]));
                    a[v] = phiGrey > 0.0 ? openvdb::Vec3f(clampedToUnit(openvdb::Vec3d(flux[v]) / phiGrey)) : openvdb::Vec3f(0.0f);
                }
            });
            moments->scattered = lattice.write(a, source);
            moments->scattered->setName(grids::kScatterAnisotropy);
        }
        std::vector<openvdb::Vec3f>().swap(a);
        std::vector<openvdb::Vec3f>().swap(flux);
        lattice.putSkin(phi, skin, corrected ? &shift : nullptr);
        auto grid = lattice.write(phi, source);
        grid->setName(grids::kScatter);
        return grid;
    }

    const Medium& medium;
    const openvdb::Vec3SGrid& source;
    const SweepSolveOptions& options;
    SweepSolveReport& report;
    Interrupter* interrupter;
    SweepMoments* moments;
    const std::chrono::steady_clock::time_point setupStart = std::chrono::steady_clock::now(); ///< before the lattice is built
    const double restG; ///< the transport's rest of the phase (Phase.h)
    const bool gather;
    detail::SweepLattice lattice;
    const std::size_t count;
    std::optional<detail::DiffusionCorrection> diffusion; ///< the sweeps' correction (the gathers' is the sweeps' solve)
    std::vector<openvdb::Vec3f> j0; ///< J0 continued (readPassSource), or empty: j0View
    std::optional<detail::SweepLattice::GridView> j0View; ///< J0, the source grid as it is
    /// J0 at voxel @a v.
    openvdb::Vec3f ownSource(std::size_t v) const { return j0View ? (*j0View)[v] : j0[v]; }
    /// a0 at voxel @a v: the source's anisotropy grid's, within the unit ball (0 without one).
    openvdb::Vec3f ownAnisotropy(std::size_t v) const
    {
        return a0View ? openvdb::Vec3f(clampedToUnit(openvdb::Vec3d((*a0View)[v]))) : openvdb::Vec3f(0.0f);
    }
    std::vector<openvdb::Vec3d> directions;
    double weight = 0.0;
    // The rest of the phase (restG ≠ 0): J0's mean direction of travel a0, per voxel; the
    // directions in world space; the direction set's opposite pairs (sweepDirections: ω, −ω in
    // turn), one of each, for the rest's quadrature correction (none for a set of no such pairs).
    std::optional<detail::SweepLattice::FirstMoment> moment;
    std::optional<detail::SweepLattice::GridView> a0View; ///< a0: the source's anisotropy grid, if any
    std::vector<openvdb::Vec3f> flux, a;
    std::vector<openvdb::Vec3d> previousCellFlux; ///< the last sweep's F, a diffusion cell's mean
    // Per voxel: what the iteration keeps (the sweep's own arrays come and go; J is made padded
    // from j0, σs and φ, with no per-voxel copy; a first moment adds a0, a, β, F, the last
    // sweep's F and the correction's ΔF, a and β read padded a leaf at a time by the sweep).
    // docs/accuracy-notes.md (ab) has what each costs.
    std::vector<openvdb::Vec3f> phi, next, skin;
    /// The last sweep's J, each sweep's made again in its memory (SweepLattice::sweepSource).
    detail::SweepLattice::SweepSource sweepSource;
    std::vector<openvdb::Vec3f> firstFlight; ///< the gather's K J0 (the same every iteration)
    AndersonMixing mixing; ///< of the corrected gathers
    /// Whether the correction's sweeps take their diffusion correction: once dropped there (voxels
    /// many mean free paths thick), building it again for every gather cost more than the sweeps.
    bool correctionAccelerates = true;
    ScatterPassOptions gatherOptions;
    bool corrected = false; ///< the last sweep added the diffusion correction (it holds it)
    double previousChange = 0.0;
    double previousMoved = 0.0; ///< |φ_{l+½} − φ_l|₁ of the last accelerated sweep, largest channel
    double previousAbsolute = 0.0; ///< |φ_{l+1} − φ_l|₁ of the last iteration, largest channel (after its correction)
    double lastGrowth = 0.0; ///< that change over the one before it
    bool restarted = false; ///< the correction diverged: dropped, the plain iteration restarted from zero
    std::string correctionNote; ///< whether and why the correction was halved or dropped
    bool accelerate;
    double damping = 1.0; ///< of the correction: kDampedCorrection once it stalled
    const char* iterations; ///< the report's words
    const char* iteration;
    const char* correctionName;
};

} // namespace

openvdb::Vec3SGrid::Ptr sweepSolve(const Medium& medium, const openvdb::Vec3SGrid& source, const SweepSolveOptions& options,
    SweepSolveReport& report, Interrupter* interrupter, SweepMoments* moments)
{
    InterruptStep step(interrupter, options.kernel == ScatterKernel::Gather ? "gathering" : "sweeping");
    SweepSolver solver(medium, source, options, report, interrupter, moments);
    return solver.solve();
}

} // namespace vxf
