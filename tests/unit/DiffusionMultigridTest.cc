// The diffusion correction's multigrid preconditioner (src/scatter/DiffusionMultigrid.h): conjugate
// gradient converges in a few iterations where Jacobi's takes many, to the same solution; the
// cycle is symmetric and positive (as conjugate gradient needs), the same bits on any thread
// count, holds on a domain whose aggregates stop shrinking, and solves a small system exactly.
#include "scatter/DiffusionMultigrid.h"

#include <catch2/catch.hpp>
#include <openvdb/util/NullInterrupter.h>
#include <tbb/global_control.h>

#include <cmath>
#include <random>
#include <unordered_map>

namespace {

using vxf::detail::DiffusionMultigrid;
using Matrix = DiffusionMultigrid::Matrix;
using Vector = DiffusionMultigrid::Vector;
using openvdb::math::pcg::SizeType;

/// DiffusionCorrection's rows over @a cells: D̃ = 1/(3 σt h) at optical thickness @a thickness
/// per cell, albedo @a albedo, Marshak's vacuum faces where no cell is.
std::unique_ptr<Matrix> diffusionMatrix(const std::vector<openvdb::Coord>& cells, double thickness, double albedo)
{
    std::unordered_map<openvdb::Coord, SizeType> index;
    for (std::size_t i = 0; i < cells.size(); ++i) index.emplace(cells[i], SizeType(i));
    auto matrix = std::make_unique<Matrix>(SizeType(cells.size()));
    const double d = 1.0 / (3.0 * thickness);
    for (std::size_t i = 0; i < cells.size(); ++i) {
        double diagonal = (1.0 - albedo) * thickness;
        for (int f = 0; f < 6; ++f) {
            openvdb::Coord next = cells[i];
            next[f >> 1] += (f & 1) ? 1 : -1;
            const auto found = index.find(next);
            if (found == index.end()) {
                diagonal += d / (0.5 + 2.0 * d);
            } else {
                diagonal += d;
                matrix->setValue(SizeType(i), found->second, -d);
            }
        }
        matrix->setValue(SizeType(i), SizeType(i), diagonal);
    }
    return matrix;
}

std::vector<openvdb::Coord> cube(int side, const openvdb::Coord& origin = openvdb::Coord(0))
{
    std::vector<openvdb::Coord> cells;
    for (int x = 0; x < side; ++x)
        for (int y = 0; y < side; ++y)
            for (int z = 0; z < side; ++z) cells.push_back(origin.offsetBy(x, y, z));
    return cells;
}

Vector randomVector(std::size_t size, unsigned seed)
{
    std::mt19937 random(seed);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    Vector v(SizeType(size), 0.0);
    for (std::size_t i = 0; i < size; ++i) v[SizeType(i)] = uniform(random);
    return v;
}

template <typename Preconditioner>
openvdb::math::pcg::State solve(const Matrix& matrix, const Vector& b, Vector& x, Preconditioner& preconditioner)
{
    openvdb::math::pcg::State termination = openvdb::math::pcg::terminationDefaults<double>();
    termination.iterations = 5000;
    termination.relativeError = 1e-8;
    openvdb::util::NullInterrupter never;
    return openvdb::math::pcg::solve(matrix, b, x, preconditioner, never, termination);
}

double largestDifference(const Vector& a, const Vector& b)
{
    double difference = 0.0;
    for (SizeType i = 0; i < a.size(); ++i) difference = std::max(difference, std::abs(a[i] - b[i]));
    return difference;
}

/// Conjugate gradient on @a matrix with @a multigrid and with Jacobi's preconditioner from the
/// same random right-hand side (@a seed): both states, and the largest difference of the
/// solutions relative to the largest of Jacobi's.
struct Solved
{
    openvdb::math::pcg::State multigrid, jacobi;
    double difference;
};
Solved solveBoth(const Matrix& matrix, DiffusionMultigrid& multigrid, unsigned seed)
{
    const Vector b = randomVector(matrix.numRows(), seed);
    Vector x(b.size(), 0.0), reference(b.size(), 0.0);
    Solved solved;
    solved.multigrid = solve(matrix, b, x, multigrid);
    openvdb::math::pcg::JacobiPreconditioner<Matrix> jacobi(matrix);
    solved.jacobi = solve(matrix, b, reference, jacobi);
    solved.difference = largestDifference(x, reference) / reference.infNorm();
    return solved;
}

} // namespace

TEST_CASE("the multigrid cycle takes conjugate gradient to Jacobi's solution in a few iterations", "[scatter][diffusion]")
{
    // Voxels half a mean free path thick at albedo 0.99, 48 across: Jacobi's iterations grow
    // with the cells across, a V-cycle's do not.
    const std::vector<openvdb::Coord> cells = cube(48, openvdb::Coord(-20, -3, 7));
    const auto matrix = diffusionMatrix(cells, 0.5, 0.99);
    DiffusionMultigrid multigrid(*matrix, cells);
    CHECK(multigrid.levels() == 4); // 110592 → 15000 (the odd origin: 24 × 25 × 25 aggregates) → 2197 → 343 cells
    CHECK(multigrid.cellsAt(multigrid.levels() - 1) <= DiffusionMultigrid::kDirectCells);
    const Solved solved = solveBoth(*matrix, multigrid, 1);
    INFO("multigrid " << solved.multigrid.iterations << " iterations, Jacobi " << solved.jacobi.iterations);
    CHECK(solved.multigrid.success);
    CHECK(solved.jacobi.success);
    CHECK(solved.multigrid.iterations <= 16);
    CHECK(solved.jacobi.iterations >= 5 * solved.multigrid.iterations);
    CHECK(solved.difference <= 1e-6);
}

TEST_CASE("the multigrid cycle is symmetric, positive and the same on any thread count", "[scatter][diffusion]")
{
    // A thick shell (a sphere with a hollow) and a slab apart from it, thin and thick voxels.
    std::vector<openvdb::Coord> cells;
    for (const openvdb::Coord& c : cube(40, openvdb::Coord(-20))) {
        const double r = std::sqrt(double(c.asVec3d().lengthSqr()));
        if (r < 19.0 && r > 7.0) cells.push_back(c);
    }
    for (const openvdb::Coord& c : cube(30, openvdb::Coord(25, -15, -3))) {
        if (c[2] < 1) cells.push_back(c);
    }
    const auto matrix = diffusionMatrix(cells, 2.0, 0.999);
    DiffusionMultigrid multigrid(*matrix, cells);
    const Vector u = randomVector(cells.size(), 2), v = randomVector(cells.size(), 3);
    Vector mu(u.size(), 0.0), mv(u.size(), 0.0);
    multigrid.apply(u, mu);
    multigrid.apply(v, mv);
    CHECK(std::abs(u.dot(mv) - v.dot(mu)) <= 1e-12 * std::sqrt(u.dot(u) * mv.dot(mv)));
    CHECK(u.dot(mu) > 0.0);
    CHECK(v.dot(mv) > 0.0);
    Vector single(u.size(), 0.0);
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        multigrid.apply(u, single);
    }
    CHECK(largestDifference(single, mu) == 0.0);
}

TEST_CASE("the multigrid cycle holds where the aggregates stop shrinking", "[scatter][diffusion]")
{
    // 3000 cells alone, 64 apart (each its own aggregate at every level), beside a block:
    // the coarsest level stays above kDirectCells and is relaxed, not factored.
    std::vector<openvdb::Coord> cells = cube(16, openvdb::Coord(-40));
    for (int i = 0; i < 3000; ++i) cells.emplace_back(64 * (i % 20), 64 * ((i / 20) % 15), 64 * (i / 300));
    const auto matrix = diffusionMatrix(cells, 1.0, 0.99);
    DiffusionMultigrid multigrid(*matrix, cells);
    CHECK(multigrid.cellsAt(multigrid.levels() - 1) > DiffusionMultigrid::kDirectCells);
    const Solved solved = solveBoth(*matrix, multigrid, 4);
    INFO("multigrid " << solved.multigrid.iterations << " iterations");
    CHECK(solved.multigrid.success);
    CHECK(solved.multigrid.iterations <= 30);
    CHECK(solved.difference <= 1e-6);
}

TEST_CASE("a system of at most kDirectCells cells is solved exactly, in one iteration", "[scatter][diffusion]")
{
    // 7³ = 343 cells: one level, factored; the cycle is the inverse, so conjugate gradient stops
    // after its first step.
    const std::vector<openvdb::Coord> cells = cube(7, openvdb::Coord(3, -9, 1));
    const auto matrix = diffusionMatrix(cells, 0.5, 0.99);
    DiffusionMultigrid multigrid(*matrix, cells);
    CHECK(multigrid.levels() == 1);
    const Solved solved = solveBoth(*matrix, multigrid, 5);
    INFO("multigrid " << solved.multigrid.iterations << " iterations");
    CHECK(solved.multigrid.success);
    CHECK(solved.multigrid.iterations <= 1);
    CHECK(solved.difference <= 1e-6);
}
