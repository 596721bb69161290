// vxf — diffusion synthetic acceleration's correction on a sweep lattice (private to libvxf).
#pragma once

#include "transport/lattice/SweepLattice.h"
#include "DiffusionMultigrid.h"

#include <openvdb/math/ConjGradient.h>

#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

namespace vxf::detail {

/// The diffusion problem whose solution corrects a transport sweep (DSA, Alcouffe 1977):
/// −∇·(D∇δ) + σa δ = σs (φ_{l+½} − φ_l), D = 1/(3σt), per channel, with Marshak's vacuum
/// condition (δ + 2D ∂δ/∂n = 0, the boundary half a cell beyond the last cell of the medium)
/// where the medium ends. Cell-centred finite volumes over the lattice's voxels whose optical
/// thickness σt·dx is at least kThinVoxel in every channel (thinner voxels, and transport
/// through them, converge by themselves: the light leaves them), faces weighted by the
/// harmonic mean of D. The cells are the voxels themselves, or with a coarsening of 2 or 4 blocks
/// of 2³ or 4³ voxels (those of the domain among them), their coefficients and right-hand side the
/// means over those voxels and each voxel taking its cell's correction: the error the sweeps
/// leave at high albedo is smooth over a mean free path, and where voxels are optically thin the
/// coarse cells still resolve it (Morel and Larsen's coarse-mesh DSA), at an eighth of the
/// unknowns and about half the iterations (the condition number goes with 1/(σt·h)²). A coarse
/// leaf of the lattice (one value for 8³ voxels) fills the cells of its block, each with its
/// value, and takes their mean correction.
/// The matrix is symmetric and positive definite (σa ≥ 0 and every connected part touches a
/// vacuum face), built once per channel with distinct coefficients (grey media: once) as
/// OpenVDB's 7-point SparseStencilMatrix, and solved by OpenVDB's preconditioned conjugate
/// gradient (math::pcg), whose dot products are deterministic: the correction does not depend
/// on the thread count. A channel whose matrix and right-hand side equal an earlier one's (grey
/// media lit white) takes its solution. Preconditioned by a multigrid V-cycle
/// (DiffusionMultigrid): Jacobi's iterations grew with the cells across the domain (the thick
/// bunny with a band: 91–106 a sweep at dim 512, 207 at dim 1024, 3.5M cells, 30% of that
/// scatter), the V-cycle's stay at 4–5 (incomplete Cholesky's triangular solves are serial).
class DiffusionCorrection
{
public:
    static constexpr double kThinVoxel = 1e-3;
    /// coarseningFor: the largest cells (2³ or 4³ voxels) whose mean optical thickness σt·h is
    /// at most kCoarseThickness. The thick bunny at albedo 0.99 to 1e-3 (bench/pipeline, 16
    /// directions): dim 128 (σt·dx 0.5) 6 sweeps in 7.5 s with cells of one voxel, 6 in 2.7 s
    /// with 2³; in 4³ (σt·h 2) the rate rose from 0.3 to 0.65 (15 sweeps, 5.4 s). Dim 256 (σt·dx
    /// 0.25): 6 sweeps in 114 s with one voxel, 5 in 19.2 s with 2³, 6 in 17.6 s with 4³.
    static constexpr double kCoarseThickness = 1.0;
    static constexpr int kMaxCoarsening = 4;

    /// The coarsening (1, 2 or 4) for @a lattice's medium.
    static int coarseningFor(const SweepLattice& lattice);

    /// Over @a lattice's medium, in cells of @a coarsening³ voxels (a power of 2; others round
    /// down). With a phase of mean cosine @a restG (the transport's, Phase.h) the diffusion
    /// coefficient is the transport-corrected 1/(3(σt − g·σs)).
    explicit DiffusionCorrection(const SweepLattice& lattice, int coarsening = 1, double restG = 0.0);

    /// Unknowns (cells of the diffusion domain).
    std::size_t size() const { return mStart.empty() ? 0 : mStart.size() - 1; }
    int coarsening() const { return mFactor; }

    struct Solve
    {
        int iterations = 0; ///< most conjugate-gradient iterations of a channel
        double residual = 0.0; ///< largest relative residual |b − Aδ|/|b| of a channel
    };

    /// δ per cell for the change φ_{l+½} − φ_l per voxel (@a next − @a phi), kept here (addTo); solved to
    /// @a tolerance relative residual (at most @a maxIterations), starting from the last
    /// solution times @a guessScale (the previous sweep's correction scaled as the change
    /// shrank; 0, or before the first solve: from 0).
    /// With @a fluxChange (per cell, the mean of its voxels' F_{l+½} − F_l of the light's first
    /// moment, grey, along the lattice's index axes: cellMeans) and a phase, the right-hand side
    /// takes the moment's part of the
    /// P1 error equations too, −∇·(χ1σs·ΔF/σtr) (ΔF grey, each channel by its own σs/σtr; see
    /// the constructor for where it fades). The moment itself is not corrected: correcting it
    /// by the P1 error equations' ε1 = −D∇δ + χ1σsΔF/σtr too made every cloud of
    /// docs/accuracy-notes.md (y) diverge (P1 synthetic acceleration is known to be unstable in
    /// several dimensions); without this term the correction, blind to the moment's lag, stalled
    /// or diverged on the forward clouds (g ≥ 0.6 at albedo 0.999).
    Solve solve(const std::vector<openvdb::Vec3f>& next, const std::vector<openvdb::Vec3f>& phi, double guessScale, double tolerance,
        int maxIterations, const std::vector<openvdb::Vec3d>* fluxChange = nullptr);

    /// Per cell, the mean of @a values (per voxel) over its voxels (empty for empty @a values).
    std::vector<openvdb::Vec3d> cellMeans(const std::vector<openvdb::Vec3f>& values) const;

    /// @a values (per voxel) += @a weight × the last solution δ, each voxel of the domain its cell's.
    void addTo(std::vector<openvdb::Vec3f>& values, double weight = 1.0) const;

private:
    /// The cells (blocks of 2^@a shift voxels a side holding a voxel of the domain) in lattice
    /// order, each one's index in @a cellIndex; each cell's voxels (mStart, mMembers), the fine
    /// leaves' cells first (mFineCells), then the coarse leaves' (mCoarse).
    std::vector<openvdb::Coord> indexCells(int shift, std::unordered_map<openvdb::Coord, std::int32_t, CoordHash>& cellIndex);

    using Matrix = openvdb::math::pcg::SparseStencilMatrix<double, 7>;
    struct Channel
    {
        std::unique_ptr<Matrix> matrix;
        std::unique_ptr<DiffusionMultigrid> preconditioner;
        int same = -1; ///< ≥ 0: this channel's coefficients equal those of channel `same`
    };
    const SweepLattice& mLattice;
    int mFactor = 1;
    /// The cells of the fine leaves' voxels: [0, mFineCells), each voxel a member of one (no
    /// voxel's cell held per voxel: 4 bytes a lattice voxel, 0.3 GB for the bunny at dim 1024).
    std::size_t mFineCells = 0;
    /// A coarse leaf's value: a member of the `count` cells of its block from `first`.
    struct CoarseCell
    {
        std::uint32_t voxel, first, count;
    };
    std::vector<CoarseCell> mCoarse;
    std::vector<std::uint32_t> mStart; ///< cell c's voxels: mMembers[mStart[c] … mStart[c + 1])
    std::vector<std::uint32_t> mMembers; ///< the domain's voxels (per-voxel indices), cell by cell
    Channel mChannels[3];
    std::vector<std::int32_t> mNeighbours; ///< with a phase, 6 per cell (−x, +x, −y, +y, −z, +z), −1: vacuum
    std::vector<openvdb::Vec3d> mMomentFactor; ///< with a phase, per cell, χ1·σs/σtr (faded)
    std::vector<double> mSolution[3]; ///< per channel, δ per cell (empty: none yet)
};

} // namespace vxf::detail
