// vxf — diffusion synthetic acceleration's correction on a sweep lattice (private to libvxf).
#pragma once

#include "SweepLattice.h"

#include <openvdb/math/ConjGradient.h>

#include <memory>
#include <vector>

namespace vxf::detail {

/// The diffusion problem whose solution corrects a transport sweep (DSA, Alcouffe 1977):
/// −∇·(D∇δ) + σa δ = σs (φ_{l+½} − φ_l), D = 1/(3σt), per channel, with Marshak's vacuum
/// condition (δ + 2D ∂δ/∂n = 0, the boundary half a voxel beyond the last voxel of the medium)
/// where the medium ends. Cell-centred finite volumes on the lattice's voxels whose optical
/// thickness σt·dx is at least kThinVoxel in every channel (thinner voxels, and transport
/// through them, converge by themselves: the light leaves them), faces weighted by the
/// harmonic mean of D. The matrix is symmetric and positive definite (σa ≥ 0 and every
/// connected part touches a vacuum face), built once per channel with distinct coefficients
/// (grey media: once) as OpenVDB's 7-point SparseStencilMatrix, and solved by OpenVDB's
/// preconditioned conjugate gradient (math::pcg) to a relative residual of 1e-2, whose dot
/// products are deterministic: the correction does not depend on the thread count. A channel
/// whose matrix and right-hand side equal an earlier one's (grey media lit white) takes its
/// solution. Jacobi preconditioning: on the bunny at dim 128 (440k unknowns) twice the
/// iterations of incomplete Cholesky (66 against 33) in half the time, as its application is
/// parallel and incomplete Cholesky's triangular solves are not.
class DiffusionCorrection
{
public:
    static constexpr double kThinVoxel = 1e-3;

    explicit DiffusionCorrection(const SweepLattice& lattice);

    /// Unknowns (voxels of the diffusion domain).
    std::size_t size() const { return mVoxels.size(); }

    struct Solve
    {
        int iterations = 0;    ///< most conjugate-gradient iterations of a channel
        double residual = 0.0; ///< largest relative residual |b − Aδ|/|b| of a channel
    };

    /// δ per voxel (0 outside the domain) for @a change = φ_{l+½} − φ_l per voxel; solved to
    /// @a tolerance relative residual (at most @a maxIterations), starting from @a delta as it
    /// is when it has the lattice's size (a guess: the previous sweep's correction, scaled),
    /// from 0 otherwise.
    Solve solve(const std::vector<openvdb::Vec3f>& change, std::vector<openvdb::Vec3f>& delta, double tolerance,
        int maxIterations) const;

private:
    using Matrix = openvdb::math::pcg::SparseStencilMatrix<double, 7>;
    struct Channel
    {
        std::unique_ptr<Matrix> matrix;
        std::unique_ptr<openvdb::math::pcg::JacobiPreconditioner<Matrix>> preconditioner;
        int same = -1; ///< ≥ 0: this channel's coefficients equal those of channel `same`
    };
    const SweepLattice& mLattice;
    std::vector<std::uint32_t> mVoxels; ///< lattice voxel (per-voxel index) of each unknown
    Channel mChannels[3];
};

} // namespace vxf::detail
