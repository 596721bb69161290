#include "DiffusionCorrection.h"

#include <vxf/core/Error.h>

#include <openvdb/util/NullInterrupter.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace vxf::detail {

DiffusionCorrection::DiffusionCorrection(const SweepLattice& lattice)
    : mLattice(lattice)
{
    constexpr int L = SweepLattice::kLeafVoxels;
    const double dx = lattice.voxelSize();
    const std::vector<openvdb::Vec3f>& sigmaT = lattice.sigmaT();
    const std::vector<openvdb::Vec3f>& sigmaS = lattice.sigmaS();
    const auto inDomain = [&](const openvdb::Vec3f& t) {
        return std::min({t[0], t[1], t[2]}) * dx >= kThinVoxel;
    };
    // Unknowns in lattice order, and each voxel's row (−1: not in the domain).
    std::vector<std::int32_t> row(lattice.voxelCount(), -1);
    for (std::size_t n = 0; n < lattice.leafCount(); ++n) {
        for (int v = 0; v < L; ++v) {
            if (!inDomain(sigmaT[n * L + v])) continue;
            row[n * L + v] = std::int32_t(mVoxels.size());
            mVoxels.push_back(std::uint32_t(n * L + v));
        }
    }
    if (mVoxels.empty()) return;


    for (int ch = 0; ch < 3; ++ch) {
        for (int other = 0; other < ch && mChannels[ch].same < 0; ++other) {
            if (mChannels[other].same >= 0) continue;
            bool equal = true;
            for (std::size_t i = 0; i < mVoxels.size() && equal; ++i) {
                const std::size_t v = mVoxels[i];
                equal = sigmaT[v][ch] == sigmaT[v][other] && sigmaS[v][ch] == sigmaS[v][other];
            }
            if (equal) mChannels[ch].same = other;
        }
        if (mChannels[ch].same >= 0) continue;
        // In units of the voxel: D̃ = D/dx = 1/(3σt·dx), σ̃a = σa·dx; row i:
        // (σ̃a + Σ_faces D̃_f + Σ_vacuum faces D̃/(½ + 2D̃)) δ_i − Σ_faces D̃_f δ_j = σs·Δφ·dx,
        // D̃_f = 2D̃_iD̃_j/(D̃_i + D̃_j). (Marshak: the face's flux D(δ_i − δ_b)/(dx/2) = δ_b/2.)
        auto matrix = std::make_unique<Matrix>(openvdb::math::pcg::SizeType(mVoxels.size()));
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mVoxels.size()), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const std::size_t v = mVoxels[i], n = v / L;
                const int x = int(v % L) >> 6, y = (int(v % L) >> 3) & 7, z = int(v % L) & 7;
                const double t = sigmaT[v][ch] * dx;
                const double d = 1.0 / (3.0 * t);
                double diagonal = std::max(0.0, t - sigmaS[v][ch] * dx);
                const int face[6][3] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
                for (const auto& f : face) {
                    const std::int64_t w = lattice.voxelIndex(n, x + f[0], y + f[1], z + f[2]);
                    const std::int32_t j = w < 0 ? -1 : row[std::size_t(w)];
                    if (j < 0) {
                        diagonal += d / (0.5 + 2.0 * d);
                    } else {
                        const double dj = 1.0 / (3.0 * sigmaT[std::size_t(w)][ch] * dx);
                        const double df = 2.0 * d * dj / (d + dj);
                        diagonal += df;
                        matrix->setValue(openvdb::math::pcg::SizeType(i), openvdb::math::pcg::SizeType(j), -df);
                    }
                }
                matrix->setValue(openvdb::math::pcg::SizeType(i), openvdb::math::pcg::SizeType(i), diagonal);
            }
        });
        mChannels[ch].preconditioner = std::make_unique<openvdb::math::pcg::JacobiPreconditioner<Matrix>>(*matrix);
        mChannels[ch].matrix = std::move(matrix);
    }
}

DiffusionCorrection::Solve DiffusionCorrection::solve(const std::vector<openvdb::Vec3f>& change, std::vector<openvdb::Vec3f>& delta,
    double tolerance, int maxIterations) const
{
    Solve result;
    const bool guess = delta.size() == mLattice.voxelCount();
    if (!guess) delta.assign(mLattice.voxelCount(), openvdb::Vec3f(0.0f));
    if (mVoxels.empty()) return result;
    const double dx = mLattice.voxelSize();
    const std::vector<openvdb::Vec3f>& sigmaS = mLattice.sigmaS();
    const auto size = openvdb::math::pcg::SizeType(mVoxels.size());
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
            for (std::size_t i = 0; i < mVoxels.size() && equal; ++i) {
                const std::size_t v = mVoxels[i];
                equal = change[v][ch] == change[v][other] && sigmaS[v][ch] == sigmaS[v][other];
            }
            if (equal) solvedAs = other;
        }
        if (solvedAs >= 0) {
            for (const std::uint32_t v : mVoxels) delta[v][ch] = delta[v][solvedAs];
            continue;
        }
        openvdb::math::pcg::Vector<double> b(size), x(size, 0.0);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mVoxels.size()), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const std::size_t v = mVoxels[i];
                b[openvdb::math::pcg::SizeType(i)] = double(sigmaS[v][ch]) * double(change[v][ch]) * dx;
                if (guess) x[openvdb::math::pcg::SizeType(i)] = double(delta[v][ch]);
            }
        });
        if (b.infNorm() == 0.0) continue;
        openvdb::math::pcg::State termination = openvdb::math::pcg::terminationDefaults<double>();
        termination.iterations = maxIterations;
        termination.relativeError = tolerance;
        openvdb::util::NullInterrupter never;
        const openvdb::math::pcg::State state = openvdb::math::pcg::solve(*channel.matrix, b, x, *channel.preconditioner, never, termination);
        result.iterations = std::max(result.iterations, state.iterations);
        result.residual = std::max(result.residual, state.relativeError);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mVoxels.size()), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const double value = x[openvdb::math::pcg::SizeType(i)];
                delta[mVoxels[i]][ch] = std::isfinite(value) ? float(value) : 0.0f;
            }
        });
    }
    return result;
}

} // namespace vxf::detail
