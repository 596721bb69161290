// vxf — the whole scattered light by sweeps or gathers, accelerated (sweeps by a diffusion correction, gathers by sweeps).
#pragma once

#include <vxf/core/Interrupter.h>
#include <vxf/transport/Medium.h>
#include <vxf/scatter/ScatterPass.h>

#include <string>
#include <vector>

namespace vxf {

struct SweepSolveOptions
{
    int maxSweeps = 40; ///< at most this many sweeps (iterations)
    /// Stop when the estimated error of the sum, |φ_l − φ_{l−1}|·ρ/(1−ρ) with ρ the ratio of the
    /// last two changes (L1 over voxels, per channel), is below this fraction of the sum.
    double tolerance = 1e-3;
    /// Diffusion synthetic acceleration after each sweep. Off: plain source iteration, each
    /// sweep one more scattering order (slow near albedo 1).
    bool accelerate = true;
    int directions = defaults::kDirections; ///< per sweep (ScatterPassOptions::directions)
    std::uint64_t rotationSeed = 1; ///< one rotation of the direction set for the whole solve
    /// The diffusion correction's cells: blocks of 1, 2 or 4 voxels a side; 0: the largest whose
    /// mean optical thickness is at most 1 (coarse-mesh DSA, see DiffusionCorrection).
    int diffusionCoarsening = 0;
    /// The transport of an iteration: the sweep kernel (SweepLattice::sweep, `directions` and
    /// `rotationSeed` above), or the gather (scatterPass with `gather`'s options, its kernel,
    /// rotation and source read set here: the lights' source read fraction-weighted once, the
    /// scattered light's continued, SourceField).
    ScatterKernel kernel = ScatterKernel::Sweep;
    ScatterPassOptions gather;
    /// How the sweeps read the source: the lights' J0 as it is (FractionWeighted), or a source
    /// made from a fluence whose skin voxels hold the light on the surface (Continued: those at
    /// their centres, SweepPass). The gather reads the lights' J0 as `gather.source` says.
    ScatterPassOptions::SourceRead source = ScatterPassOptions::SourceRead::FractionWeighted;
    /// Warm start: the iteration starts from this estimate of the sum (a previous frame's
    /// `scatter` on the same voxels), read where it is active, 0 elsewhere; null: from 0. Only
    /// the number of iterations changes, the stopping rule is the same.
    const openvdb::Vec3SGrid* initial = nullptr;
    /// The sweeps take each 8³ block of the source's active tiles deep inside the surface as one
    /// cell (SweepLattice::Tiles::Coarse: variable resolution, scatter's `band`), not as 512
    /// voxels; the result holds the tiles' values. The gathers voxelize them whatever this says.
    bool coarseTiles = false;
};

struct SweepSolveReport
{
    struct Iteration
    {
        int index = 0; ///< sweeps so far
        openvdb::Vec3d energy{0.0}; ///< Σ over voxels of the scattered fluence after it
        double change = 0.0; ///< |φ_l − φ_{l−1}|₁ / |φ_l|₁, largest channel
        double ratio = 0.0; ///< change over the previous change (ρ, the convergence rate)
        double error = 0.0; ///< change·ρ/(1−ρ): the estimated error of the sum
        int diffusionIterations = 0; ///< sweeps: conjugate-gradient iterations of the correction
        int correctionSweeps = 0; ///< gathers: sweeps of the correction's own solve
        double diffusionResidual = 0.0;
        double seconds = 0.0;
        double sweepSeconds = 0.0; ///< of which the transport sweep (all directions)
    };
    std::vector<Iteration> iterations;
    std::string stopReason;
    bool converged = false;
    bool accelerated = false; ///< the diffusion correction ran (and was kept)
    std::size_t voxels = 0; ///< voxels swept per direction (the touched leaves')
    std::size_t diffusionUnknowns = 0;
    int diffusionCoarsening = 1; ///< the correction's cells: blocks of this many voxels cubed
    double setupSeconds = 0.0; ///< lattice and diffusion matrices
};

/// The scattered fluence Σ_{k≥1} φ_k of the source J0 = @a source, solved as a whole:
/// φ = K(J0 + Sφ) (K: the sweep kernel, sweepPass, or the gather, scatterPass, as
/// options.kernel says; S = σs/4π) by the iteration
/// φ_{l+½} = K(J0 + Sφ_l), then with options.accelerate φ_{l+1} = φ_{l+½} + δ, δ the sweeps' diffusion
/// correction −∇·(D∇δ) + σa δ = σs(φ_{l+½} − φ_l) (Larsen's DSA: the error source iteration
/// leaves is smooth and nearly isotropic, which diffusion captures). An iteration is then no
/// longer one scattering order: its φ_l is an estimate of the whole sum. Every channel stops
/// together when the estimated error is within options.tolerance of the sum, or when the
/// change itself is below it and stops falling (the floor of the diffusion solve). Should the
/// correction make larger changes grow (ρ ≥ 1 after the third sweep), it is halved if it had
/// helped for five sweeps or more (voxels about two mean free paths thick: it overshoots), and
/// dropped otherwise or when it grows again, plain source iteration going on (the report says
/// which): the correction's diffusion is not the sweeps' discretisation (no consistent DSA),
/// and in voxels many mean free paths thick (σt·dx ≫ 1: the stability suite's σt 1000 and 1e6
/// at 32 voxels per unit) it amplifies instead of damping. The correction runs on cells of 2³
/// or 4³ voxels where those stay within a mean free path (coarse-mesh DSA, see
/// SweepSolveOptions::diffusionCoarsening). Output: a Vec3f grid named "scatter" on @a source's
/// topology; finite. Results do not depend on the thread count.
///
/// With the gather an iteration costs one gather pass (the first the lights' J0 alone, kept: it
/// is the same each time), and its fluence holds the skin voxels' light on the surface, as
/// the gathers give it. Its correction is not diffusion but the sweeps' own accelerated solve
/// (transport synthetic acceleration): δ = (I − K_s S)⁻¹ K_s S(φ_{l+½} − φ_l), K_s the sweep
/// kernel, solved to 1e-2 of δ by a nested sweepSolve (its own diffusion correction inside). The
/// sweeps differ from the gather by a few percent per order, so the gathers converge at rates of
/// 0.1-0.3 to the gather's answer (the correction vanishes with the change: it preconditions,
/// the gathers set the answer), with Anderson mixing of depth one over the corrected gathers
/// (SweepSolve.cc: where the sweeps' sum lies above the gather's the correction overshoots): the
/// thick bunny at dim 96 (albedo 0.99) to 1e-3 in 3 gathers where the diffusion-corrected
/// gathers took 7. The second iteration's change over the first is
/// no rate (the first made the whole estimate), so an accelerated solve stops at the second only
/// when its change is within a tenth of the tolerance.
///
/// An anisotropic rest of the phase (medium.material().phaseG = g* ≠ 0, Phase.h) is carried by
/// the light's mean direction of travel: each sweep's source toward ω is (J0 + σs·φ_l/4π)·R(a, ω),
/// R the rest of the phase (RestPhase: the light a Henyey-Greenstein lobe about a, scattered
/// by the rest's Legendre moments to order 3), a the mean of J0's a0 and the scattered light's
/// F_l/φ_l weighted by their grey J (one vector for the channels, SweepLattice::FirstMoment),
/// F_l the last sweep's first moment. The diffusion correction takes 1/(3(σt − g*σs)) and the
/// moment's change as a source (DiffusionCorrection::solve) and corrects φ alone. The sweeps
/// only: with the gather the medium must be isotropic (Medium::isotropic; UsageError).
/// @a moments: a0 as a grid (`scatter_source_anisotropy`; null: J0 isotropic), and out the
/// scattered fluence's anisotropy a = F/φ (`scatter_anisotropy`, source's topology).
struct SweepMoments
{
    const openvdb::Vec3SGrid* source = nullptr;
    openvdb::Vec3SGrid::Ptr scattered;
};
openvdb::Vec3SGrid::Ptr sweepSolve(const Medium& medium, const openvdb::Vec3SGrid& source, const SweepSolveOptions& options,
    SweepSolveReport& report, Interrupter* interrupter = nullptr, SweepMoments* moments = nullptr);

} // namespace vxf
