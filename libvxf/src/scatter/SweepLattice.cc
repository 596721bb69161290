#include "SweepLattice.h"

#include <vxf/core/Error.h>
#include <vxf/core/Hash.h>

#include <openvdb/tree/LeafManager.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

namespace vxf::detail {

namespace {

/// A padded cell a sweep reads from a neighbouring leaf: its index in the padded block, the
/// neighbour (0…26 as in SweepLattice::neighbour) and the voxel there.
struct Ghost
{
    int padded, slot, local;
};

/// The cells upwind of a leaf along octant @a octant: one layer on each upwind face, edge and
/// corner (9³ − 8³ = 217), in no particular order.
std::vector<Ghost> upwindGhosts(int octant)
{
    std::vector<Ghost> ghosts;
    int range[3][9];
    for (int a = 0; a < 3; ++a) {
        const int ghost = (octant >> a) & 1 ? 8 : -1;
        range[a][0] = ghost;
        for (int i = 0; i < 8; ++i) range[a][i + 1] = i;
    }
    for (int i : range[0]) {
        for (int j : range[1]) {
            for (int k : range[2]) {
                const int p[3] = {i, j, k};
                int d[3], l[3];
                bool inside = true;
                for (int a = 0; a < 3; ++a) {
                    d[a] = p[a] < 0 ? -1 : (p[a] > 7 ? 1 : 0);
                    l[a] = p[a] - 8 * d[a];
                    inside = inside && d[a] == 0;
                }
                if (inside) continue;
                ghosts.push_back({SweepLattice::paddedIndex(i, j, k), (d[0] + 1) * 9 + (d[1] + 1) * 3 + (d[2] + 1),
                    SweepLattice::localIndex(l[0], l[1], l[2])});
            }
        }
    }
    return ghosts;
}

/// Weights of the linear source along one step of optical depth @a tau: the radiance a step
/// adds is len·(in·J_upwind + own·J_here) for J linear between them, attenuated e^{−σt(len−s)};
/// in = ∫₀¹ v e^{−τv} dv, own = ∫₀¹ (1−v) e^{−τv} dv, and the step's transmittance e^{−τ}.
/// Finite for every τ ≥ 0 (τ → ∞: in → 0, own → 1/τ, the radiance J/σt).
struct StepWeights
{
    double in, own, transmittance;
};

inline StepWeights stepWeights(double tau)
{
    StepWeights w;
    w.transmittance = std::exp(-tau);
    if (tau < 0.25) {
        // Σ_n (−τ)ⁿ/n! · 1/(n+2) and Σ_n (−τ)ⁿ/n! · 1/((n+1)(n+2)): no cancellation near 0
        // (the terms after n = 6 add less than 2e-9).
        double term = 1.0;
        w.in = w.own = 0.0;
        for (int n = 0; n < 7; ++n) {
            w.in += term / (n + 2);
            w.own += term / ((n + 1) * (n + 2));
            term *= -tau / (n + 1);
        }
    } else {
        const double e = w.transmittance, inverse = 1.0 / (tau * tau);
        w.in = (1.0 - e - tau * e) * inverse;
        w.own = (tau - 1.0 + e) * inverse;
    }
    return w;
}

} // namespace

std::size_t SweepLattice::CoordHasher::operator()(const openvdb::Coord& c) const { return std::size_t(coordKey(c)); }

SweepLattice::SweepLattice(const Medium& medium, const openvdb::Vec3SGrid& topology)
    : mVoxelSize(medium.voxelSize())
{
    openvdb::MaskTree mask(medium.density().tree(), false, openvdb::TopologyCopy());
    mask.topologyUnion(topology.tree());
    mask.voxelizeActiveTiles();
    for (auto it = mask.cbeginLeaf(); it; ++it) mOrigins.push_back(it->origin());

    mLeafIndex.reserve(mOrigins.size());
    for (std::size_t n = 0; n < mOrigins.size(); ++n) mLeafIndex.emplace(mOrigins[n], std::int32_t(n));
    mNeighbours.assign(mOrigins.size() * 27, -1);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mOrigins.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t n = r.begin(); n != r.end(); ++n) {
            for (int s = 0; s < 27; ++s) {
                const openvdb::Coord o = mOrigins[n].offsetBy(8 * (s / 9 - 1), 8 * (s / 3 % 3 - 1), 8 * (s % 3 - 1));
                const auto found = mLeafIndex.find(o);
                if (found != mLeafIndex.end()) mNeighbours[n * 27 + s] = found->second;
            }
        }
    });

    // Upwind order per octant: by the leaf's position along the octant's diagonal. A leaf's
    // upwind neighbours (face, edge, corner) lie 1 to 3 wavefronts before it.
    for (int octant = 0; octant < 8; ++octant) {
        std::vector<long long> key(mOrigins.size());
        for (std::size_t n = 0; n < mOrigins.size(); ++n) {
            long long k = 0;
            for (int a = 0; a < 3; ++a) k += ((octant >> a) & 1 ? -1 : 1) * (long long)(mOrigins[n][a] >> 3);
            key[n] = k;
        }
        std::vector<std::int32_t>& order = mOrder[octant];
        order.resize(mOrigins.size());
        std::iota(order.begin(), order.end(), 0);
        std::stable_sort(order.begin(), order.end(), [&key](std::int32_t a, std::int32_t b) { return key[a] < key[b]; });
        for (std::size_t i = 0; i < order.size(); ++i) {
            if (i == 0 || key[order[i]] != key[order[i - 1]]) mWavefronts[octant].push_back(i);
        }
        mWavefronts[octant].push_back(order.size());
    }

    mSigmaTVoxel.resize(voxelCount());
    mSigmaS.resize(voxelCount());
    mInterior.assign(voxelCount(), 1.0f);
    std::vector<float> distance(voxelCount(), -1.0f);
    std::vector<openvdb::Vec3f> inside(voxelCount());
    const bool surface = medium.surface() != nullptr;
    std::vector<std::uint8_t> skin(surface ? voxelCount() : 0, 0);
    std::vector<openvdb::Vec3f> skinNormal(surface ? voxelCount() : 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mOrigins.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        Medium::Sampler sampler(medium);
        for (std::size_t n = r.begin(); n != r.end(); ++n) {
            for (int v = 0; v < kLeafVoxels; ++v) {
                const openvdb::Coord c = mOrigins[n].offsetBy(v >> 6, (v >> 3) & 7, v & 7);
                // A voxel's own coefficients (a trilinear read at its centre weighs it alone).
                openvdb::Vec3d t = sampler.sigmaT(c.asVec3d()), s = sampler.sigmaS(c);
                for (int ch = 0; ch < 3; ++ch) {
                    if (!std::isfinite(t[ch]) || t[ch] < 0.0) t[ch] = 0.0;
                    if (!std::isfinite(s[ch])) s[ch] = 0.0;
                }
                const std::size_t i = n * kLeafVoxels + v;
                mSigmaTVoxel[i] = openvdb::Vec3f(t);
                mSigmaS[i] = openvdb::Vec3f(s);
                if (surface) {
                    const double d = sampler.signedDistance(c.asVec3d());
                    distance[i] = float(d);
                    mInterior[i] = float(1.0 / std::max(std::clamp(0.5 - d, 0.0, 1.0), Medium::kMinFraction));
                    openvdb::Vec3d point, normal;
                    if (sampler.skinPoint(c, point, normal)) {
                        skin[i] = 1;
                        skinNormal[i] = openvdb::Vec3f(normal);
                    }
                }
                inside[i] = openvdb::Vec3f(t * double(mInterior[i]));
            }
        }
    });
    mSigmaT = padded(inside);
    mDistance = padded(distance);
    mSkinIndex.assign(surface ? voxelCount() : 0, -1);
    for (std::size_t i = 0; i < skin.size(); ++i) {
        if (!skin[i]) continue;
        mSkinIndex[i] = std::int32_t(mSkin.size());
        mSkin.push_back({std::uint32_t(i), skinNormal[i], float(std::max(-double(distance[i]), 0.0) * mVoxelSize)});
    }
}

std::vector<openvdb::Vec3f> SweepLattice::withSkin(const std::vector<openvdb::Vec3f>& fluence,
    const std::vector<openvdb::Vec3f>& skinFluence, const std::vector<openvdb::Vec3f>* shift) const
{
    std::vector<openvdb::Vec3f> out = fluence;
    for (std::size_t s = 0; s < mSkin.size() && s < skinFluence.size(); ++s) {
        const std::uint32_t v = mSkin[s].voxel;
        out[v] = skinFluence[s] + (shift ? (*shift)[v] : openvdb::Vec3f(0.0f));
    }
    return out;
}

std::vector<openvdb::Vec3f> SweepLattice::sweepSource(const std::vector<openvdb::Vec3f>& source) const
{
    std::vector<openvdb::Vec3f> inside(source.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, source.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) inside[i] = source[i] * mInterior[i];
    });
    return padded(inside);
}

std::vector<openvdb::Vec3f> SweepLattice::read(const openvdb::Vec3SGrid& grid) const
{
    std::vector<openvdb::Vec3f> values(voxelCount(), openvdb::Vec3f(0.0f));
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mOrigins.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        auto acc = grid.getConstAccessor();
        for (std::size_t n = r.begin(); n != r.end(); ++n) {
            for (int v = 0; v < kLeafVoxels; ++v) {
                openvdb::Vec3f value;
                if (acc.probeValue(mOrigins[n].offsetBy(v >> 6, (v >> 3) & 7, v & 7), value)) values[n * kLeafVoxels + v] = value;
            }
        }
    });
    return values;
}

template <typename T>
std::vector<T> SweepLattice::padded(const std::vector<T>& values) const
{
    std::vector<T> out(mOrigins.size() * kPaddedVoxels);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mOrigins.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t n = r.begin(); n != r.end(); ++n) {
            T* block = &out[n * kPaddedVoxels];
            for (int i = -1; i <= 8; ++i) {
                for (int j = -1; j <= 8; ++j) {
                    for (int k = -1; k <= 8; ++k) {
                        const int di = i < 0 ? -1 : (i > 7 ? 1 : 0), dj = j < 0 ? -1 : (j > 7 ? 1 : 0), dk = k < 0 ? -1 : (k > 7 ? 1 : 0);
                        const int leaf = neighbour(n, di, dj, dk);
                        block[paddedIndex(i, j, k)] = leaf < 0 ? T(0)
                                                               : values[std::size_t(leaf) * kLeafVoxels + localIndex(i - 8 * di, j - 8 * dj, k - 8 * dk)];
                    }
                }
            }
        }
    });
    return out;
}

template std::vector<float> SweepLattice::padded(const std::vector<float>&) const;
template std::vector<openvdb::Vec3f> SweepLattice::padded(const std::vector<openvdb::Vec3f>&) const;

openvdb::Vec3SGrid::Ptr SweepLattice::write(const std::vector<openvdb::Vec3f>& values, const openvdb::Vec3SGrid& topology) const
{
    const auto valueAt = [&](const openvdb::Coord& c) {
        const auto found = mLeafIndex.find(c & ~7);
        if (found == mLeafIndex.end()) return openvdb::Vec3f(0.0f);
        const openvdb::Vec3f v = values[std::size_t(found->second) * kLeafVoxels + localIndex(c[0] & 7, c[1] & 7, c[2] & 7)];
        return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]) ? v : openvdb::Vec3f(0.0f);
    };

    auto grid = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    grid->setTransform(topology.transformPtr()->copy());
    grid->tree().topologyUnion(topology.tree());
    openvdb::tree::LeafManager<openvdb::Vec3STree> leaves(grid->tree());
    leaves.foreach([&](openvdb::Vec3STree::LeafNodeType& leaf, std::size_t) {
        for (auto it = leaf.beginValueOn(); it; ++it) it.setValue(valueAt(it.getCoord()));
    });
    // Active tiles: the mean of their voxels.
    std::vector<std::pair<openvdb::CoordBBox, openvdb::Vec3f>> tiles;
    for (auto it = grid->tree().cbeginValueOn(); it; ++it) {
        if (!it.isTileValue()) continue;
        openvdb::CoordBBox box;
        it.getBoundingBox(box);
        tiles.emplace_back(box, openvdb::Vec3f(0.0f));
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tiles.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t t = r.begin(); t != r.end(); ++t) {
            openvdb::Vec3d sum(0.0);
            for (auto c = tiles[t].first.begin(); c; ++c) sum += openvdb::Vec3d(valueAt(*c));
            tiles[t].second = openvdb::Vec3f(sum / double(tiles[t].first.volume()));
        }
    });
    for (const auto& [box, value] : tiles) grid->tree().fill(box, value, true);
    return grid;
}

void SweepLattice::sweep(const std::vector<openvdb::Vec3f>& source, const std::vector<openvdb::Vec3d>& directions, double weight,
    std::vector<openvdb::Vec3f>& fluence, std::vector<openvdb::Vec3f>* skinFluence, Interrupter* interrupter) const
{
    if (skinFluence) skinFluence->assign(mSkin.size(), openvdb::Vec3f(0.0f));
    const bool skins = skinFluence && !mSkin.empty();
    if (source.size() != mOrigins.size() * kPaddedVoxels || fluence.size() != voxelCount()) {
        throw Error("sweep: source or fluence does not match the lattice");
    }
    std::array<std::vector<Ghost>, 8> ghosts;
    for (int octant = 0; octant < 8; ++octant) ghosts[octant] = upwindGhosts(octant);
    std::vector<openvdb::Vec3f> psi(voxelCount()); // ψ of the direction being swept
    const float w = float(weight);
    const int stride[3] = {100, 10, 1};

    for (std::size_t d = 0; d < directions.size(); ++d) {
        const openvdb::Vec3d& omega = directions[d];
        int octant = 0, sign[3];
        for (int a = 0; a < 3; ++a) {
            sign[a] = omega[a] < 0.0 ? -1 : 1;
            if (omega[a] < 0.0) octant |= 1 << a;
        }
        // Short characteristics: from a voxel's centre back along −ω to the plane of the
        // previous layer of centres across the dominant axis m, whose crossing lies between
        // the four upwind voxels there (bilinear weights, all in [0, 1]: positive, no new
        // extrema), len = dx/|ω_m| away.
        const int m = std::abs(omega[0]) >= std::abs(omega[1]) ? (std::abs(omega[0]) >= std::abs(omega[2]) ? 0 : 2)
                                                               : (std::abs(omega[1]) >= std::abs(omega[2]) ? 1 : 2);
        const int b = (m + 1) % 3, c = (m + 2) % 3;
        const double am = std::abs(omega[m]);
        const double ub = std::abs(omega[b]) / am, uc = std::abs(omega[c]) / am;
        const float wt[4] = {float((1 - ub) * (1 - uc)), float(ub * (1 - uc)), float((1 - ub) * uc), float(ub * uc)};
        const int o0 = -sign[m] * stride[m];
        const int off[4] = {o0, o0 - sign[b] * stride[b], o0 - sign[c] * stride[c], o0 - sign[b] * stride[b] - sign[c] * stride[c]};
        const double len = mVoxelSize / am;
        const std::vector<std::int32_t>& order = mOrder[octant];
        const std::vector<std::size_t>& fronts = mWavefronts[octant];
        const std::vector<Ghost>& upwind = ghosts[octant];

        const auto sweepLeaf = [&](std::size_t n, openvdb::Vec3f* buffer) {
            for (const Ghost& g : upwind) {
                const int leaf = mNeighbours[n * 27 + g.slot];
                buffer[g.padded] = leaf < 0 ? openvdb::Vec3f(0.0f) : psi[std::size_t(leaf) * kLeafVoxels + g.local];
            }
            const openvdb::Vec3f* st = &mSigmaT[n * kPaddedVoxels];
            const openvdb::Vec3f* j = &source[n * kPaddedVoxels];
            const float* distance = &mDistance[n * kPaddedVoxels];
            openvdb::Vec3f* out = &psi[n * kLeafVoxels];
            openvdb::Vec3f* phi = &fluence[n * kLeafVoxels];
            for (int qx = 0; qx < 8; ++qx) {
                const int x = sign[0] > 0 ? qx : 7 - qx;
                for (int qy = 0; qy < 8; ++qy) {
                    const int y = sign[1] > 0 ? qy : 7 - qy;
                    for (int qz = 0; qz < 8; ++qz) {
                        const int z = sign[2] > 0 ? qz : 7 - qz;
                        const int p = paddedIndex(x, y, z);
                        openvdb::Vec3f psiIn(0.0f), jIn(0.0f), stIn(0.0f);
                        float dIn = 0.0f;
                        for (int i = 0; i < 4; ++i) {
                            psiIn += wt[i] * buffer[p + off[i]];
                            jIn += wt[i] * j[p + off[i]];
                            stIn += wt[i] * st[p + off[i]];
                            dIn += wt[i] * distance[p + off[i]];
                        }
                        // The step's part inside the surface (signed distance linear along it):
                        // all of it, none, or the part next to the end inside, whose σt and J
                        // then hold over that part.
                        const float dHere = distance[p];
                        double inside = 1.0;
                        openvdb::Vec3f sigmaStart = stIn, sigmaEnd = st[p], jStart = jIn, jEnd = j[p];
                        if (dHere >= 0.0f && dIn >= 0.0f) {
                            inside = 0.0;
                        } else if (dHere >= 0.0f) {
                            inside = dIn / (dIn - dHere);
                            sigmaEnd = stIn;
                            jEnd = jIn;
                        } else if (dIn >= 0.0f) {
                            inside = dHere / (dHere - dIn);
                            sigmaStart = st[p];
                            jStart = j[p];
                        }
                        openvdb::Vec3f result = psiIn;
                        if (inside > 0.0) {
                            const double h = len * inside;
                            StepWeights sw{0.0, 0.0, 1.0};
                            double tauBefore = -1.0;
                            for (int ch = 0; ch < 3; ++ch) {
                                const double sa = sigmaStart[ch], sb = sigmaEnd[ch];
                                if (sa <= 0.0 && sb <= 0.0) { // no extinction: J integrates as it is
                                    result[ch] = float(psiIn[ch] + 0.5 * h * (double(jStart[ch]) + double(jEnd[ch])));
                                    continue;
                                }
                                if (sa == sb) { // the common case inside: S linear is J linear, no division
                                    const double tau = sa * h;
                                    if (tau != tauBefore) sw = stepWeights(tau);
                                    tauBefore = tau;
                                    result[ch] = float(sw.transmittance * psiIn[ch] + h * (sw.in * jStart[ch] + sw.own * jEnd[ch]));
                                    continue;
                                }
                                // dψ/dτ = −ψ + S with the source function S = J/σt linear in the
                                // optical depth τ = ½(σa + σb)·h: ψ = e^{−τ}ψ_in + τ(in·S_a + own·S_b),
                                // exact for those, and S_b where the step is optically thick (the
                                // local equilibrium J/σt, whatever σt does along the step). An end
                                // without medium (σt = 0) takes the other end's S.
                                double Sa = sa > 0.0 ? double(jStart[ch]) / sa : 0.0, Sb = sb > 0.0 ? double(jEnd[ch]) / sb : 0.0;
                                if (sa <= 0.0) Sa = Sb;
                                if (sb <= 0.0) Sb = Sa;
                                const double tau = 0.5 * (sa + sb) * h;
                                if (tau != tauBefore) sw = stepWeights(tau);
                                tauBefore = tau;
                                result[ch] = float(sw.transmittance * psiIn[ch] + tau * (sw.in * Sa + sw.own * Sb));
                            }
                        }
                        buffer[p] = result;
                        const int v = localIndex(x, y, z);
                        out[v] = result;
                        phi[v] += w * result;
                        const std::int32_t s = skins ? mSkinIndex[n * kLeafVoxels + v] : -1;
                        if (s >= 0) {
                            // On from the centre to the surface along ω, if ω leaves it.
                            const Skin& k = mSkin[std::size_t(s)];
                            const double cosine = double(k.normal.dot(openvdb::Vec3f(omega)));
                            if (cosine > 0.0) {
                                const double path = double(k.depth) / std::max(cosine, 0.05);
                                openvdb::Vec3f onSurface;
                                for (int ch = 0; ch < 3; ++ch) {
                                    const double sigma = st[p][ch], tau = sigma * path;
                                    onSurface[ch] = sigma > 0.0 ? float(result[ch] * std::exp(-tau) - double(j[p][ch]) / sigma * std::expm1(-tau))
                                                                : float(result[ch] + double(j[p][ch]) * path);
                                }
                                (*skinFluence)[std::size_t(s)] += w * onSurface;
                            }
                        }
                    }
                }
            }
        };
        for (std::size_t f = 0; f + 1 < fronts.size(); ++f) {
            tbb::parallel_for(tbb::blocked_range<std::size_t>(fronts[f], fronts[f + 1], 1), [&](const tbb::blocked_range<std::size_t>& r) {
                std::vector<openvdb::Vec3f> buffer(kPaddedVoxels);
                for (std::size_t i = r.begin(); i != r.end(); ++i) sweepLeaf(std::size_t(order[i]), buffer.data());
            });
        }
        if (interrupter && interrupter->wasInterrupted(int(100 * (d + 1) / directions.size()))) throw Interrupted();
    }
}

} // namespace vxf::detail
