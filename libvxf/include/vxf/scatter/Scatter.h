// vxf — the scatter stage: the multiple scattering solved whole by accelerated sweeps or gathers
// (the default), or by plain source iteration over passes, with early stopping.
#pragma once

#include <vxf/transport/AdaptiveBand.h>
#include <vxf/scatter/ScatterPass.h>
#include <vxf/scatter/SweepSolve.h>

#include <vxf/core/VoxelSet.h>
#include <vxf/core/MemoryBudget.h>
#include <vxf/core/Scene.h>
#include <vxf/io/VoxelSetFile.h>

#include <string>
#include <vector>

namespace vxf {

struct ScatterOptions
{
    int passes = defaults::kPasses; ///< at most this many passes (0: none, `scatter` zero: single scattering alone)
    /// Stop when the rest of the series, φ_K·r/(1−r) with r the last pass's energy ratio (per
    /// channel), is known to within this fraction of the sum so far, and add it (0: never).
    /// Near albedo 1 the passes settle into the slowest mode long before the rest is small.
    double tolerance = defaults::kTolerance;
    bool keepPasses = false; ///< keep each pass as `scatter_pass_K`
    int fromPass = 0; ///< continue from `scatter_pass_K` (0: from `scatter_source`)
    /// After the last pass, add the geometric tail of the series: φ_K·r/(1−r) with
    /// r = φ_K/φ_{K−1} per voxel and channel, capped by the global energy ratio of the last
    /// two passes (itself ≤ 0.99). Makes albedo ≈ 1 converge in few passes.
    bool extrapolateTail = false;
    /// Passes after the first `finePasses` run on a lattice `coarseFactor` times coarser
    /// (coarsenMedium; the source is block-averaged onto it, their sum brought back by one
    /// fine gather): high scattering orders are smooth, and a coarse pass costs about
    /// coarseFactor⁴ less.
    /// 0: every pass at full resolution.
    int finePasses = 0;
    int coarseFactor = defaults::kCoarseFactor; ///< 2, 4 or 8
    /// After the coarse passes, the cycles that correct their bias (see scatter()).
    /// Off only to measure what it buys.
    bool coarseCorrection = true;
    /// Adaptive narrow band (world units): full resolution within this distance of the
    /// surface, 8³ and 128³ tiles deeper (see coarsenBeyondBand). 0: full resolution everywhere.
    double band = 0.0;
    /// Solve for the whole sum at once by passes of either kernel (pass.kernel: sweeps or
    /// gathers) with diffusion synthetic acceleration (sweepSolve), whose iterations are not
    /// scattering orders. Not with keepPasses, fromPass or finePasses, which need the orders:
    /// those run plain source iteration, one order per pass.
    bool accelerate = true;
    /// Warm start of the accelerated solve (SweepSolveOptions::initial): a previous frame's
    /// `scatter`, taken when it lies on the source's voxels (the same transform), ignored
    /// otherwise (ScatterReport::warmStarted says which). Null: start from zero.
    openvdb::Vec3SGrid::ConstPtr warmStart;
    ScatterPassOptions pass;
};

struct ScatterReport
{
    struct Pass
    {
        int index = 0; ///< K of φ_K
        openvdb::Vec3d energy{0.0}; ///< Σ over voxels of φ_K (tiles weighted by their voxels)
        double ratio = 0.0; ///< energy (max channel) relative to the previous pass
        double seconds = 0.0;
        bool coarse = false; ///< ran on the coarse lattice
        /// Accelerated sweeps: |φ_l − φ_{l−1}|₁/|φ_l|₁ of the sum (the residual per iteration);
        /// `energy` is then the whole sum's, not one order's.
        double change = 0.0;
        int diffusionIterations = 0; ///< accelerated sweeps: conjugate-gradient iterations of the correction
        int correctionSweeps = 0; ///< accelerated gathers: sweeps of the correction (SweepSolveReport)
        double sweepSeconds = 0.0; ///< accelerated sweeps: of `seconds`, the transport sweep
    };
    std::vector<Pass> passes;
    std::string stopReason;
    double tailFactor = 0.0; ///< r/(1−r) of the global energy ratio (0: no extrapolation); per voxel it varies
    AdaptiveBandReport band; ///< the resolution the passes ran at
    double fineGatherSeconds = 0.0; ///< after coarse passes: the fine gathers and the correction cycle
    int correctionPasses = 0; ///< coarse passes of the correction cycles
    int correctionCycles = 0; ///< how many correction cycles ran
    bool accelerated = false; ///< the sum was solved by accelerated sweeps or gathers (passes are iterations)
    bool warmStarted = false; ///< the solve started from options.warmStart
    std::size_t sweptVoxels = 0; ///< accelerated sweeps: voxels swept per direction (the touched leaves')
    std::size_t diffusionUnknowns = 0; ///< accelerated sweeps: cells of the diffusion correction
    int diffusionCoarsening = 1; ///< accelerated sweeps: those cells are blocks of this many voxels cubed
    double setupSeconds = 0.0; ///< accelerated sweeps: the lattice and the diffusion matrices
};

/// Scatter options from a scene's settings (keepPasses when "scatter_passes" is an output).
ScatterOptions scatterOptionsFrom(const SceneSettings& settings);

/// Whether scatter() with @a options carries an anisotropic phase's first moment: only the
/// accelerated sweeps solving the whole sum do. For any other scatter the light stage lights the
/// similarity relation's isotropic medium (DirectLightOptions::similarity).
bool carriesFirstMoment(const ScatterOptions& options);

/// Σ over active values of a Vec3f grid, active tiles weighted by their voxel count.
openvdb::Vec3d gridEnergy(const openvdb::Vec3SGrid& grid);

/// The scatter stage's peak per active voxel of the medium's density beyond the fixed part: what
/// each added voxel took between the two largest of bench/scale's rows (docs/reports/scale.md),
/// the larger medium's, rounded up: scripts/make-smoke's puff with a Henyey-Greenstein phase, 256³
/// to 384³ (718 → 2144 MiB for 4.59M → 15.5M voxels: 137 bytes); the bunny's dims 256 to 512 took
/// 109. Small volumes hold more a voxel (the smoke at 256³ is within 2% of the estimate), large
/// ones less (102M voxels at 720³ took 146 bytes, measured before the solve stopped holding a
/// zero sum of 12 bytes a voxel: docs/accuracy-notes.md (af)).
/// scatter checks it against the memory budget before it allocates.
inline constexpr double kScatterBytesPerVoxel = 145.0;
/// The scatter's peak for a density of @a voxels active voxels: what scatter() checks, and
/// `vxf scatter` from the file's count before it reads.
MemoryEstimate scatterMemory(double voxels);

/// With a band (ScatterOptions::band) the accelerated sweeps hold the grids read and written
/// per active voxel and their own arrays per swept voxel (the band's leaves' voxels and one a
/// coarse cell). Fitted to the thick bunny at dim 512 with bands of one and two mean free paths
/// (2011 and 2294 MiB for 14.0M and 18.5M swept of 28.1M active: 66 bytes a swept voxel, 38 an
/// active one), rounded up; it gives the solve without a band 3112 MiB against 2728 measured.
inline constexpr double kBandedScatterBytesPerActiveVoxel = 40.0, kBandedScatterBytesPerSweptVoxel = 70.0;
/// The banded scatter's peak for @a voxels active voxels of which the sweeps take @a swept
/// (scatter() checks it once the band has made its tiles, instead of scatterMemory).
MemoryEstimate bandedScatterMemory(double voxels, double swept);

/// The transport's medium of @a set and @a material for scatter() with @a options: read
/// through its trees (Medium::Lookups::Trees) where the accelerated sweeps solve the whole sum,
/// whose lattice reads each voxel once, so that no dense copy is held through the solve; with
/// dense copies where gathers or passes march through it.
Medium scatterMedium(const VoxelSet& set, const Material& material, const ScatterOptions& options);

/// Run scattering passes on @a set: J_k = σs·φ_k/(4π) feeds pass k+1 (J_0 is `scatter_source`,
/// read from the set, so an artist may have edited it). @a medium is the transport's (Medium):
/// with a forward phase (material().phaseG = g* ≠ 0) and a source lit with its moment
/// (`scatter_source_anisotropy`), the accelerated sweeps carry the rest of the phase
/// (RestPhase) and write `scatter_anisotropy`; every other way (gather kernel, plain, kept,
/// coarse or continued passes, a source lit by the similarity relation:
/// DirectLightOptions::similarity) solves
/// medium.isotropic(), the similarity relation, a source lit with the moment scaled by 1 − g*
/// (the share of the once-scattered light that leaves isotropically under it; a volume light's
/// emission alike), and drops a stale `scatter_anisotropy`. Writes `scatter` = Σ_{k≥1} φ_k and,
/// when the set has `direct`, `illumination` = direct + scatter; with keepPasses also
/// `scatter_pass_K`. With options.accelerate (and no keepPasses, fromPass or finePasses) the
/// sum is solved whole by accelerated sweeps or gathers (sweepSolve), at most options.passes
/// of them, to the tolerance, nothing extrapolated. Otherwise, plain source iteration: with
/// fromPass = K the iteration restarts from `scatter_pass_K` (as edited)
/// and the sum from `scatter_pass_1..K`. Stops after options.passes, or when the rest
/// of the series is known to within the tolerance (and adds it), or at once when the medium does not scatter (σs = 0: `scatter`
/// is 0). Topology: that of `scatter_source`, with the deep interior made tiles when options.band > 0
/// (`scatter_source` itself is left as it was). With options.finePasses, passes after those
/// run on the coarse lattice (their `scatter_pass_K` interpolated back to the fine topology)
/// and their sum returns to the fine lattice as a source: `scatter` adds one fine gather of
/// J_N + σs·(Σ coarse φ)/4π, which resolves the light near the surface at full resolution,
/// and correction cycles (conjugate-gradient steps of two fine gathers each, until what is
/// left is below the tolerance, at least 0.3%, of the sum) solve for what the coarse
/// lattice's slightly different operator left out; see SourceIteration.cc.
/// A source nowhere negative gives a sum nowhere negative: what an accelerated solve's correction
/// leaves below zero is set to zero, and the stop reason says how low it was.
/// Throws vxf::Error naming a missing grid, vxf::UsageError for a bad coarseFactor.
ScatterReport scatter(VoxelSet& set, const Medium& medium, const ScatterOptions& options = {}, Interrupter* interrupter = nullptr);

/// `illumination` = `direct` + `scatter` into @a set, when it holds both (scatter does this at
/// its end; a caller that reads `direct` only after the solve calls it then).
void putIllumination(VoxelSet& set);

/// How a scatter stage reads its input from a file: every grid but `direct`, which only
/// `illumination` needs, at the end; read it then (readGridsInto(set, path, {grids::kDirect},
/// scatterInputRead())) and call putIllumination. The solve holds none of its 12 bytes a voxel
/// (`vxf scatter`, `vxf run`). The light it carries (the source, its anisotropy, `direct`, the
/// passes) must be finite: a NaN is refused with the file, grid and voxel.
VoxelSetReadOptions scatterInputRead();

} // namespace vxf
