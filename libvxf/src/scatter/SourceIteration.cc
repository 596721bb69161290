#include "SourceIteration.h"

#include <vxf/core/GridRoles.h>
#include <vxf/core/MemoryBudget.h>
#include <vxf/transport/Phase.h>

#include <vxf/transport/AdaptiveBand.h>
#include <vxf/scatter/CoarseLevel.h>

#include <vxf/core/Error.h>
#include <vxf/light/InteriorField.h>

#include <openvdb/tools/Composite.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/ValueTransformer.h>
#include <openvdb/tree/LeafManager.h>

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

namespace vxf::detail {

namespace {

/// Σ |v| per channel over active values, tiles weighted by their voxel count.
openvdb::Vec3d gridL1(const openvdb::Vec3SGrid& grid)
{
    openvdb::Vec3d sum(0.0);
    for (auto it = grid.cbeginValueOn(); it; ++it) {
        const openvdb::Vec3f v = *it;
        sum += openvdb::Vec3d(std::abs(v[0]), std::abs(v[1]), std::abs(v[2])) * double(it.getVoxelCount());
    }
    return sum;
}

/// At most this many correction cycles after coarse passes (each costs two fine gathers).
constexpr int kMaxCorrectionCycles = 6;

/// What is known of the rest of a series of passes, Σ_{k>K} φ_k, from its last two passes.
struct SeriesTail
{
    bool known = false; ///< every channel's pass ratio is in [0, 1): the series converges
    openvdb::Vec3d ratio{0.0}; ///< r = E_K/E_{K−1} per channel (E: energy, Σ over voxels)
    openvdb::Vec3d rest{0.0}; ///< energy of the rest were it geometric from here: E_K·r/(1−r)
    openvdb::Vec3d uncertainty{std::numeric_limits<double>::infinity()}; ///< bound on |true rest − rest|
};

/// The rest from φ_K = @a last and φ_{K−1} = @a before (same lattice). Once the passes have
/// the shape of the operator's slowest mode u (eigenvalue r∞), φ_{K+1} = r∞·φ_K and the rest is
/// φ_K·r/(1−r). Where a faster mode w (eigenvalue s, |s| ≤ r) is left, φ_K = a·u·r∞^K + b·w·s^K,
/// the residual ρ = φ_K − r·φ_{K−1} is b·w·s^{K−1}(s − r) and the estimate misses
/// ρ·s/((1−s)(1−r)) voxel by voxel, at most |ρ|·r/(1−r)²: its L1 norm bounds the error of the
/// rest's energy and of every voxel's share in it. (A ratio of energies alone settles long
/// before the shape does: albedo 0.9999 stopped with 1.4% too much light at the brightest
/// voxel while its energy was within 0.03%.)
SeriesTail seriesTail(
    const openvdb::Vec3SGrid& last, const openvdb::Vec3SGrid& before, const openvdb::Vec3d& energy, const openvdb::Vec3d& energyBefore)
{
    SeriesTail t;
    t.known = true;
    for (int c = 0; c < 3; ++c) {
        t.ratio[c] = energyBefore[c] != 0.0 ? energy[c] / energyBefore[c] : 0.0;
        t.known = t.known && t.ratio[c] >= 0.0 && t.ratio[c] < 1.0;
    }
    if (!t.known) return t;
    openvdb::Vec3d residual(0.0);
    auto b = before.getConstAccessor();
    for (auto it = last.cbeginValueOn(); it; ++it) {
        const openvdb::Vec3d d = openvdb::Vec3d(*it) - t.ratio * openvdb::Vec3d(b.getValue(it.getCoord()));
        residual += openvdb::Vec3d(std::abs(d[0]), std::abs(d[1]), std::abs(d[2])) * double(it.getVoxelCount());
    }
    for (int c = 0; c < 3; ++c) {
        const double r = t.ratio[c];
        t.rest[c] = energy[c] * r / (1.0 - r);
        t.uncertainty[c] = residual[c] * r / ((1.0 - r) * (1.0 - r));
    }
    return t;
}

/// y = combine(y, x) voxel by voxel and tile by tile on @a y's topology, in parallel over the
/// leaves (@a x on the same topology: a tile reads x at its origin).
template <typename Combine>
void combineInPlace(openvdb::Vec3SGrid& y, const openvdb::Vec3SGrid& x, const Combine& combine)
{
    openvdb::tree::LeafManager<openvdb::Vec3STree> leaves(y.tree());
    leaves.foreach ([&](openvdb::Vec3STree::LeafNodeType& leaf, std::size_t) {
        auto acc = x.getConstAccessor();
        for (auto it = leaf.beginValueOn(); it; ++it) it.setValue(combine(*it, acc.getValue(it.getCoord())));
    });
    auto acc = x.getConstAccessor();
    for (auto it = y.tree().beginValueOn(); it; ++it) {
        if (it.isTileValue()) it.setValue(combine(*it, acc.getValue(it.getCoord())));
    }
}

/// sum += δ on @a sum's topology (δ is computed on the same).
/// δ is a difference of two estimates: it may not take a fluence below zero (where the sum is
/// tiny, at the medium's edge); where the sum is negative already (an artist's negative
/// source) it adds as it is.
void addCorrection(openvdb::Vec3SGrid& sum, const openvdb::Vec3SGrid& delta)
{
    combineInPlace(sum, delta, [](const openvdb::Vec3f& a, const openvdb::Vec3f& d) {
        openvdb::Vec3f v = a + d;
        for (int c = 0; c < 3; ++c) {
            if (a[c] >= 0.0f) v[c] = std::max(v[c], 0.0f);
        }
        return v;
    });
}

/// Σ a·b per channel over @a a's active values (tiles weighted by their voxel count); @a b
/// on the same topology.
openvdb::Vec3d innerProduct(const openvdb::Vec3SGrid& a, const openvdb::Vec3SGrid& b)
{
    openvdb::Vec3d sum(0.0);
    auto acc = b.getConstAccessor();
    for (auto it = a.cbeginValueOn(); it; ++it) {
        const openvdb::Vec3d x(*it), y(acc.getValue(it.getCoord()));
        sum += openvdb::Vec3d(x[0] * y[0], x[1] * y[1], x[2] * y[2]) * double(it.getVoxelCount());
    }
    return sum;
}

/// y += a·x per channel, on @a y's topology (@a x on the same).
void axpy(openvdb::Vec3SGrid& y, const openvdb::Vec3d& a, const openvdb::Vec3SGrid& x)
{
    combineInPlace(y, x, [&a](const openvdb::Vec3f& yv, const openvdb::Vec3f& xv) {
        return openvdb::Vec3f(float(yv[0] + a[0] * xv[0]), float(yv[1] + a[1] * xv[1]), float(yv[2] + a[2] * xv[2]));
    });
}

/// a·x per channel, as a new grid.
openvdb::Vec3SGrid::Ptr scaled(const openvdb::Vec3d& a, const openvdb::Vec3SGrid& x)
{
    auto y = x.deepCopy();
    openvdb::tools::foreach (y->beginValueOn(), [a](const openvdb::Vec3STree::ValueOnIter& it) {
        const openvdb::Vec3f v = *it;
        it.setValue(openvdb::Vec3f(float(v[0] * a[0]), float(v[1] * a[1]), float(v[2] * a[2])));
    });
    return y;
}

/// The coefficients c (per channel) of a correction cycle's step s = Σ_i c_i·v_i over the
/// directions v_i found so far, that minimise the error left in the norm of M = I − A: the
/// Galerkin conditions ⟨v_j, ρ − Ms⟩ = 0 for all j (inner products weighted by S), i.e.
/// Σ_i ⟨v_j, Mv_i⟩ c_i = ⟨v_j, ρ⟩. With M self-adjoint and positive that is the conjugate
/// gradient step (on all directions, as the coarse preconditioner is not exactly linear).
/// @a gram[j][i] = ⟨v_j, Mv_i⟩, @a along[j] = ⟨v_j, ρ⟩. Where the system is singular (a
/// direction adds nothing new) only the newest direction steps, by ⟨v, ρ⟩/⟨v, Mv⟩ in [0, 16]
/// (1, the plain step, if even that fails).
std::vector<openvdb::Vec3d> cycleStep(const std::vector<std::vector<openvdb::Vec3d>>& gram, const std::vector<openvdb::Vec3d>& along)
{
    const std::size_t n = along.size();
    std::vector<openvdb::Vec3d> c(n, openvdb::Vec3d(0.0));
    for (int ch = 0; ch < 3; ++ch) {
        // Gaussian elimination with partial pivoting on the n × (n+1) system.
        std::vector<std::vector<double>> m(n, std::vector<double>(n + 1));
        double scale = 0.0;
        for (std::size_t j = 0; j < n; ++j) {
            for (std::size_t i = 0; i < n; ++i) m[j][i] = gram[j][i][ch];
            m[j][n] = along[j][ch];
            scale = std::max(scale, std::abs(m[j][j]));
        }
        bool solved = scale > 0.0 && std::isfinite(scale);
        for (std::size_t k = 0; k < n && solved; ++k) {
            std::size_t pivot = k;
            for (std::size_t j = k + 1; j < n; ++j) pivot = std::abs(m[j][k]) > std::abs(m[pivot][k]) ? j : pivot;
            std::swap(m[k], m[pivot]);
            if (!(std::abs(m[k][k]) > 1e-9 * scale)) {
                solved = false;
                break;
            }
            for (std::size_t j = k + 1; j < n; ++j) {
                const double f = m[j][k] / m[k][k];
                for (std::size_t i = k; i <= n; ++i) m[j][i] -= f * m[k][i];
            }
        }
        std::vector<double> x(n, 0.0);
        for (std::size_t k = n; k-- > 0 && solved;) {
            double v = m[k][n];
            for (std::size_t i = k + 1; i < n; ++i) v -= m[k][i] * x[i];
            x[k] = v / m[k][k];
            solved = std::isfinite(x[k]) && std::abs(x[k]) <= 1e3;
        }
        if (solved) {
            for (std::size_t i = 0; i < n; ++i) c[i][ch] = x[i];
            continue;
        }
        const double newest = gram[n - 1][n - 1][ch], alpha = along[n - 1][ch] / newest;
        c[n - 1][ch] = newest > 0.0 && std::isfinite(alpha) ? std::clamp(alpha, 0.0, 16.0) : 1.0;
    }
    return c;
}

/// Plain source iteration, one scattering order per pass (scatter() without acceleration, or
/// with passes kept, continued or coarse): the passes on the set's lattice, or after
/// options.finePasses on a coarse one, the series' tail where it is known, and a coarse sum
/// brought back to the fine lattice by a fine gather and correction cycles.
struct SourceIteration
{
    VoxelSet& set;
    const Medium& medium;
    const ScatterOptions& options;
    ScatterReport& report;
    Interrupter* interrupter;
    openvdb::Vec3SGrid::Ptr sum; ///< Σ φ_k on the fine lattice
    openvdb::Vec3SGrid::Ptr j; ///< the next pass's source
    int k; ///< passes so far (from options.fromPass)

    double previous = 0.0; ///< the last pass's energy (largest channel)
    const Medium* levelMedium = &medium; ///< the lattice the passes run on: the set's, or after options.finePasses a coarse one
    CoarseMedium coarse{};
    openvdb::Vec3SGrid::Ptr levelSum = sum; ///< Σ φ_k on the level (sum itself while fine)
    double levelVoxels = 1.0; ///< fine voxels per level voxel (energies in fine units)
    openvdb::Vec3SGrid::Ptr last{}, beforeLast{};
    openvdb::Vec3SGrid::Ptr fineSource{}; ///< J_N, the fine source when the passes went coarse
    openvdb::Vec3d energyBefore{0.0}; ///< E_{K−1}
    bool tailAdded = false;

    // The return to the fine lattice (returnToFineLattice) and its correction cycles.
    openvdb::Vec3SGrid::Ptr coarseTail{}, source{}, residual{};
    int correctionPasses = 0, fineGathers = 1, cycles = 0;
    double cycleTolerance = 0.0, previousSize = 0.0;
    std::string added{}; ///< each cycle's step as a share of the sum
    std::string ending{}; ///< why the cycles stopped, unless the rest fell below the tolerance
    /// The directions so far, v_i (each cycle's δ), their images Mv_i, and ⟨v_j, Mv_i⟩_S (2 fine
    /// grids per cycle kept: Sv_j is made again when needed).
    std::vector<openvdb::Vec3SGrid::Ptr> directions{}, images{};
    std::vector<std::vector<openvdb::Vec3d>> gram{};
    openvdb::Vec3d uncorrected{0.0}; ///< the sum's energy before the cycles
    openvdb::Vec3SGrid::Ptr correction{}; ///< Σ of the cycles' steps

    openvdb::Vec3d energy(const openvdb::Vec3SGrid& g) const { return gridEnergy(g) * levelVoxels; }

    void run()
    {
        for (int pass = 0; pass < options.passes; ++pass) {
            if (!runPass()) break;
        }
        if (report.stopReason.empty()) {
            report.stopReason = fmt::format("reached {} passes", options.passes);
            // Say what the limit left out, when the last two passes (on one lattice) tell: near
            // albedo 1 a few plain passes miss most of the light, and the image alone does not show it.
            // (After coarse passes the correction cycles below solve for the whole rest: a limit
            // of 20 passes on the thick bunny left 49% out, and the first cycle added 35%.)
            const bool corrected = levelSum != sum && options.coarseCorrection;
            if (!options.extrapolateTail && !corrected && last && beforeLast) {
                const std::size_t n = report.passes.size();
                const SeriesTail tail =
                    seriesTail(*last, *beforeLast, report.passes[n - 1].energy / levelVoxels, report.passes[n - 2].energy / levelVoxels);
                const openvdb::Vec3d total = levelSum == sum ? gridEnergy(*sum) : gridEnergy(*sum) + energy(*levelSum);
                double missing = 0.0, ratio = 0.0;
                for (int c = 0; c < 3; ++c) {
                    if (total[c] > 0.0 && tail.rest[c] * levelVoxels / total[c] > missing) {
                        missing = tail.rest[c] * levelVoxels / total[c];
                        ratio = tail.ratio[c];
                    }
                }
                // (Not when the ratios say nothing, e.g. an artist's source of both signs.)
                if (tail.known && missing > std::max(options.tolerance, 1e-3)) {
                    report.stopReason += fmt::format(
                        "; the rest of the series would add about {:.2g}% or more to the scattered light (pass ratio {:.4f}): {}",
                        100.0 * missing, ratio,
                        options.finePasses > 0 ? "raise passes"
                                               : "raise passes, or set fine_passes (the passes after them run on a coarser lattice, "
                                                 "which converges albedo near 1 in seconds)");
                }
            }
        }
        if (options.extrapolateTail && !tailAdded && last && beforeLast) extrapolateTail();
        if (levelSum != sum) returnToFineLattice();
    }

    /// After options.finePasses the passes go on on a lattice options.coarseFactor times coarser.
    void goCoarse()
    {
        const int f = options.coarseFactor;
        coarse = coarsenMedium(medium, f);
        fineSource = j;
        j = blockAverage(*j, f, coarse.transform);
        // One voxel more all round, so interpolating back near the surface meets values.
        openvdb::tools::dilateActiveValues(j->tree(), 1, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::EXPAND_TILES);
        levelSum = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
        levelSum->setTransform(coarse.transform);
        levelSum->tree().topologyUnion(j->tree());
        levelMedium = coarse.medium.get();
        levelVoxels = double(f) * f * f;
        last = beforeLast = nullptr; // the tail's ratio is taken on one level
    }

    /// One pass; false when the passes stop (the source is zero, or the rest of the series is known and added).
    bool runPass()
    {
        const auto start = std::chrono::steady_clock::now();
        if (options.finePasses > 0 && levelMedium == &medium && k >= options.finePasses) goCoarse();
        // The lights' source J0 is read fraction-weighted, every pass's own continued (SourceField).
        ScatterPassOptions passOptions = options.pass;
        if (k == 0) passOptions.source = ScatterPassOptions::SourceRead::FractionWeighted;
        passOptions.rotationSeed = std::uint64_t(k + 1); // sweeps: each order's rays elsewhere
        auto phi = scatterPass(*levelMedium, *j, passOptions, interrupter);
        ++k;
        ScatterReport::Pass info;
        info.index = k;
        info.energy = energy(*phi);
        info.ratio = previous > 0.0 ? maxChannel(info.energy) / previous : 0.0;
        info.coarse = levelMedium != &medium;
        previous = maxChannel(info.energy);
        const openvdb::Vec3d energyPrevious = energyBefore;
        energyBefore = info.energy;
        if (options.keepPasses) {
            set.put(named(info.coarse ? prolong(*phi, *sum) : phi->deepCopy(), fmt::format("scatter_pass_{}", k)));
        }
        j = sourceFromFluence(*levelMedium, *phi);
        const openvdb::Vec3d summed = (levelSum == sum ? gridEnergy(*sum) : gridEnergy(*sum) + energy(*levelSum)) + info.energy;
        const double total = maxChannel(summed);
        beforeLast = last;
        last = phi->deepCopy(); // φ_K outlives compSum, which empties phi
        openvdb::tools::compSum(*levelSum, *phi);
        info.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        report.passes.push_back(info);
        if (total <= 0.0) {
            report.stopReason = "the source is zero";
            return false;
        }
        if (options.tolerance <= 0.0 || !beforeLast) return true;
        // Stop when the rest of the series is known to within the tolerance (of each
        // channel's sum), and add it: near albedo 1 this ends the passes long before the
        // rest is small. (A bare "this pass added little" test stops albedo 0.99 with a
        // tenth of the light still missing.)
        const SeriesTail tail = seriesTail(*last, *beforeLast, info.energy / levelVoxels, energyPrevious / levelVoxels);
        bool settled = tail.known;
        for (int c = 0; c < 3; ++c) settled = settled && tail.uncertainty[c] * levelVoxels <= options.tolerance * std::abs(summed[c]);
        if (!settled) return true;
        const openvdb::Vec3f factor(openvdb::Vec3d(
            tail.ratio[0] / (1.0 - tail.ratio[0]), tail.ratio[1] / (1.0 - tail.ratio[1]), tail.ratio[2] / (1.0 - tail.ratio[2])));
        openvdb::tools::foreach (last->beginValueOn(), [factor](const openvdb::Vec3STree::ValueOnIter& it) {
            const openvdb::Vec3f v = *it;
            it.setValue(openvdb::Vec3f(v[0] * factor[0], v[1] * factor[1], v[2] * factor[2]));
        });
        openvdb::tools::compSum(*levelSum, *last);
        const int c = summed[0] >= summed[1] && summed[0] >= summed[2] ? 0 : summed[1] >= summed[2] ? 1 : 2;
        report.tailFactor = factor[c];
        report.stopReason = fmt::format("after pass {} the rest of the series, phi_K r/(1-r) with pass ratio r = {:.4f}, "
                                        "is {:.2g} of the sum, known to within {:.2g}, below the tolerance {:.2g}; added",
            k, tail.ratio[c], tail.rest[c] * levelVoxels / summed[c], tail.uncertainty[c] * levelVoxels / summed[c], options.tolerance);
        tailAdded = true;
        return false;
        return true;
    }

    void extrapolateTail()
    {
        // Σ_{k>K} φ_k ≈ φ_K (r + r² + …) = φ_K r/(1−r), with r = φ_K/φ_{K−1} per voxel and
        // channel (regions near the boundary decay faster) capped by the global energy
        // ratio of the last two passes (≤ 0.99). Where passes still grow (light still
        // arriving) the local ratio is no estimate of the tail; the cap keeps it bounded.
        // (A voxel whose own settled ratio exceeds the global one is underestimated.)
        const double global = std::min(0.99, std::max(0.0, report.passes.back().ratio));
        report.tailFactor = global / (1.0 - global);
        auto before = beforeLast->getConstAccessor();
        const float cap = float(global);
        openvdb::tools::foreach (
            last->beginValueOn(),
            [&before, cap](const openvdb::Vec3STree::ValueOnIter& it) {
                const openvdb::Vec3f b = before.getValue(it.getCoord());
                openvdb::Vec3f tail = *it;
                for (int c = 0; c < 3; ++c) {
                    const float r = b[c] > 0.0f ? std::clamp(tail[c] / b[c], 0.0f, cap) : cap;
                    tail[c] *= r / (1.0f - r);
                }
                it.setValue(tail);
            },
            /*threaded=*/false);
        openvdb::tools::compSum(*levelSum, *last);
        report.stopReason += fmt::format("; geometric tail extrapolated per voxel (global ratio {:.4f})", global);
    }

    /// A series of coarse passes from the fine source @a fineJ, summed on the coarse lattice; @a count the passes it took.
    openvdb::Vec3SGrid::Ptr coarseSeries(const openvdb::Vec3SGrid& fineJ, int& count)
    {
        const int f = options.coarseFactor;
        auto jc = blockAverage(fineJ, f, coarse.transform);
        openvdb::tools::dilateActiveValues(jc->tree(), 1, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::EXPAND_TILES);
        auto acc = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
        acc->setTransform(coarse.transform);
        acc->tree().topologyUnion(jc->tree());
        // The series ends as soon as its pass ratio nears the first series' last one
        // (the coarse operator's largest eigenvalue, within 1e-3): the rest is then
        // φ_K·r/(1−r); or when the rest is below the tolerance (at least 1e-3) of the
        // series itself. Sizes are L1 norms, as a residual has both signs. (Measured
        // against the whole sum instead, a small residual's series stopped after a pass
        // or two and lost the 1/(1 − r) that its smooth part needs: cycles at albedo
        // 0.999 settled 10% off.)
        const double dominant = report.passes.back().ratio;
        const double tolerance = std::max(options.tolerance, 1e-3);
        double before = 0.0, sizes = 0.0;
        for (count = 0; count < std::max(options.passes, 1); ++count) {
            auto phi = scatterPass(*coarse.medium, *jc, options.pass, interrupter);
            const double size = maxChannel(gridL1(*phi));
            const double r = before > 0.0 ? size / before : 0.0;
            const bool settled = count >= 3 && dominant < 0.999 && std::abs(r - dominant) < 1e-3;
            before = size;
            sizes += size;
            if (!settled) jc = sourceFromFluence(*coarse.medium, *phi);
            if (settled) {
                const float scale = float(1.0 / (1.0 - dominant));
                openvdb::tools::foreach (
                    phi->beginValueOn(), [scale](const openvdb::Vec3STree::ValueOnIter& it) { it.setValue(*it * scale); });
            }
            openvdb::tools::compSum(*acc, *phi);
            if (settled || size == 0.0 || (count > 0 && r < 1.0 && size * r / (1.0 - r) < tolerance * sizes)) {
                ++count;
                break;
            }
        }
        return acc;
    }

    // Back on the fine lattice by a fine gather, not by interpolating the coarse sum:
    // Σ_{k>N} φ_k = K(Σ_{k≥N} J_k) ≈ g = K(J_N + S·P ê), with K the fine gather, S = σs/4π,
    // P = prolong and ê = Σ coarse φ. The sources are smooth, so the coarse lattice
    // carries them well; the fluence they give falls off within a mean free path of the
    // surface, which only the fine gather resolves.
    // The coarse lattice also leaks a little more light (its surface voxels are block
    // averages), and near albedo 1 the series' 1/(1−r) magnifies a small change of r.
    // What g misses, e = E − g, solves e = KSe + ρ with ρ = KS(g − P ê) (from
    // E = KSφ_N + KSE for the exact E): correction cycles solve for it, below.
    void returnToFineLattice()
    {
        const auto start = std::chrono::steady_clock::now();
        coarseTail = prolong(*levelSum, *sum);
        source = sourceFromFluence(medium, *coarseTail);
        openvdb::tools::compSum(*source, *fineSource); // fineSource is not needed after
        auto g = scatterPass(medium, *source, options.pass, interrupter);
        // The residual of the sum X = g, r(X) = A(φ_N + X) − X with A = KS, is
        // ρ = A(g − Pê) (as g = A(φ_N + Pê)): the cycles' right-hand side.
        if (options.coarseCorrection) {
            auto difference = g->deepCopy();
            axpy(*difference, openvdb::Vec3d(-1.0), *coarseTail);
            residual = scatterPass(medium, *sourceFromFluence(medium, *difference), options.pass, interrupter);
            ++fineGathers;
        }
        openvdb::tools::compSum(*sum, *g);
        // Each cycle approximates the error e the same way as the sum itself: δ = ρ + A(ρ + Pê)
        // with ê the coarse series of Sρ. The coarse series is off by 1/(1 − r) where the
        // coarse operator's largest eigenvalue r differs from the fine one's, so near albedo 1
        // δ itself overshoots or falls short (added as it is, the cycles never settled near
        // albedo 1). δ is a
        // preconditioned direction instead: the step is the combination of all directions so
        // far that minimises the error left in the norm of M = I − A (self-adjoint with the
        // weight S: the gather is reciprocal), a conjugate gradient step (see cycleStep), and
        // ρ ← ρ − Ms (Mδ = δ − Aδ costs the cycle's second gather) (docs/accuracy-notes.md,
        // "Behind the code: Scatter").
        // The cycles go on until the rest, |s|·q/(1−q) with q the ratio of the last two
        // steps, is below the tolerance of the sum, but at least 0.3% (the coarse lattice's
        // other errors are larger than that), or for at most kMaxCorrectionCycles.
        cycleTolerance = std::max(options.tolerance, 3e-3);
        // The directions so far, v_i (each cycle's δ), their images Mv_i, and ⟨v_j, Mv_i⟩_S
        // (2 fine grids per cycle kept: Sv_j is made again when needed).
        // Σ of the steps, added to the sum at the end: a step may take the sum below zero
        // on the way (near albedo 1 the first overshoots by half), and clamping it there
        // would leave the residual ρ out of step with the sum (it did: 12% too much light).
        uncorrected = gridEnergy(*sum); // the sum's energy before the cycles
        correction = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
        correction->setTransform(sum->transformPtr());
        correction->tree().topologyUnion(sum->tree());
        while (options.coarseCorrection && cycles < kMaxCorrectionCycles) {
            if (!correctionCycle()) break;
        }
        if (cycles > 0) addCorrection(*sum, *correction);
        report.correctionPasses = correctionPasses;
        report.correctionCycles = cycles;
        report.fineGatherSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        report.stopReason += fmt::format(
            "; passes after {} on a {}x coarser lattice, their sum gathered on the fine one", options.finePasses, options.coarseFactor);
        if (options.coarseCorrection) {
            report.stopReason +=
                fmt::format(", corrected by {} more cycle{} (adding {} of the sum{}; {} coarse passes, {} fine gathers in all, {:.2f} s)",
                    cycles, cycles == 1 ? "" : "s", added, ending, correctionPasses, fineGathers, report.fineGatherSeconds);
        }
    }

    /// One correction cycle (returnToFineLattice); false when the rest fell below the tolerance.
    bool correctionCycle()
    {
        ++cycles;
        auto rhoSource = sourceFromFluence(medium, *residual);
        int passes = 0;
        coarseTail = prolong(*coarseSeries(*rhoSource, passes), *sum);
        correctionPasses += passes;
        source = sourceFromFluence(medium, *coarseTail);
        openvdb::tools::compSum(*source, *rhoSource);
        auto delta = scatterPass(medium, *source, options.pass, interrupter);
        axpy(*delta, openvdb::Vec3d(1.0), *residual); // δ = ρ + A(ρ + Pê)
        const auto deltaSource = sourceFromFluence(medium, *delta);
        auto deltaImage = delta->deepCopy(); // Mδ = δ − Aδ
        axpy(*deltaImage, openvdb::Vec3d(-1.0), *scatterPass(medium, *deltaSource, options.pass, interrupter));
        fineGathers += 2;
        directions.push_back(delta);
        images.push_back(deltaImage);
        const std::size_t n = directions.size();
        std::vector<openvdb::Vec3d> along;
        for (std::size_t d = 0; d + 1 < n; ++d) {
            const auto vSource = sourceFromFluence(medium, *directions[d]);
            gram[d].push_back(innerProduct(*vSource, *deltaImage));
            along.push_back(innerProduct(*vSource, *residual));
        }
        gram.emplace_back();
        for (std::size_t i = 0; i < n; ++i) gram.back().push_back(innerProduct(*deltaSource, *images[i]));
        along.push_back(innerProduct(*deltaSource, *residual));
        const std::vector<openvdb::Vec3d> weights = cycleStep(gram, along);
        auto step = scaled(weights[0], *directions[0]);
        auto stepImage = scaled(weights[0], *images[0]);
        for (std::size_t i = 1; i < n; ++i) {
            axpy(*step, weights[i], *directions[i]);
            axpy(*stepImage, weights[i], *images[i]);
        }
        axpy(*residual, openvdb::Vec3d(-1.0), *stepImage);
        int c = 0; // the step's largest channel, with its sign
        const openvdb::Vec3d e = gridEnergy(*step);
        for (int ch = 1; ch < 3; ++ch) c = std::abs(e[ch]) > std::abs(e[c]) ? ch : c;
        const double size = std::abs(e[c]);
        axpy(*correction, openvdb::Vec3d(1.0), *step);
        const double total = maxChannel(uncorrected + gridEnergy(*correction));
        added += fmt::format("{}{:+.2g}%", added.empty() ? "" : ", ", 100.0 * e[c] / std::max(total, 1e-300));
        const double q = previousSize > 0.0 ? size / previousSize : 1.0;
        previousSize = size;
        if (q < 1.0 && size * q / (1.0 - q) < cycleTolerance * total) {
            ending = "";
            return false;
        }
        ending = fmt::format(
            "; stopped at the limit of {} cycles, the rest not yet below {:g} of the sum", kMaxCorrectionCycles, cycleTolerance);
        return true;
    }
};

} // namespace

void iterateSources(VoxelSet& set, const Medium& medium, const ScatterOptions& options, ScatterReport& report, Interrupter* interrupter,
    openvdb::Vec3SGrid::Ptr sum, openvdb::Vec3SGrid::Ptr j, int k)
{
    SourceIteration iteration{set, medium, options, report, interrupter, std::move(sum), std::move(j), k};
    iteration.run();
}

} // namespace vxf::detail
