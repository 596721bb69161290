#include "DiffusionCorrection.h"

#include <vxf/core/Error.h>
#include <vxf/core/Hash.h>

#include <openvdb/util/NullInterrupter.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace vxf::detail {

int DiffusionCorrection::coarseningFor(const SweepLattice& lattice)
{
    // The mean optical thickness σt·dx of the domain's voxels (the thickest channel).
    const SweepLattice::Coefficient sigmaT = lattice.sigmaT();
    double sum = 0.0, count = 0.0; // (a coarse cell weighs as its voxels)
    for (std::size_t v = 0; v < sigmaT.size(); ++v) {
        const openvdb::Vec3f t = sigmaT[v];
        if (std::min({t[0], t[1], t[2]}) * lattice.voxelSize() < kThinVoxel) continue;
        sum += std::max({t[0], t[1], t[2]}) * lattice.voxelSize() * lattice.voxelsAt(v);
        count += lattice.voxelsAt(v);
    }
    int factor = 1;
    while (count > 0.0 && factor < kMaxCoarsening && 2 * factor * sum <= kCoarseThickness * count) factor *= 2;
    return factor;
}

std::vector<openvdb::Coord> DiffusionCorrection::indexCells(
    int shift, std::unordered_map<openvdb::Coord, std::int32_t, CoordHash>& cellIndex)
{
    constexpr int L = SweepLattice::kLeafVoxels;
    const SweepLattice& lattice = mLattice;
    const SweepLattice::Coefficient sigmaT = lattice.sigmaT();
    const double dx = lattice.voxelSize();
    const auto inDomain = [&](const openvdb::Vec3f& t) { return std::min({t[0], t[1], t[2]}) * dx >= kThinVoxel; };
    std::vector<openvdb::Coord> cells;
    mStart.assign(1, 0);
    mMembers.clear();
    // A fine leaf's cells are its own (its origin a multiple of 8, a cell at most 8 wide): each
    // indexed once, in the order of its first voxel, its voxels in lattice order.
    const int side = std::max(1, 8 >> shift); // a leaf's cells a side
    std::vector<std::int32_t> local(std::size_t(side * side * side));
    std::vector<std::uint32_t> filled;
    cellIndex.reserve(lattice.leafCount() * local.size()); // (at most: no rehashing)
    for (std::size_t n = 0; n < lattice.fineLeafCount(); ++n) {
        std::fill(local.begin(), local.end(), -1);
        const std::size_t first = cells.size();
        const auto localCell = [&](int v) { return (((v >> 6) >> shift) * side + (((v >> 3) & 7) >> shift)) * side + ((v & 7) >> shift); };
        for (int v = 0; v < L; ++v) {
            if (!inDomain(sigmaT[n * L + v])) continue;
            std::int32_t& cell = local[std::size_t(localCell(v))];
            if (cell < 0) {
                cell = std::int32_t(cells.size() - first);
                const openvdb::Coord c = lattice.origin(n).offsetBy(v >> 6, (v >> 3) & 7, v & 7);
                cells.emplace_back(c[0] >> shift, c[1] >> shift, c[2] >> shift);
                cellIndex.emplace(cells.back(), std::int32_t(cells.size() - 1));
                mStart.push_back(0);
            }
            ++mStart[first + std::size_t(cell) + 1];
        }
        // The counts to starts, then the voxels to their places.
        for (std::size_t c = first; c < cells.size(); ++c) mStart[c + 1] += mStart[c];
        mMembers.resize(mStart.back());
        filled.assign(mStart.begin() + std::ptrdiff_t(first), mStart.end() - 1);
        for (int v = 0; v < L; ++v) {
            if (inDomain(sigmaT[n * L + v])) mMembers[filled[std::size_t(local[std::size_t(localCell(v))])]++] = std::uint32_t(n * L + v);
        }
    }
    mFineCells = cells.size();
    // A coarse leaf's cell: the cells of its block (each of its one value; the diffusion's
    // grid stays uniform), its correction their mean.
    for (std::size_t n = lattice.fineLeafCount(); n < lattice.leafCount(); ++n) {
        const auto v = std::uint32_t(lattice.voxelStart(n));
        if (!inDomain(sigmaT[v])) continue;
        const openvdb::Coord first(lattice.origin(n)[0] >> shift, lattice.origin(n)[1] >> shift, lattice.origin(n)[2] >> shift);
        mCoarse.push_back({v, std::uint32_t(cells.size()), std::uint32_t(side * side * side)});
        for (int a = 0; a < side; ++a) {
            for (int b = 0; b < side; ++b) {
                for (int c = 0; c < side; ++c) {
                    cellIndex.emplace(first.offsetBy(a, b, c), std::int32_t(cells.size())); // (new: the blocks are apart)
                    cells.push_back(first.offsetBy(a, b, c));
                    mMembers.push_back(v);
                    mStart.push_back(std::uint32_t(mMembers.size()));
                }
            }
        }
    }
    if (cells.empty()) mStart.clear();
    mMembers.shrink_to_fit(); // (grown leaf by leaf: up to twice its size, kept for the solve)
    mStart.shrink_to_fit();
    return cells;
}

DiffusionCorrection::DiffusionCorrection(const SweepLattice& lattice, int coarsening, double restG)
    : mLattice(lattice)
    , mFactor(std::max(coarsening, 1))
{
    const double dx = lattice.voxelSize();
    int shift = 0; // log2 of the coarsening (1, 2, 4, …)
    while ((2 << shift) <= mFactor) ++shift;
    mFactor = 1 << shift;
    const double h = dx * mFactor; // a cell's width
    const SweepLattice::Coefficient sigmaT = lattice.sigmaT(), sigmaS = lattice.sigmaS();
    std::unordered_map<openvdb::Coord, std::int32_t, CoordHash> cellIndex;
    const std::vector<openvdb::Coord> cells = indexCells(shift, cellIndex);
    if (cells.empty()) return;
    // A cell's coefficients: the means over its voxels of the domain.
    std::vector<openvdb::Vec3d> cellSigmaT(cells.size(), openvdb::Vec3d(0.0)), cellSigmaA(cells.size(), openvdb::Vec3d(0.0));
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cells.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t c = r.begin(); c != r.end(); ++c) {
            for (std::uint32_t k = mStart[c]; k < mStart[c + 1]; ++k) {
                const openvdb::Vec3d t(sigmaT[mMembers[k]]), s(sigmaS[mMembers[k]]);
                cellSigmaT[c] += restG != 0.0 ? t - restG * s : t; // the transport's σtr (D = 1/3σtr)
                for (int ch = 0; ch < 3; ++ch) cellSigmaA[c][ch] += std::max(0.0, t[ch] - s[ch]);
            }
            const double count = double(mStart[c + 1] - mStart[c]);
            cellSigmaT[c] /= count;
            cellSigmaA[c] /= count;
        }
    });

    // With a phase, each cell's six neighbours (−1: vacuum) and its factor of the moment's
    // change, χ1·σs/σtr per channel (solve's fluxChange), faded by 1/(σtr·h) in cells thicker
    // than a transport mean free path: there a sweep's flux within a cell is not diffusion's,
    // and the term slowed the smoke puff at 3 mean free paths per voxel (g 0.2, albedo 0.999)
    // from 7 sweeps to 70 (docs/accuracy-notes.md (y)).
    if (restG != 0.0) {
        mNeighbours.assign(cells.size() * 6, -1);
        mMomentFactor.assign(cells.size(), openvdb::Vec3d(0.0));
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cells.size()), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t c = r.begin(); c != r.end(); ++c) {
                for (int f = 0; f < 6; ++f) {
                    openvdb::Coord next = cells[c];
                    next[f >> 1] += (f & 1) ? 1 : -1;
                    const auto found = cellIndex.find(next);
                    if (found != cellIndex.end()) mNeighbours[c * 6 + std::size_t(f)] = found->second;
                }
                openvdb::Vec3d s(0.0);
                for (std::uint32_t k = mStart[c]; k < mStart[c + 1]; ++k) s += openvdb::Vec3d(sigmaS[mMembers[k]]);
                s /= double(mStart[c + 1] - mStart[c]);
                for (int ch = 0; ch < 3; ++ch) {
                    mMomentFactor[c][ch] = restG * s[ch] / cellSigmaT[c][ch] * std::min(1.0, 1.0 / (cellSigmaT[c][ch] * h));
                }
            }
        });
    }

    for (int ch = 0; ch < 3; ++ch) {
        for (int other = 0; other < ch && mChannels[ch].same < 0; ++other) {
            if (mChannels[other].same >= 0) continue;
            bool equal = true;
            for (std::size_t i = 0; i < mMembers.size() && equal; ++i) {
                const std::size_t v = mMembers[i];
                equal = sigmaT[v][ch] == sigmaT[v][other] && sigmaS[v][ch] == sigmaS[v][other];
            }
            if (equal) mChannels[ch].same = other;
        }
        if (mChannels[ch].same >= 0) continue;
        // In units of the cell: D̃ = D/h = 1/(3σt·h), σ̃a = σa·h; row i:
        // (σ̃a + Σ_faces D̃_f + Σ_vacuum faces D̃/(½ + 2D̃)) δ_i − Σ_faces D̃_f δ_j = σs·Δφ·h,
        // D̃_f = 2D̃_iD̃_j/(D̃_i + D̃_j). (Marshak: the face's flux D(δ_i − δ_b)/(h/2) = δ_b/2.)
        auto matrix = std::make_unique<Matrix>(openvdb::math::pcg::SizeType(cells.size()));
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cells.size()), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const double d = 1.0 / (3.0 * cellSigmaT[i][ch] * h);
                double diagonal = cellSigmaA[i][ch] * h;
                const int face[6][3] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
                for (const auto& f : face) {
                    const auto found = cellIndex.find(cells[i].offsetBy(f[0], f[1], f[2]));
                    if (found == cellIndex.end()) {
                        diagonal += d / (0.5 + 2.0 * d);
                    } else {
                        const double dj = 1.0 / (3.0 * cellSigmaT[std::size_t(found->second)][ch] * h);
                        const double df = 2.0 * d * dj / (d + dj);
                        diagonal += df;
                        matrix->setValue(openvdb::math::pcg::SizeType(i), openvdb::math::pcg::SizeType(found->second), -df);
                    }
                }
                matrix->setValue(openvdb::math::pcg::SizeType(i), openvdb::math::pcg::SizeType(i), diagonal);
            }
        });
        mChannels[ch].preconditioner = std::make_unique<DiffusionMultigrid>(*matrix, cells);
        mChannels[ch].matrix = std::move(matrix);
    }
}

std::vector<openvdb::Vec3d> DiffusionCorrection::cellMeans(const std::vector<openvdb::Vec3f>& values) const
{
    std::vector<openvdb::Vec3d> means;
    if (values.empty()) return means;
    means.assign(size(), openvdb::Vec3d(0.0));
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, means.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t c = r.begin(); c != r.end(); ++c) {
            for (std::uint32_t k = mStart[c]; k < mStart[c + 1]; ++k) means[c] += openvdb::Vec3d(values[mMembers[k]]);
            means[c] /= double(mStart[c + 1] - mStart[c]);
        }
    });
    return means;
}

DiffusionCorrection::Solve DiffusionCorrection::solve(const std::vector<openvdb::Vec3f>& next, const std::vector<openvdb::Vec3f>& phi,
    double guessScale, double tolerance, int maxIterations, const std::vector<openvdb::Vec3d>* fluxChange)
{
    Solve result;
    if (mMembers.empty()) return result;
    const double h = mLattice.voxelSize() * mFactor;
    const SweepLattice::Coefficient sigmaS = mLattice.sigmaS();
    const std::size_t cells = size();
    const auto count = openvdb::math::pcg::SizeType(cells);
    const auto change = [&](std::size_t v) { return next[v] - phi[v]; };
    // The first moment's change per cell (its voxels' mean), for the term −∇·(χ1σsΔF/σtr).
    const std::vector<openvdb::Vec3d>* cellFlux = fluxChange && !fluxChange->empty() && !mMomentFactor.empty() ? fluxChange : nullptr;
    if (cellFlux && cellFlux->size() != cells) throw Error("diffusion correction: the first moment's change is not one a cell");
    for (int ch = 0; ch < 3; ++ch) {
        const int source = mChannels[ch].same >= 0 ? mChannels[ch].same : ch;
        const Channel& channel = mChannels[source];
        // A channel with the same matrix and right-hand side as one solved already (grey media
        // lit white): its solution.
        int solvedAs = -1;
        for (int other = 0; other < ch && solvedAs < 0 && mChannels[ch].same >= 0; ++other) {
            const int otherSource = mChannels[other].same >= 0 ? mChannels[other].same : other;
            if (otherSource != source) continue;
            bool equal = true;
            for (std::size_t i = 0; i < mMembers.size() && equal; ++i) {
                const std::size_t v = mMembers[i];
                const openvdb::Vec3f d = change(v);
                equal = d[ch] == d[other] && sigmaS[v][ch] == sigmaS[v][other];
            }
            if (equal) solvedAs = other;
        }
        if (solvedAs >= 0) {
            mSolution[ch] = mSolution[solvedAs];
            continue;
        }
        // A cell's right-hand side: the mean over its voxels; the guess: the last solution, scaled.
        openvdb::math::pcg::Vector<double> b(count), x(count, 0.0);
        const bool guess = mSolution[ch].size() == cells && guessScale > 0.0;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cells), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t c = r.begin(); c != r.end(); ++c) {
                double rhs = 0.0;
                for (std::uint32_t k = mStart[c]; k < mStart[c + 1]; ++k) {
                    const std::size_t v = mMembers[k];
                    rhs += double(sigmaS[v][ch]) * double(change(v)[ch]);
                }
                rhs = rhs / double(mStart[c + 1] - mStart[c]) * h;
                if (cellFlux) {
                    // −∮ G·n over the cell's faces (in units of the cell, as the rows are), G =
                    // χ1σsΔF/σtr at a face the mean of its two cells', 0 at a vacuum face (taking
                    // the cell's own there, where the light streams out, the sweeps diverged on
                    // every cloud of docs/accuracy-notes.md (y)).
                    const double own = mMomentFactor[c][ch];
                    for (int f = 0; f < 6; ++f) {
                        const int j = mNeighbours[c * 6 + std::size_t(f)];
                        const double g = j < 0 ? 0.0
                                               : 0.5 *
                                (own * (*cellFlux)[c][f >> 1] + mMomentFactor[std::size_t(j)][ch] * (*cellFlux)[std::size_t(j)][f >> 1]);
                        rhs -= (f & 1) ? g : -g;
                    }
                }
                b[openvdb::math::pcg::SizeType(c)] = rhs;
                if (guess) x[openvdb::math::pcg::SizeType(c)] = mSolution[ch][c] * guessScale;
            }
        });
        mSolution[ch].assign(cells, 0.0);
        if (b.infNorm() == 0.0) continue;
        openvdb::math::pcg::State termination = openvdb::math::pcg::terminationDefaults<double>();
        termination.iterations = maxIterations;
        termination.relativeError = tolerance;
        openvdb::util::NullInterrupter never;
        const openvdb::math::pcg::State state =
            openvdb::math::pcg::solve(*channel.matrix, b, x, *channel.preconditioner, never, termination);
        result.iterations = std::max(result.iterations, state.iterations);
        result.residual = std::max(result.residual, state.relativeError);
        for (std::size_t c = 0; c < cells; ++c) {
            const double value = x[openvdb::math::pcg::SizeType(c)];
            mSolution[ch][c] = std::isfinite(value) ? value : 0.0;
        }
    }
    return result;
}

void DiffusionCorrection::addTo(std::vector<openvdb::Vec3f>& values, double weight) const
{
    // The fine leaves' cells: each voxel of the domain is a member of one (coarse ones: below).
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mFineCells), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t c = r.begin(); c != r.end(); ++c) {
            for (std::uint32_t k = mStart[c]; k < mStart[c + 1]; ++k) {
                const std::uint32_t v = mMembers[k];
                for (int ch = 0; ch < 3; ++ch) {
                    if (mSolution[ch].size() > c) values[v][ch] += float(weight * mSolution[ch][c]);
                }
            }
        }
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mCoarse.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            const CoarseCell& cell = mCoarse[i];
            for (int ch = 0; ch < 3; ++ch) {
                if (mSolution[ch].size() < std::size_t(cell.first) + cell.count) continue;
                double sum = 0.0;
                for (std::uint32_t c = cell.first; c < cell.first + cell.count; ++c) sum += mSolution[ch][c];
                values[cell.voxel][ch] += float(weight * sum / double(cell.count));
            }
        }
    });
}

} // namespace vxf::detail
