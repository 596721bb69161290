// vxf — the sweep lattice built (SweepLattice.h): the medium's leaves indexed, coarse cells
// chosen, its coefficients read padded, grids read onto it and written from it.
#include "SweepSteps.h"

#include <vxf/core/Error.h>
#include <vxf/core/Hash.h>
#include <vxf/transport/AdaptiveBand.h>

#include <openvdb/tools/FindActiveValues.h>
#include <openvdb/tree/LeafManager.h>

#include <fmt/format.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <unordered_map>

namespace vxf::detail {

SweepLattice::SweepLattice(
    const Medium& medium, const openvdb::Vec3SGrid& topology, Coefficients coefficients, Tiles tiles, double maxCellDepth)
    : SweepLattice(medium, openvdb::MaskTree(topology.tree(), false, openvdb::TopologyCopy()), coefficients, tiles, maxCellDepth)
{
}

SweepLattice::SweepLattice(
    const Medium& medium, const openvdb::MaskTree& topology, Coefficients coefficients, Tiles tiles, double maxCellDepth)
    : mVoxelSize(medium.voxelSize())
{
    indexLeaves(medium, topology, tiles, maxCellDepth);
    readMedium(medium, coefficients == Coefficients::PerVoxel);
}

bool SweepLattice::thinEnoughForCell(Medium::Sampler& sampler, const openvdb::Coord& origin, double maxCellDepth)
{
    const openvdb::Vec3d sigma = sampler.sigmaT(origin.asVec3d() + openvdb::Vec3d(3.5));
    return std::max({sigma[0], sigma[1], sigma[2]}) * 8.0 * sampler.medium().voxelSize() <= maxCellDepth;
}

std::vector<openvdb::Coord> SweepLattice::coarseBlocks(const Medium& medium, const openvdb::MaskTree& topology, double maxCellDepth)
{
    std::vector<openvdb::CoordBBox> tiles;
    for (auto it = topology.cbeginValueOn(); it; ++it) {
        if (!it.isTileValue()) continue;
        openvdb::CoordBBox box;
        it.getBoundingBox(box);
        tiles.push_back(box);
    }
    const openvdb::FloatGrid* surface = medium.surface();
    std::optional<openvdb::tools::FindActiveValues<openvdb::FloatTree>> band;
    if (surface) band.emplace(surface->tree());
    tbb::enumerable_thread_specific<std::vector<openvdb::Coord>> found;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tiles.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
        std::vector<openvdb::Coord>& mine = found.local();
        auto distance = surface ? std::optional<openvdb::FloatGrid::ConstAccessor>(surface->getConstAccessor()) : std::nullopt;
        Medium::Sampler sampler(medium);
        for (std::size_t t = r.begin(); t != r.end(); ++t) {
            const openvdb::CoordBBox& box = tiles[t];
            for (int x = box.min().x(); x <= box.max().x(); x += 8) {
                for (int y = box.min().y(); y <= box.max().y(); y += 8) {
                    for (int z = box.min().z(); z <= box.max().z(); z += 8) {
                        const openvdb::Coord origin(x, y, z);
                        // Deep: no voxel of the surface's band within a voxel of the block, and
                        // the block inside it (the level set's inactive values hold its sign).
                        if (surface &&
                            (band->anyActiveValues(openvdb::CoordBBox(origin.offsetBy(-1), origin.offsetBy(8))) ||
                                distance->getValue(origin.offsetBy(4)) >= 0.0f)) {
                            continue;
                        }
                        if (!thinEnoughForCell(sampler, origin, maxCellDepth)) continue;
                        mine.push_back(origin);
                    }
                }
            }
        }
    });
    std::vector<openvdb::Coord> blocks;
    for (const std::vector<openvdb::Coord>& mine : found) blocks.insert(blocks.end(), mine.begin(), mine.end());
    // In the tree's order, whatever the thread count.
    std::sort(blocks.begin(), blocks.end(), [](const openvdb::Coord& a, const openvdb::Coord& b) { return a < b; });
    return blocks;
}

void SweepLattice::requireFine(const char* what) const
{
    if (mFineLeaves != mOrigins.size()) throw Error(fmt::format("sweep lattice: {} takes no coarse leaves", what));
}

void SweepLattice::indexLeaves(const Medium& medium, const openvdb::MaskTree& topology, Tiles tiles, double maxCellDepth)
{
    openvdb::MaskTree mask(medium.density().tree(), false, openvdb::TopologyCopy());
    mask.topologyUnion(topology);
    const std::vector<openvdb::Coord> coarseOrigins =
        tiles == Tiles::Coarse ? coarseBlocks(medium, topology, maxCellDepth) : std::vector<openvdb::Coord>{};
    for (const openvdb::Coord& origin : coarseOrigins) {
        mask.fill(openvdb::CoordBBox(origin, origin.offsetBy(7)), false, false); // swept as a cell, not as voxels
    }
    mask.voxelizeActiveTiles();
    const auto isCoarse = [&](const openvdb::Coord& origin) {
        return std::binary_search(coarseOrigins.begin(), coarseOrigins.end(), origin, [](const auto& a, const auto& b) { return a < b; });
    };
    for (auto it = mask.cbeginLeaf(); it; ++it) {
        if (coarseOrigins.empty() || !isCoarse(it->origin())) mOrigins.push_back(it->origin());
    }
    mFineLeaves = mOrigins.size();
    mOrigins.insert(mOrigins.end(), coarseOrigins.begin(), coarseOrigins.end());

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
        for (std::size_t n = 0; n < mOrigins.size(); ++n) key[n] = frontKey(n, octant);
        std::vector<std::int32_t>& order = mOrder[octant];
        order.resize(mOrigins.size());
        std::iota(order.begin(), order.end(), 0);
        std::stable_sort(order.begin(), order.end(), [&key](std::int32_t a, std::int32_t b) { return key[a] < key[b]; });
        for (std::size_t i = 0; i < order.size(); ++i) {
            if (i == 0 || key[order[i]] != key[order[i - 1]]) mWavefronts[octant].push_back(i);
        }
        mWavefronts[octant].push_back(order.size());
        // The fine leaves' places among the faces a sweep keeps (mFacePlace).
        const std::vector<std::size_t>& fronts = mWavefronts[octant];
        std::size_t widest = 0;
        for (std::size_t f = 0; f + 1 < fronts.size(); ++f) {
            std::size_t fine = 0;
            for (std::size_t i = fronts[f]; i < fronts[f + 1]; ++i) fine += coarse(std::size_t(order[i])) ? 0 : 1;
            widest = std::max(widest, fine);
        }
        mFacePlace[octant].assign(mFineLeaves, -1);
        for (std::size_t f = 0; f + 1 < fronts.size(); ++f) {
            const long long ring = ((key[order[fronts[f]]] % 4) + 4) % 4;
            std::size_t place = std::size_t(ring) * widest;
            for (std::size_t i = fronts[f]; i < fronts[f + 1]; ++i) {
                if (!coarse(std::size_t(order[i]))) mFacePlace[octant][std::size_t(order[i])] = std::int32_t(place++);
            }
        }
        mFacePlaces[octant] = 4 * widest;
    }
}

void SweepLattice::readMedium(const Medium& medium, bool perVoxel)
{
    // σt and σs per voxel: density × the material's where the medium is that (no σa/σs grids).
    const bool fromDensity = !medium.sigmaAGrid() && !medium.sigmaSGrid();
    if (perVoxel && fromDensity) {
        mDensityVoxel.resize(voxelCount());
        mMaterialSigmaT = medium.material().sigmaT();
        mMaterialSigmaS = medium.material().sigmaS;
    } else if (perVoxel) {
        mSigmaTVoxel.resize(voxelCount());
        mSigmaS.resize(voxelCount());
    }
    const openvdb::FloatGrid::ConstAccessor densityAccessor = medium.density().getConstAccessor();
    const bool surface = medium.surface() != nullptr;
    // Per voxel while the leaves are read: the signed distance (every voxel's, a coarse cell's
    // too) and 1/f (a fine leaf's voxels; a coarse cell is deep, f = 1).
    ScratchArray<float> distance(surface ? voxelCount() : 0), interior(surface ? voxelCount() : 0);
    // σt inside the surface, per voxel: one float where it is grey by construction (the
    // density's times a grey material's), three until known otherwise (the construction's peak:
    // 37 bytes a voxel had held the bunny at dim 1024 to 9.2 GB).
    const openvdb::Vec3d materialSigmaT = medium.material().sigmaT();
    InsideSigma inside(voxelCount(), fromDensity && materialSigmaT[0] == materialSigmaT[1] && materialSigmaT[0] == materialSigmaT[2]);
    // The skin's voxels (centres within half a voxel of the surface) with their normals, per leaf.
    std::vector<std::vector<std::pair<std::uint16_t, openvdb::Vec3f>>> skin(surface ? mOrigins.size() : 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mOrigins.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        Medium::Sampler sampler(medium);
        openvdb::FloatGrid::ConstAccessor density = densityAccessor;
        for (std::size_t n = r.begin(); n != r.end(); ++n) {
            if (coarse(n)) {
                readCoarseCell(n, sampler, density, perVoxel, fromDensity, inside, distance);
                continue;
            }
            for (int v = 0; v < kLeafVoxels; ++v) {
                const openvdb::Coord c = mOrigins[n].offsetBy(v >> 6, (v >> 3) & 7, v & 7);
                // A voxel's own coefficients (a trilinear read at its centre weighs it alone).
                const openvdb::Vec3d t = finiteCoefficient(sampler.sigmaT(c.asVec3d()), true);
                const std::size_t i = n * kLeafVoxels + v;
                if (perVoxel && fromDensity) {
                    mDensityVoxel[i] = density.getValue(c); // (the sampler reads it so: sigmaT(), sigmaS())
                } else if (perVoxel) {
                    mSigmaTVoxel[i] = openvdb::Vec3f(t);
                    mSigmaS[i] = openvdb::Vec3f(finiteCoefficient(sampler.sigmaS(c), false));
                }
                double inverseFraction = 1.0;
                if (surface) {
                    const double d = sampler.signedDistance(c.asVec3d());
                    distance[i] = float(d);
                    interior[i] = float(1.0 / std::max(std::clamp(0.5 - d, 0.0, 1.0), Medium::kMinFraction));
                    inverseFraction = double(interior[i]);
                    openvdb::Vec3d point, normal;
                    // (skinPoint reads d again: only where it can find the skin.)
                    if (std::abs(d) < 0.5 && sampler.skinPoint(c, point, normal))
                        skin[n].emplace_back(std::uint16_t(v), openvdb::Vec3f(normal));
                }
                inside.set(i, openvdb::Vec3f(t * inverseFraction));
            }
        }
    });
    // The coarse cells' σt, held one value a cell after the fine leaves' blocks.
    std::vector<openvdb::Vec3f> coarseSigmaT(voxelCount() - mFineLeaves * kLeafVoxels);
    for (std::size_t c = 0; c < coarseSigmaT.size(); ++c) coarseSigmaT[c] = inside.at(mFineLeaves * kLeafVoxels + c);
    // Grey σt (every voxel's the same in each channel) held as one float: a third of the
    // lattice's largest array (issue 62: 16 bytes a voxel).
    inside.makeGreyIfItIs();
    // A narrow-band level set's interior value, as signedDistance reads it at a voxel centre.
    const float interiorDistance = surface ? float(double(-medium.surface()->background()) / medium.voxelSize()) : 0.0f;
    holdPadded(inside, distance, interior, coarseSigmaT, interiorDistance);
    inside = InsideSigma(0, false);
    mSkinIndex.assign(mInterior.size(), -1);
    for (std::size_t n = 0; n < skin.size(); ++n) {
        for (const auto& [v, normal] : skin[n]) {
            const std::size_t i = n * kLeafVoxels + v;
            // A skin voxel's centre lies within half a voxel of the surface: never in a deep leaf.
            const std::size_t at = shallowIndex(i);
            if (at == kNone) throw Error("sweep lattice: a skin voxel in a deep leaf");
            mSkinIndex[at] = std::int32_t(mSkin.size());
            mSkin.push_back({std::uint32_t(i), normal, float(std::max(-double(distance[i]), 0.0) * mVoxelSize)});
        }
    }
}

void SweepLattice::InsideSigma::makeGreyIfItIs()
{
    if (rgb.empty()) return;
    const tbb::blocked_range<std::size_t> all(0, rgb.size());
    const bool isGrey = tbb::parallel_reduce(
        all, true,
        [&](const tbb::blocked_range<std::size_t>& r, bool same) {
            for (std::size_t i = r.begin(); same && i != r.end(); ++i) same = rgb[i][0] == rgb[i][1] && rgb[i][0] == rgb[i][2];
            return same;
        },
        [](bool a, bool b) { return a && b; });
    if (!isGrey) return;
    grey = ScratchArray<float>(rgb.size());
    tbb::parallel_for(all, [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) grey[i] = rgb[i][0];
    });
    rgb = ScratchArray<openvdb::Vec3f>();
}

void SweepLattice::readCoarseCell(std::size_t n, Medium::Sampler& sampler, openvdb::FloatGrid::ConstAccessor& density, bool perVoxel,
    bool fromDensity, InsideSigma& inside, ScratchArray<float>& distance)
{
    // The means over the block's voxels: one read where the density holds the block as a tile.
    const openvdb::Coord& origin = mOrigins[n];
    const int samples = density.probeConstLeaf(origin) ? kLeafVoxels : 1;
    openvdb::Vec3d t(0.0), s(0.0);
    double densitySum = 0.0;
    for (int v = 0; v < samples; ++v) {
        const openvdb::Coord c = origin.offsetBy(v >> 6, (v >> 3) & 7, v & 7);
        t += finiteCoefficient(sampler.sigmaT(c.asVec3d()), true);
        s += finiteCoefficient(sampler.sigmaS(c), false);
        densitySum += double(density.getValue(c));
    }
    const std::size_t i = voxelStart(n);
    inside.set(i, openvdb::Vec3f(t / double(samples))); // (deep: wholly inside, f = 1)
    if (perVoxel && fromDensity) {
        mDensityVoxel[i] = float(densitySum / double(samples));
    } else if (perVoxel) {
        mSigmaTVoxel[i] = inside.at(i);
        mSigmaS[i] = openvdb::Vec3f(s / double(samples));
    }
    if (!distance.empty()) distance[i] = std::min(-1.0f, float(sampler.signedDistance(origin.offsetBy(4).asVec3d())));
}

namespace {

/// The mean of a grid's values over the 8³ block at @a origin, 0 where it is not active (a
/// coarse cell's value read from a grid).
openvdb::Vec3f blockMean(const openvdb::Vec3SGrid::ConstAccessor& acc, const openvdb::Coord& origin)
{
    openvdb::Vec3f value;
    if (const openvdb::Vec3STree::LeafNodeType* leaf = acc.probeConstLeaf(origin)) return leafMean(*leaf);
    return acc.probeValue(origin, value) ? value : openvdb::Vec3f(0.0f);
}

/// @a values (per voxel) at the padded voxels @a index (SweepLattice::paddedVoxels) into
/// @a block; 0 where no leaf is.
template <typename T>
void gatherPadded(const std::int64_t* index, const T* values, T* block)
{
    for (int q = 0; q < SweepLattice::kPaddedVoxels; ++q) block[q] = index[q] < 0 ? T(0) : values[std::size_t(index[q])];
}

/// Whether all of a padded block's values are equal.
template <typename T>
bool allEqual(const T* block)
{
    return std::all_of(block, block + SweepLattice::kPaddedVoxels, [&](const T& v) { return v == block[0]; });
}

/// Where each counted block starts when they lie one after another: @a count(n) values for
/// leaf n, @a none where it has none; the total in @a total.
template <typename Count>
std::vector<std::size_t> blockStarts(std::size_t leaves, Count&& count, std::size_t none, std::size_t& total)
{
    std::vector<std::size_t> start(leaves, none);
    total = 0;
    for (std::size_t n = 0; n < leaves; ++n) {
        const std::size_t values = count(n);
        if (values == 0) continue;
        start[n] = total;
        total += values;
    }
    return start;
}

} // namespace

void SweepLattice::holdPadded(const InsideSigma& inside, const ScratchArray<float>& distance, const ScratchArray<float>& interior,
    const std::vector<openvdb::Vec3f>& coarseSigmaT, float interiorDistance)
{
    const std::size_t leaves = mOrigins.size();
    const bool surface = !distance.empty(), grey = !inside.grey.empty();
    // @a visit(n, index, sigmaT) for each fine leaf n in parallel: its padded voxels' indices and
    // its padded σt (floats where grey, else colours).
    const auto eachFineLeaf = [&](const auto& visit) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mFineLeaves), [&](const tbb::blocked_range<std::size_t>& r) {
            std::int64_t index[kPaddedVoxels];
            std::vector<float> greyBlock(grey ? kPaddedVoxels : 0);
            std::vector<openvdb::Vec3f> rgbBlock(grey ? 0 : kPaddedVoxels);
            for (std::size_t n = r.begin(); n != r.end(); ++n) {
                paddedVoxels(n, index);
                if (grey) {
                    gatherPadded(index, inside.grey.data(), greyBlock.data());
                } else {
                    gatherPadded(index, inside.rgb.data(), rgbBlock.data());
                }
                visit(n, index, greyBlock.data(), rgbBlock.data());
            }
        });
    };
    // Each fine leaf classified on its padded blocks: deep (wholly more than half a voxel
    // inside, or no surface), uniform (deep, one σt: every step of a sweep there alike), and
    // whether its distance is held. A coarse leaf is deep and of one σt.
    mDeep.assign(leaves, 1);
    mUniform.assign(leaves, 1);
    std::vector<std::uint8_t> holdsDistance(mFineLeaves, 0);
    eachFineLeaf([&](std::size_t n, const std::int64_t* index, const float* greyBlock, const openvdb::Vec3f* rgbBlock) {
        if (surface) {
            float d[kPaddedVoxels];
            gatherPadded(index, distance.data(), d);
            mDeep[n] = std::all_of(d, d + kPaddedVoxels, [](float v) { return v < -0.5f; }) ? 1 : 0;
            const bool interiorOnly =
                std::all_of(d, d + kPaddedVoxels, [&](float v) { return v <= -kDistanceHeld || v == interiorDistance; });
            holdsDistance[n] = interiorOnly ? 0 : 1;
        }
        mUniform[n] = mDeep[n] && (grey ? allEqual(greyBlock) : allEqual(rgbBlock)) ? 1 : 0;
    });
    // Where each leaf's blocks start; then only those blocks made, a leaf at a time.
    std::size_t sigmaTCount = 0, distanceCount = 0, shallowCount = 0;
    mSigmaTStart = blockStarts(
        mFineLeaves, [&](std::size_t n) { return mUniform[n] ? std::size_t(1) : std::size_t(kPaddedVoxels); }, kNone, sigmaTCount);
    // A coarse leaf's one σt after the fine leaves' blocks.
    if (grey) {
        mSigmaTGrey.resize(sigmaTCount + coarseSigmaT.size());
    } else {
        mSigmaT.resize(sigmaTCount + coarseSigmaT.size());
    }
    for (std::size_t c = 0; c < coarseSigmaT.size(); ++c) {
        mSigmaTStart.push_back(sigmaTCount + c);
        if (grey) {
            mSigmaTGrey[sigmaTCount + c] = coarseSigmaT[c][0];
        } else {
            mSigmaT[sigmaTCount + c] = coarseSigmaT[c];
        }
    }
    if (surface) {
        mDistanceStart = blockStarts(
            mFineLeaves, [&](std::size_t n) { return holdsDistance[n] ? std::size_t(kPaddedVoxels) : 0; }, kNone, distanceCount);
        mShallowStart = blockStarts(
            leaves, [&](std::size_t n) { return mDeep[n] ? 0 : std::size_t(kLeafVoxels); }, kNone, shallowCount);
        mDistance.resize(distanceCount);
        mInterior.resize(shallowCount);
    }
    eachFineLeaf([&](std::size_t n, const std::int64_t* index, const float* greyBlock, const openvdb::Vec3f* rgbBlock) {
        // A uniform leaf's one σt: its block's first value (all are alike).
        const std::ptrdiff_t sigmaTValues = mUniform[n] ? 1 : kPaddedVoxels, at = std::ptrdiff_t(mSigmaTStart[n]);
        if (grey) {
            std::copy(greyBlock, greyBlock + sigmaTValues, mSigmaTGrey.begin() + at);
        } else {
            std::copy(rgbBlock, rgbBlock + sigmaTValues, mSigmaT.begin() + at);
        }
        if (!surface) return;
        if (holdsDistance[n]) gatherPadded(index, distance.data(), &mDistance[mDistanceStart[n]]);
        if (!mDeep[n]) {
            const float* own = interior.data() + n * kLeafVoxels;
            std::copy(own, own + kLeafVoxels, mInterior.begin() + std::ptrdiff_t(mShallowStart[n]));
        }
    });
}

SweepLattice::Coefficient SweepLattice::coefficient(
    const std::vector<openvdb::Vec3f>& held, const openvdb::Vec3d& perDensity, bool nonNegative) const
{
    Coefficient c;
    if (mDensityVoxel.empty()) {
        c.mValues = &held;
    } else {
        c.mDensity = &mDensityVoxel;
        c.mPerDensity = perDensity;
        c.mNonNegative = nonNegative;
    }
    return c;
}

SweepLattice::Coefficient SweepLattice::sigmaT() const { return coefficient(mSigmaTVoxel, mMaterialSigmaT, true); }

SweepLattice::Coefficient SweepLattice::sigmaS() const { return coefficient(mSigmaS, mMaterialSigmaS, false); }

std::size_t SweepLattice::bytes() const
{
    const auto of = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
    std::size_t sum = of(mOrigins) + of(mNeighbours) + of(mSigmaT) + of(mSigmaTGrey) + of(mDistance) + of(mDistanceStart) + of(mDeep) +
        of(mUniform) + of(mSigmaTStart) + of(mShallowStart) + of(mInterior) + of(mSigmaTVoxel) + of(mSigmaS) + of(mDensityVoxel) +
        of(mSkin) + of(mSkinIndex);
    for (int o = 0; o < 8; ++o) sum += of(mOrder[o]) + of(mWavefronts[o]) + of(mFacePlace[o]);
    return sum + mLeafIndex.size() * (sizeof(openvdb::Coord) + sizeof(std::int32_t) + 2 * sizeof(void*)) +
        mLeafIndex.bucket_count() * sizeof(void*);
}

void SweepLattice::putSkin(
    std::vector<openvdb::Vec3f>& fluence, const std::vector<openvdb::Vec3f>& skinFluence, const std::vector<openvdb::Vec3f>* shift) const
{
    for (std::size_t s = 0; s < mSkin.size() && s < skinFluence.size(); ++s) {
        const std::uint32_t v = mSkin[s].voxel;
        fluence[v] = skinFluence[s] + (shift ? (*shift)[v] : openvdb::Vec3f(0.0f));
    }
}

void SweepLattice::skinAtCentres(
    std::vector<openvdb::Vec3f>& values, const std::function<openvdb::Vec3f(const openvdb::Coord&)>& centre) const
{
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mSkin.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t s = r.begin(); s != r.end(); ++s) {
            const std::uint32_t v = mSkin[s].voxel;
            const int local = int(v % kLeafVoxels);
            const openvdb::Coord c = mOrigins[v / kLeafVoxels].offsetBy(local >> 6, (local >> 3) & 7, local & 7);
            values[v] = centre(c) / interiorOf(v);
        }
    });
}

SweepLattice::SweepSource SweepLattice::sweepSource(std::vector<openvdb::Vec3f> source) const
{
    return sweepSource([&source](std::size_t v) { return source[v]; });
}

SweepLattice::SweepSource SweepLattice::sweepSource(
    const std::function<openvdb::Vec3f(std::size_t)>& sourceAt, SweepSource::Layout layout) const
{
    return sweepSource(sourceAt, layout, SweepSource());
}

SweepLattice::SweepSource SweepLattice::sweepSource(
    const std::function<openvdb::Vec3f(std::size_t)>& sourceAt, SweepSource::Layout layout, SweepSource reuse) const
{
    const auto inside = [&](std::size_t v) { return mInterior.empty() ? sourceAt(v) : sourceAt(v) * interiorOf(v); };
    SweepSource out = std::move(reuse);
    out.layout = mFineLeaves == mOrigins.size() ? layout : SweepSource::Layout::PerVoxel; // (a coarse leaf has no padded block)
    // Every value is written below, whatever the memory held.
    const std::size_t size = out.layout == SweepSource::Layout::PerVoxel ? voxelCount() : mOrigins.size() * kPaddedVoxels;
    if (out.values.size() != size) out.values = ScratchArray<openvdb::Vec3f>(size);
    if (out.layout == SweepSource::Layout::PerVoxel) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, voxelCount()), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t v = r.begin(); v != r.end(); ++v) out.values[v] = inside(v);
        });
        return out;
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mOrigins.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        std::int64_t index[kPaddedVoxels];
        for (std::size_t n = r.begin(); n != r.end(); ++n) {
            openvdb::Vec3f* block = &out.values[n * kPaddedVoxels];
            paddedVoxels(n, index);
            for (int q = 0; q < kPaddedVoxels; ++q) block[q] = index[q] < 0 ? openvdb::Vec3f(0.0f) : inside(std::size_t(index[q]));
        }
    });
    return out;
}

std::vector<openvdb::Vec3f> SweepLattice::read(const openvdb::Vec3SGrid& grid) const
{
    std::vector<openvdb::Vec3f> values(voxelCount(), openvdb::Vec3f(0.0f));
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mOrigins.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        auto acc = grid.getConstAccessor();
        for (std::size_t n = r.begin(); n != r.end(); ++n) {
            if (coarse(n)) {
                values[voxelStart(n)] = blockMean(acc, mOrigins[n]);
                continue;
            }
            for (int v = 0; v < kLeafVoxels; ++v) {
                openvdb::Vec3f value;
                if (acc.probeValue(mOrigins[n].offsetBy(v >> 6, (v >> 3) & 7, v & 7), value)) values[n * kLeafVoxels + v] = value;
            }
        }
    });
    return values;
}

void SweepLattice::paddedVoxels(std::size_t n, std::int64_t* index) const
{
    for (int i = -1; i <= 8; ++i) {
        for (int j = -1; j <= 8; ++j) {
            for (int k = -1; k <= 8; ++k) index[paddedIndex(i, j, k)] = voxelIndex(n, i, j, k);
        }
    }
}

SweepLattice::GridView::GridView(const SweepLattice& lattice, const openvdb::Vec3SGrid& grid)
    : mLeaves(lattice.fineLeafCount(), nullptr)
    , mTiles(lattice.leafCount(), openvdb::Vec3f(0.0f))
    , mFineLeaves(lattice.fineLeafCount())
    , mFineVoxels(lattice.fineLeafCount() * kLeafVoxels)
{
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lattice.leafCount()), [&](const tbb::blocked_range<std::size_t>& r) {
        auto acc = grid.getConstAccessor();
        for (std::size_t n = r.begin(); n != r.end(); ++n) {
            const openvdb::Coord& origin = lattice.origin(n);
            if (lattice.coarse(n)) {
                mTiles[n] = blockMean(acc, origin);
                continue;
            }
            mLeaves[n] = acc.probeConstLeaf(origin);
            openvdb::Vec3f value;
            if (!mLeaves[n] && acc.probeValue(origin, value)) mTiles[n] = value; // an active tile holds the whole leaf
        }
    });
}

openvdb::Vec3SGrid::Ptr SweepLattice::write(const std::vector<openvdb::Vec3f>& values, const openvdb::Vec3SGrid& topology) const
{
    const auto valueAt = [&](const openvdb::Coord& c) {
        const std::int64_t i = indexOf(c);
        if (i < 0) return openvdb::Vec3f(0.0f);
        const openvdb::Vec3f v = values[std::size_t(i)];
        return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]) ? v : openvdb::Vec3f(0.0f);
    };

    auto grid = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    grid->setTransform(topology.transformPtr()->copy());
    grid->tree().topologyUnion(topology.tree());
    openvdb::tree::LeafManager<openvdb::Vec3STree> leaves(grid->tree());
    leaves.foreach ([&](openvdb::Vec3STree::LeafNodeType& leaf, std::size_t) {
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
            // 8³ blocks at a time (a tile's are whole): a coarse cell's value holds for its block.
            const openvdb::CoordBBox& box = tiles[t].first;
            openvdb::Vec3d sum(0.0);
            for (int x = box.min().x(); x <= box.max().x(); x += 8) {
                for (int y = box.min().y(); y <= box.max().y(); y += 8) {
                    for (int z = box.min().z(); z <= box.max().z(); z += 8) {
                        const openvdb::Coord origin(x, y, z);
                        const std::int64_t i = indexOf(origin);
                        if (i >= 0 && coarse(leafOf(std::size_t(i)))) {
                            sum += openvdb::Vec3d(valueAt(origin)) * double(kLeafVoxels);
                            continue;
                        }
                        for (auto c = openvdb::CoordBBox(origin, origin.offsetBy(7)).begin(); c; ++c) sum += openvdb::Vec3d(valueAt(*c));
                    }
                }
            }
            tiles[t].second = openvdb::Vec3f(sum / double(box.volume()));
        }
    });
    for (const auto& [box, value] : tiles) grid->tree().fill(box, value, true);
    return grid;
}

const std::array<SweepLattice::UpwindVoxel, SweepLattice::kLeafVoxels>& SweepLattice::upwindVoxels(int octant, int major)
{
    static const std::array<std::array<UpwindVoxel, kLeafVoxels>, 24> orders = [] {
        std::array<std::array<UpwindVoxel, kLeafVoxels>, 24> all;
        for (int o = 0; o < 8; ++o) {
            for (int m = 0; m < 3; ++m) {
                const int b = (m + 1) % 3, c = (m + 2) % 3;
                int k = 0;
                for (int qm = 0; qm < 8; ++qm) {
                    for (int qb = 0; qb < 8; ++qb) {
                        for (int qc = 0; qc < 8; ++qc) {
                            int q[3];
                            q[m] = qm;
                            q[b] = qb;
                            q[c] = qc;
                            int x[3];
                            for (int a = 0; a < 3; ++a) x[a] = (o >> a) & 1 ? 7 - q[a] : q[a];
                            all[std::size_t(3 * o + m)][std::size_t(k++)] = {
                                std::int16_t(paddedIndex(x[0], x[1], x[2])), std::int16_t(localIndex(x[0], x[1], x[2]))};
                        }
                    }
                }
            }
        }
        return all;
    }();
    return orders[std::size_t(3 * (octant & 7) + major % 3)];
}

} // namespace vxf::detail
