// vxf — a multigrid V-cycle preconditioning the diffusion correction's conjugate gradient (private to libvxf).
#pragma once

#include <openvdb/math/ConjGradient.h>
#include <openvdb/math/Coord.h>

#include <cstdint>
#include <memory>
#include <vector>

namespace vxf::detail {

/// One V-cycle of aggregation multigrid as the preconditioner z = M⁻¹r of OpenVDB's conjugate
/// gradient (math::pcg), for a symmetric positive definite 7-point matrix over cells of a
/// uniform grid (DiffusionCorrection's): Jacobi preconditioning takes iterations in proportion
/// to the cells across the domain (207 on the bunny at dim 1024, 3.5M cells, 30% of its
/// scatter), a V-cycle a number that barely grows with them.
///
/// Each coarser level aggregates the cells of 2³ blocks (coordinates halved); its matrix is the
/// Galerkin product PᵀAP of the piecewise-constant prolongation P with the couplings across the
/// blocks' faces halved: Galerkin alone weighs a smooth error's gradient twice (the piecewise-
/// constant interpolant's jumps), and the V-cycle's coarse correction falls short by half at
/// every level; halved, a coarse face couples as the diffusion rediscretised on cells twice as
/// wide, while the rows' sums (absorption and the vacuum faces, what bounds the slowest modes)
/// add up exactly. Red-black Gauss-Seidel smooths (red then black before the coarse correction,
/// black then red after it: the cycle is a symmetric operator, positive definite for any
/// positive definite coarse matrices, as conjugate gradient needs); the coarsest level of at
/// most kDirectCells is solved exactly (dense Cholesky), a larger one (the aggregates stopped
/// shrinking: scattered islands) by kCoarsestSweeps symmetric sweeps. Every sum runs in a fixed
/// order: the result does not depend on the thread count.
class DiffusionMultigrid : public openvdb::math::pcg::Preconditioner<double>
{
public:
    using Matrix = openvdb::math::pcg::SparseStencilMatrix<double, 7>;
    using Vector = openvdb::math::pcg::Vector<double>;
    static constexpr std::size_t kDirectCells = 512;
    static constexpr int kCoarsestSweeps = 8;
    /// Gauss-Seidel sweeps (red and black) before and after each coarse correction.
    static constexpr int kSmoothing = 2;

    /// For @a matrix (kept by reference: it outlives this), whose row i is the cell @a cells[i]
    /// and couples only face neighbours.
    DiffusionMultigrid(const Matrix& matrix, const std::vector<openvdb::Coord>& cells);
    ~DiffusionMultigrid() override;

    /// z = one V-cycle applied to r, from z = 0.
    void apply(const Vector& r, Vector& z) override;

    /// Levels, the finest included.
    int levels() const { return int(mLevels.size()); }
    /// Cells of level @a l.
    std::size_t cellsAt(int l) const;

    struct Level; ///< a level's matrix, colours, aggregates and vectors (DiffusionMultigrid.cc)

private:
    /// x = the cycle from level @a l down applied to b (the finest: the caller's vectors).
    void cycle(std::size_t l, const double* b, double* x);
    std::vector<std::unique_ptr<Level>> mLevels;
    std::vector<double> mCholesky; ///< the coarsest level's lower factor, dense, row-major (empty: sweeps)
};

} // namespace vxf::detail
