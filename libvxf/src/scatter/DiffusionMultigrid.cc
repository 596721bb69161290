#include "DiffusionMultigrid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace vxf::detail {

using openvdb::math::pcg::SizeType;

struct DiffusionMultigrid::Level
{
    const Matrix* matrix = nullptr; ///< this level's (the finest: the caller's)
    std::unique_ptr<Matrix> own; ///< a coarser level's
    std::vector<double> inverseDiagonal;
    std::vector<std::uint32_t> red, black; ///< the rows by the parity of their cell's x + y + z
    std::vector<std::uint32_t> childStart, children; ///< per row, its cells on the next finer level
    std::vector<double> b, x, r; ///< a coarser level's right-hand side and solution; the residual

    std::size_t size() const { return matrix->numRows(); }
};

namespace {

constexpr std::size_t kGrain = 4096;

/// The halved coordinates of @a cells grouped: per aggregate its cells (@a childStart,
/// @a children, in the order of the aggregates' coordinates), per cell its aggregate
/// (@a parent); returns the aggregates' coordinates.
std::vector<openvdb::Coord> aggregate(const std::vector<openvdb::Coord>& cells, std::vector<std::uint32_t>& parent,
    std::vector<std::uint32_t>& childStart, std::vector<std::uint32_t>& children)
{
    const auto half = [](const openvdb::Coord& c) { return openvdb::Coord(c[0] >> 1, c[1] >> 1, c[2] >> 1); };
    children.resize(cells.size());
    for (std::size_t i = 0; i < cells.size(); ++i) children[i] = std::uint32_t(i);
    tbb::parallel_sort(children.begin(), children.end(), [&](std::uint32_t a, std::uint32_t b) {
        const openvdb::Coord ha = half(cells[a]), hb = half(cells[b]);
        return ha < hb || (ha == hb && a < b);
    });
    std::vector<openvdb::Coord> coarse;
    parent.resize(cells.size());
    childStart.clear();
    for (std::size_t k = 0; k < children.size(); ++k) {
        const openvdb::Coord h = half(cells[children[k]]);
        if (coarse.empty() || coarse.back() != h) {
            coarse.push_back(h);
            childStart.push_back(std::uint32_t(k));
        }
        parent[children[k]] = std::uint32_t(coarse.size() - 1);
    }
    childStart.push_back(std::uint32_t(children.size()));
    return coarse;
}

/// The coarse matrix over the aggregates of @a fine (see the class): each aggregate's row sum
/// the sum of its cells', a coupling across its faces half the sum of its cells'.
std::unique_ptr<DiffusionMultigrid::Matrix> coarseMatrix(const DiffusionMultigrid::Matrix& fine, const std::vector<std::uint32_t>& parent,
    const std::vector<std::uint32_t>& childStart, const std::vector<std::uint32_t>& children)
{
    const std::size_t count = childStart.size() - 1;
    auto coarse = std::make_unique<DiffusionMultigrid::Matrix>(SizeType(count));
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, kGrain), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t I = range.begin(); I != range.end(); ++I) {
            double rowSum = 0.0;
            std::pair<std::uint32_t, double> faces[6];
            int faceCount = 0;
            for (std::uint32_t k = childStart[I]; k < childStart[I + 1]; ++k) {
                const std::uint32_t i = children[k];
                for (auto entry = fine.getConstRow(SizeType(i)).cbegin(); entry; ++entry) {
                    const double a = *entry;
                    rowSum += a;
                    const std::uint32_t J = parent[entry.column()];
                    if (J == I) continue;
                    int f = 0;
                    while (f < faceCount && faces[f].first != J) ++f;
                    if (f == faceCount) {
                        if (faceCount == 6) continue; // (a face neighbour's aggregate: at most 6)
                        faces[faceCount++] = {J, 0.0};
                    }
                    faces[f].second += 0.5 * a;
                }
            }
            double diagonal = rowSum;
            for (int f = 0; f < faceCount; ++f) {
                diagonal -= faces[f].second;
                coarse->setValue(SizeType(I), SizeType(faces[f].first), faces[f].second);
            }
            coarse->setValue(SizeType(I), SizeType(I), diagonal);
        }
    });
    return coarse;
}

/// @a level's inverse diagonal and its rows by colour, its cells at @a cells.
void prepare(DiffusionMultigrid::Level& level, const std::vector<openvdb::Coord>& cells)
{
    const std::size_t count = level.size();
    level.inverseDiagonal.resize(count);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, kGrain), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const double d = level.matrix->getValue(SizeType(i), SizeType(i));
            level.inverseDiagonal[i] = d > 0.0 ? 1.0 / d : 0.0;
        }
    });
    for (std::size_t i = 0; i < count; ++i) {
        ((cells[i][0] + cells[i][1] + cells[i][2]) & 1 ? level.black : level.red).push_back(std::uint32_t(i));
    }
    level.r.assign(count, 0.0);
}

/// Gauss-Seidel over the rows @a rows (one colour: none couples another of them).
void relax(const DiffusionMultigrid::Level& level, const std::vector<std::uint32_t>& rows, const double* b, double* x)
{
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows.size(), kGrain), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
            const std::uint32_t i = rows[k];
            double sum = b[i];
            for (auto entry = level.matrix->getConstRow(SizeType(i)).cbegin(); entry; ++entry) {
                if (entry.column() != i) sum -= *entry * x[entry.column()];
            }
            x[i] = sum * level.inverseDiagonal[i];
        }
    });
}

/// The residual b − Ax on @a level's red rows, 0 on its black ones (just relaxed).
void residual(DiffusionMultigrid::Level& level, const double* b, const double* x)
{
    for (const std::uint32_t i : level.black) level.r[i] = 0.0;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, level.red.size(), kGrain), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
            const std::uint32_t i = level.red[k];
            double sum = b[i];
            for (auto entry = level.matrix->getConstRow(SizeType(i)).cbegin(); entry; ++entry) sum -= *entry * x[entry.column()];
            level.r[i] = sum;
        }
    });
}

/// The lower Cholesky factor of @a matrix, dense and row-major (empty when a pivot is not positive).
std::vector<double> cholesky(const DiffusionMultigrid::Matrix& matrix)
{
    const std::size_t n = matrix.numRows();
    std::vector<double> l(n * n, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
        for (auto entry = matrix.getConstRow(SizeType(i)).cbegin(); entry; ++entry) l[i * n + entry.column()] = *entry;
    }
    for (std::size_t j = 0; j < n; ++j) {
        double d = l[j * n + j];
        for (std::size_t k = 0; k < j; ++k) d -= l[j * n + k] * l[j * n + k];
        if (!(d > 0.0)) return {};
        d = std::sqrt(d);
        l[j * n + j] = d;
        for (std::size_t i = j + 1; i < n; ++i) {
            double s = l[i * n + j];
            for (std::size_t k = 0; k < j; ++k) s -= l[i * n + k] * l[j * n + k];
            l[i * n + j] = s / d;
        }
        for (std::size_t k = j + 1; k < n; ++k) l[j * n + k] = 0.0;
    }
    return l;
}

} // namespace

DiffusionMultigrid::DiffusionMultigrid(const Matrix& matrix, const std::vector<openvdb::Coord>& cells)
    : openvdb::math::pcg::Preconditioner<double>(matrix)
{
    auto finest = std::make_unique<Level>();
    finest->matrix = &matrix;
    prepare(*finest, cells);
    mLevels.push_back(std::move(finest));
    std::vector<openvdb::Coord> coords;
    const std::vector<openvdb::Coord>* current = &cells;
    while (mLevels.back()->size() > kDirectCells) {
        const Level& fine = *mLevels.back();
        auto coarse = std::make_unique<Level>();
        std::vector<std::uint32_t> parent;
        std::vector<openvdb::Coord> next = aggregate(*current, parent, coarse->childStart, coarse->children);
        if (double(next.size()) > 0.8 * double(fine.size())) break; // stalled: islands of a few cells
        coarse->own = coarseMatrix(*fine.matrix, parent, coarse->childStart, coarse->children);
        coarse->matrix = coarse->own.get();
        prepare(*coarse, next);
        coarse->b.assign(next.size(), 0.0);
        coarse->x.assign(next.size(), 0.0);
        coords.swap(next);
        current = &coords;
        mLevels.push_back(std::move(coarse));
    }
    if (mLevels.back()->size() <= kDirectCells) mCholesky = cholesky(*mLevels.back()->matrix);
}

DiffusionMultigrid::~DiffusionMultigrid() = default;

std::size_t DiffusionMultigrid::cellsAt(int l) const { return mLevels[std::size_t(l)]->size(); }

void DiffusionMultigrid::apply(const Vector& r, Vector& z) { cycle(0, r.data(), z.data()); }

void DiffusionMultigrid::cycle(std::size_t l, const double* b, double* x)
{
    Level& level = *mLevels[l];
    const std::size_t count = level.size();
    std::fill(x, x + count, 0.0);
    if (l + 1 == mLevels.size() && !mCholesky.empty()) {
        // L Lᵀ x = b: forward, then back substitution.
        for (std::size_t i = 0; i < count; ++i) {
            double s = b[i];
            for (std::size_t k = 0; k < i; ++k) s -= mCholesky[i * count + k] * x[k];
            x[i] = s / mCholesky[i * count + i];
        }
        for (std::size_t i = count; i-- > 0;) {
            double s = x[i];
            for (std::size_t k = i + 1; k < count; ++k) s -= mCholesky[k * count + i] * x[k];
            x[i] = s / mCholesky[i * count + i];
        }
        return;
    }
    const bool coarsest = l + 1 == mLevels.size();
    const int sweeps = coarsest ? kCoarsestSweeps : kSmoothing;
    for (int s = 0; s < sweeps; ++s) {
        relax(level, level.red, b, x);
        relax(level, level.black, b, x);
    }
    if (!coarsest) {
        residual(level, b, x);
        Level& coarse = *mLevels[l + 1];
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, coarse.size(), kGrain), [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t I = range.begin(); I != range.end(); ++I) {
                double sum = 0.0;
                for (std::uint32_t k = coarse.childStart[I]; k < coarse.childStart[I + 1]; ++k) sum += level.r[coarse.children[k]];
                coarse.b[I] = sum;
            }
        });
        cycle(l + 1, coarse.b.data(), coarse.x.data());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, coarse.size(), kGrain), [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t I = range.begin(); I != range.end(); ++I) {
                for (std::uint32_t k = coarse.childStart[I]; k < coarse.childStart[I + 1]; ++k) x[coarse.children[k]] += coarse.x[I];
            }
        });
    }
    for (int s = 0; s < sweeps; ++s) {
        relax(level, level.black, b, x);
        relax(level, level.red, b, x);
    }
}

} // namespace vxf::detail
