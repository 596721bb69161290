// vxf — the lattice's transport sweep (SweepLattice::sweep): one upwind pass over the leaves a
// direction, fine leaves and coarse cells, with the first moment a phase carries.
#include "SweepSteps.h"

#include <vxf/core/Error.h>
#include <vxf/core/Hash.h>

#include <openvdb/tree/LeafManager.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <type_traits>
#include <unordered_map>

namespace vxf::detail {

namespace {

/// @a f(q) for each padded index q a sweep of @a octant reads: the leaf's own voxels and its
/// upwind halo, 9³ of the block's 10³ (the downwind halo is the next leaves' to read).
template <typename F>
void forUpwindBlock(int octant, F&& f)
{
    const int lo[3] = {octant & 1 ? 0 : -1, octant & 2 ? 0 : -1, octant & 4 ? 0 : -1};
    for (int x = lo[0]; x < lo[0] + 9; ++x) {
        for (int y = lo[1]; y < lo[1] + 9; ++y) {
            const int row = SweepLattice::paddedIndex(x, y, lo[2]);
            for (int q = row; q < row + 9; ++q) f(q);
        }
    }
}

/// @a f(start, count) for runs of padded indices covering forUpwindBlock's: the 9 slabs of x
/// the sweep reads, each whole (100 indices, of which 81 are read), for loops the compiler
/// vectorizes.
template <typename F>
void forUpwindSlabs(int octant, F&& f)
{
    const int lo = octant & 1 ? 0 : -1;
    for (int x = lo; x < lo + 9; ++x) f(SweepLattice::paddedIndex(x, -1, -1), 100);
}

/// A leaf's source toward ω over its upwind block: @a toward = @a j·RestPhase(a, ω, β·ω), a by
/// component (@a ax, @a ay, @a az), the factors made in @a rest by slabs (restFactors).
void towardOmega(int octant, const RestPhase& restPhase, const openvdb::Vec3f& omega, const QuadratureCorrection* beta,
    const openvdb::Vec3f* j, const float* ax, const float* ay, const float* az, float* rest, openvdb::Vec3f* toward)
{
    forUpwindSlabs(octant,
        [&](int start, int count) { restFactors(restPhase, omega, beta, ax + start, ay + start, az + start, count, rest + start); });
    forUpwindBlock(octant, [&](int q) { toward[q] = j[q] * rest[q]; });
}

/// A leaf's upwind ghosts in its padded @a buffer: what its @a neighbours (27) handed on, a
/// fine one's downwind faces (@a faces, at its place @a facePlace), a coarse one's light through
/// the face the ghost lies across (@a leaving, null: no coarse leaves, the loop without their
/// test), 0 where none is.
void fillGhosts(const std::vector<Ghost>& upwind, const std::int32_t* neighbours, std::size_t fineLeaves, const openvdb::Vec3f* faces,
    const std::int32_t* facePlace, const openvdb::Vec3f* leaving, openvdb::Vec3f* buffer)
{
    constexpr std::size_t kFace = SweepLattice::kFaceVoxels;
    if (!leaving) {
        for (const Ghost& g : upwind) {
            const int leaf = neighbours[g.slot];
            buffer[g.padded] = leaf >= 0 ? faces[std::size_t(facePlace[leaf]) * kFace + std::size_t(g.face)] : openvdb::Vec3f(0.0f);
        }
        return;
    }
    for (const Ghost& g : upwind) {
        const int leaf = neighbours[g.slot];
        buffer[g.padded] = leaf < 0           ? openvdb::Vec3f(0.0f)
            : std::size_t(leaf) >= fineLeaves ? leaving[(std::size_t(leaf) - fineLeaves) * 3 + std::size_t(g.face / 64)]
                                              : faces[std::size_t(facePlace[leaf]) * kFace + std::size_t(g.face)];
    }
}

/// A uniform leaf's sweep (sweepLeaf's short path: every step whole, one σt) a row at a time,
/// with per channel @a transmittance, @a in and @a own (uniformWeights).
void sweepUniformLeaf(const openvdb::Vec3d& omega, const float (&transmittance)[3], const float (&in)[3], const float (&own)[3],
    const float* wt, const int* off, const openvdb::Vec3f* j, openvdb::Vec3f* buffer, float w, openvdb::Vec3f* phi,
    openvdb::Vec3f* fluxHere, const openvdb::Vec3f& worldOmega)
{
    const float* jf = j->asPointer();
    float* bf = buffer->asPointer();
    forRows(octantOf(omega), dominantAxis(omega), [&](int p, int v, auto axis) {
        constexpr int kPadded = decltype(axis)::kPadded, kLocal = decltype(axis)::kLocal;
        float psiIn[24], jIn[24];
        blendUpwindRow<3, kPadded>(bf, p, wt, off, psiIn);
        blendUpwindRow<3, kPadded>(jf, p, wt, off, jIn);
        for (int k = 0; k < 8; ++k) {
            openvdb::Vec3f result;
            const float* jHere = jf + 3 * (p + kPadded * k);
            for (int ch = 0; ch < 3; ++ch)
                result[ch] = transmittance[ch] * psiIn[3 * k + ch] + in[ch] * jIn[3 * k + ch] + own[ch] * jHere[ch];
            const int q = v + kLocal * k;
            buffer[p + kPadded * k] = result;
            phi[q] += w * result;
            if (fluxHere) fluxHere[q] += (w * (result[0] + result[1] + result[2]) * (1.0f / 3.0f)) * worldOmega;
        }
    });
}

} // namespace

void SweepLattice::sweep(const SweepSource& source, const std::vector<openvdb::Vec3d>& directions, double weight,
    std::vector<openvdb::Vec3f>& fluence, std::vector<openvdb::Vec3f>* skinFluence, Interrupter* interrupter,
    const FirstMoment* moment) const
{
    if (skinFluence) skinFluence->assign(mSkin.size(), openvdb::Vec3f(0.0f));
    const bool skins = skinFluence && !mSkin.empty();
    const bool padded = source.layout == SweepSource::Layout::Padded;
    if (source.values.size() != (padded ? mOrigins.size() * kPaddedVoxels : voxelCount()) || fluence.size() != voxelCount()) {
        throw Error("sweep: source or fluence does not match the lattice");
    }
    const float w = float(weight);
    if (moment &&
        (moment->worldDirections.size() != directions.size() || !moment->sourceAnisotropy ||
            moment->sourceAnisotropy->size() != voxelCount() ||
            (!moment->corrections.empty() && moment->corrections.size() != directions.size()) || !moment->flux ||
            moment->flux->size() != voxelCount())) {
        throw Error("sweep: the first moment's arrays do not match the lattice");
    }
    std::vector<openvdb::Vec3f>* flux = moment ? moment->flux : nullptr;

    // The directions in batches of one octant, at most kSweepBatch each (in the order given
    // within an octant): a batch's directions visit a leaf one after another while its source
    // and fluence are in cache, and each keeps of a leaf only its downwind faces, all that the
    // next leaves read.
    std::vector<std::vector<std::size_t>> batches;
    for (int o = 0; o < 8; ++o) {
        std::vector<std::size_t> inOctant;
        for (std::size_t d = 0; d < directions.size(); ++d) {
            if (octantOf(directions[d]) == o) inOctant.push_back(d);
        }
        for (std::size_t i = 0; i < inOctant.size(); i += kSweepBatch) {
            batches.emplace_back(
                inOctant.begin() + std::ptrdiff_t(i), inOctant.begin() + std::ptrdiff_t(std::min(inOctant.size(), i + kSweepBatch)));
        }
    }
    const std::size_t coarseLeaves = mOrigins.size() - mFineLeaves;
    std::size_t largest = 0;
    for (const std::vector<std::size_t>& batch : batches) largest = std::max(largest, batch.size());
    // What a leaf hands on: a fine leaf its downwind faces (the last four wavefronts',
    // mFacePlace), a coarse one each face's light.
    const std::size_t places = *std::max_element(mFacePlaces.begin(), mFacePlaces.end());
    std::vector<openvdb::Vec3f> faces(largest * places * kFaceVoxels), leaving(largest * coarseLeaves * 3);
    const std::vector<CubeChords> chords = coarseLeaves > 0 ? cubeChords(directions) : std::vector<CubeChords>{};
    struct Scratch
    {
        std::vector<openvdb::Vec3f> buffer, toward;
        /// Gathered once a leaf and batch (a moment's, or a source per voxel): the leaf's padded
        /// block's voxels (paddedVoxels), J and a over it (0 where no voxel is; a by component).
        std::vector<std::int64_t> index;
        std::vector<openvdb::Vec3f> block;
        std::vector<float> ax, ay, az;
        std::vector<float> rest; ///< RestPhase over the block, a direction's
        CoarseWeights coarse; ///< the last coarse cell's weights
    };
    tbb::enumerable_thread_specific<Scratch> scratches([] {
        const std::vector<openvdb::Vec3f> zeros(kPaddedVoxels, openvdb::Vec3f(0.0f));
        const std::vector<float> scalars(kPaddedVoxels, 0.0f);
        return Scratch{zeros, zeros, std::vector<std::int64_t>(kPaddedVoxels), zeros, scalars, scalars, scalars, scalars, CoarseWeights{}};
    });
    std::size_t swept = 0;
    for (const std::vector<std::size_t>& batch : batches) {
        const int octant = octantOf(directions[batch.front()]);
        const std::vector<Ghost> upwind = upwindGhosts(octant);
        const std::array<std::int16_t, kFaceVoxels> downwind = downwindFaces(octant);
        const std::int32_t* facePlace = mFacePlace[std::size_t(octant)].data();
        leavesInUpwindOrder(octant, [&](std::size_t n) {
            if (coarse(n)) {
                for (std::size_t slot = 0; slot < batch.size(); ++slot) {
                    sweepCoarseLeaf(n, directions, batch[slot], chords[batch[slot]], faces.data() + slot * places * kFaceVoxels, facePlace,
                        leaving.data() + slot * coarseLeaves * 3, source, w, fluence, moment, scratches.local().coarse);
                }
                return;
            }
            Scratch& scratch = scratches.local();
            openvdb::Vec3f* buffer = scratch.buffer.data();
            for (std::size_t slot = 0; slot < batch.size(); ++slot) {
                const std::size_t d = batch[slot];
                const openvdb::Vec3d& omega = directions[d];
                const openvdb::Vec3f* ownFaces = faces.data() + slot * places * kFaceVoxels;
                const openvdb::Vec3f* ownLeaving = leaving.data() + slot * coarseLeaves * 3;
                fillGhosts(upwind, &mNeighbours[n * 27], mFineLeaves, ownFaces, facePlace, coarseLeaves > 0 ? ownLeaving : nullptr, buffer);
                // The leaf's padded block of J: as it is (padded, no moment), or gathered once a
                // batch by the block's index, with a moment's a beside it; with a moment, J
                // toward ω: J·RestPhase(a, ω, β·ω), over the gathered blocks.
                const openvdb::Vec3f* j = padded ? &source.values[n * kPaddedVoxels] : nullptr;
                if (slot == 0 && (moment || !padded)) {
                    paddedVoxels(n, scratch.index.data());
                    const openvdb::Vec3f* a = moment ? moment->sourceAnisotropy->data() : nullptr;
                    forUpwindBlock(octant, [&](int q) {
                        const std::int64_t v = scratch.index[std::size_t(q)];
                        scratch.block[std::size_t(q)] = v < 0 ? openvdb::Vec3f(0.0f) : padded ? j[q] : source.values[std::size_t(v)];
                        if (!a) return;
                        const openvdb::Vec3f here = v < 0 ? openvdb::Vec3f(0.0f) : a[v];
                        scratch.ax[std::size_t(q)] = here[0];
                        scratch.ay[std::size_t(q)] = here[1];
                        scratch.az[std::size_t(q)] = here[2];
                    });
                }
                if (moment || !padded) j = scratch.block.data();
                openvdb::Vec3f worldOmega(0.0f);
                if (moment) {
                    worldOmega = openvdb::Vec3f(moment->worldDirections[d]);
                    const QuadratureCorrection* beta = moment->corrections.empty() ? nullptr : &moment->corrections[d];
                    towardOmega(octant, moment->rest, worldOmega, beta, j, scratch.ax.data(), scratch.ay.data(), scratch.az.data(),
                        scratch.rest.data(), scratch.toward.data());
                    j = scratch.toward.data();
                }
                openvdb::Vec3f* fluxHere = flux ? &(*flux)[n * kLeafVoxels] : nullptr;
                std::vector<openvdb::Vec3f>* skinHere = skins ? skinFluence : nullptr;
                if (mSigmaTGrey.empty()) {
                    sweepLeaf(n, &mSigmaT[mSigmaTStart[n]], omega, j, buffer, w, &fluence[n * kLeafVoxels], fluxHere, worldOmega, skinHere);
                } else {
                    sweepLeaf(
                        n, &mSigmaTGrey[mSigmaTStart[n]], omega, j, buffer, w, &fluence[n * kLeafVoxels], fluxHere, worldOmega, skinHere);
                }
                openvdb::Vec3f* leafFaces = &faces[(slot * places + std::size_t(facePlace[n])) * kFaceVoxels];
                for (int k = 0; k < kFaceVoxels; ++k) leafFaces[k] = buffer[downwind[std::size_t(k)]];
            }
        });
        swept += batch.size();
        if (interrupter && interrupter->wasInterrupted(int(100 * swept / directions.size()))) throw Interrupted();
    }
}

void SweepLattice::sweepCoarseLeaf(std::size_t n, const std::vector<openvdb::Vec3d>& directions, std::size_t d, const CubeChords& chords,
    const openvdb::Vec3f* faces, const std::int32_t* facePlace, openvdb::Vec3f* leaving, const SweepSource& source, float weight,
    std::vector<openvdb::Vec3f>& fluence, const FirstMoment* moment, CoarseWeights& cache) const
{
    // The light entering through each upwind face: what the neighbour there hands on through
    // it (a fine leaf's downwind face's mean).
    const int octant = octantOf(directions[d]);
    openvdb::Vec3f in[3];
    for (int a = 0; a < 3; ++a) {
        int step[3] = {0, 0, 0};
        step[a] = (octant >> a) & 1 ? 1 : -1;
        const int m = neighbour(n, step[0], step[1], step[2]);
        in[a] = openvdb::Vec3f(0.0f);
        if (m < 0) continue;
        if (coarse(std::size_t(m))) {
            in[a] = leaving[(std::size_t(m) - mFineLeaves) * 3 + std::size_t(a)];
            continue;
        }
        const openvdb::Vec3f* f = &faces[std::size_t(facePlace[m]) * kFaceVoxels + std::size_t(a) * 64];
        for (int k = 0; k < 64; ++k) in[a] += f[k];
        in[a] *= 1.0f / 64.0f;
    }
    const std::size_t i = voxelStart(n);
    openvdb::Vec3f j = source.values[i], worldOmega(0.0f);
    if (moment) {
        worldOmega = openvdb::Vec3f(moment->worldDirections[d]);
        const openvdb::Vec3f& a = (*moment->sourceAnisotropy)[i];
        j *=
            moment->corrections.empty() ? moment->rest(a, worldOmega) : moment->rest(a, worldOmega, moment->corrections[d].betaDotOmega(a));
    }
    openvdb::Vec3f* flux = moment ? &(*moment->flux)[i] : nullptr;
    sweepCoarseCell(n, chords, in, j, weight, fluence[i], flux, worldOmega, cache, &leaving[(n - mFineLeaves) * 3]);
}

std::vector<CubeChords> cubeChords(const std::vector<openvdb::Vec3d>& directions)
{
    std::vector<CubeChords> chords;
    for (const openvdb::Vec3d& omega : directions) chords.emplace_back(omega);
    return chords;
}

CubeChords::CubeChords(const openvdb::Vec3d& omega)
{
    // Exit points on a grid of kSide² on each downwind face, each back along −ω to where it
    // entered (the first upwind face the line meets), weighted by its face's share of the flow
    // |ω_a|/|ω|₁.
    const double flow = std::abs(omega[0]) + std::abs(omega[1]) + std::abs(omega[2]);
    const double step = 8.0 / kSide;
    for (int a = 0; a < 3; ++a) {
        share[a] = std::abs(omega[a]) / flow;
        if (omega[a] == 0.0) continue;
        for (int p = 0; p < kSide; ++p) {
            for (int q = 0; q < kSide; ++q) {
                double u[3]; // the exit point's distance from the cube's upwind side along each axis
                u[a] = 8.0;
                u[(a + 1) % 3] = (p + 0.5) * step;
                u[(a + 2) % 3] = (q + 0.5) * step;
                Chord chord{std::numeric_limits<double>::infinity(), share[a] / double(kSide * kSide), a, a};
                for (int b = 0; b < 3; ++b) {
                    if (omega[b] != 0.0 && u[b] / std::abs(omega[b]) < chord.length) {
                        chord.length = u[b] / std::abs(omega[b]);
                        chord.entry = b;
                    }
                }
                chords.push_back(chord);
                mean += chord.weight * chord.length;
            }
        }
    }
}

const CoarseWeights& coarseWeights(double sigma, double voxelSize, const CubeChords& cube, CoarseWeights& cache)
{
    if (cache.sigma == sigma && cache.cube == &cube) return cache;
    cache = CoarseWeights{};
    cache.sigma = sigma;
    cache.cube = &cube;
    const double mean = cube.mean * voxelSize;
    for (const CubeChords::Chord& chord : cube.chords) {
        const double c = chord.length * voxelSize, w = chord.weight;
        const StepWeights step = stepWeights(sigma * c);
        const double g = step.in + step.own; // (1 − T)/τ
        cache.out[chord.exit][chord.entry] += w / cube.share[chord.exit] * step.transmittance;
        cache.outJ[chord.exit] += w / cube.share[chord.exit] * c * g;
        cache.meanIn[chord.entry] += w * c * g / mean;
        cache.meanJ += w * c * c * step.own / mean;
    }
    return cache;
}

void SweepLattice::sweepCoarseCell(std::size_t n, const CubeChords& cube, const openvdb::Vec3f (&in)[3], const openvdb::Vec3f& j,
    float weight, openvdb::Vec3f& phi, openvdb::Vec3f* flux, const openvdb::Vec3f& worldOmega, CoarseWeights& cache,
    openvdb::Vec3f* out) const
{
    // Light entering evenly through each upwind face, J even over the cube: a chord of length c
    // from upwind face e to downwind face a carries T(c)·in_e + c·g(c)·J out through a
    // (stepWeights, g = in + own), and the cube's mean is its chords' path-weighted mean,
    // g(c)·in_e + c·own(c)·J: what enters equals what is absorbed plus what leaves. Each face's
    // own light, not one value for all three, and the chords themselves, not the step over
    // their mean (docs/accuracy-notes.md (ah)).
    const openvdb::Vec3f sigma = paddedSigmaT(n, 0);
    openvdb::Vec3f mean;
    for (int a = 0; a < 3; ++a) out[a] = openvdb::Vec3f(0.0f);
    for (int ch = 0; ch < 3; ++ch) {
        const CoarseWeights& w = coarseWeights(double(sigma[ch]), mVoxelSize, cube, cache);
        double m = w.meanJ * j[ch];
        for (int e = 0; e < 3; ++e) m += w.meanIn[e] * in[e][ch];
        mean[ch] = float(m);
        for (int a = 0; a < 3; ++a) {
            double o = w.outJ[a] * j[ch];
            for (int e = 0; e < 3; ++e) o += w.out[a][e] * in[e][ch];
            out[a][ch] = float(o);
        }
    }
    phi += weight * mean;
    if (flux) *flux += (weight * (mean[0] + mean[1] + mean[2]) * (1.0f / 3.0f)) * worldOmega;
}

template <typename Sigma>
void SweepLattice::sweepLeaf(std::size_t n, const Sigma* leafSigmaT, const openvdb::Vec3d& omega, const openvdb::Vec3f* j,
    openvdb::Vec3f* buffer, float w, openvdb::Vec3f* phi, openvdb::Vec3f* fluxHere, const openvdb::Vec3f& worldOmega,
    std::vector<openvdb::Vec3f>* skinFluence) const
{
    const Characteristic path = characteristic(omega);
    const float* wt = path.weight;
    const int* off = path.offset;
    const double len = mVoxelSize * path.length;
    const PaddedSigma<Sigma> st{leafSigmaT};
    constexpr bool kGrey = std::is_same_v<Sigma, float>; // the channels' steps share their weights
    const float* distance = distanceBlock(n); // (deep leaves do not read it)
    // Per channel, the last step's weights (uniformWeights); the last varying step's
    // (varyingWeights), shared by a grey medium's channels.
    UniformWeights uw[3];
    VaryingWeights vw;
    if (mUniform[n]) {
        // The short path of a deep leaf of one σt (about half the thick bunny's leaves at dim
        // 256): what the general path below computes there (every step whole, σt the same at
        // both ends, no skin), to the bit, without its tests, the step's weights once a leaf.
        const openvdb::Vec3f sigmaT = st[0]; // the leaf's one σt: its padded block is not streamed
        for (int ch = 0; ch < 3; ++ch) uniformWeights(sigmaT[ch], len, uw[ch]);
        const float transmittance[3] = {uw[0].transmittance, uw[1].transmittance, uw[2].transmittance},
                    in[3] = {uw[0].in, uw[1].in, uw[2].in}, own[3] = {uw[0].own, uw[1].own, uw[2].own};
        sweepUniformLeaf(omega, transmittance, in, own, wt, off, j, buffer, w, phi, fluxHere, worldOmega);
        return;
    }
    const bool deep = mDeep[n] != 0; // no surface within reach: every step whole, no skin
    const std::int32_t* skinIndex = skinFluence && !deep && !mSkinIndex.empty() ? &mSkinIndex[mShallowStart[n]] : nullptr;
    // A voxel's step from its upwind reads: ψ, J, σt and the signed distance blended at the
    // characteristic's crossing (dIn −1 in a deep leaf), and whether σt is the same upwind as here.
    const auto step = [&](int p, int v, const openvdb::Vec3f& psiIn, const openvdb::Vec3f& jIn, openvdb::Vec3f stIn, float dIn,
                          bool uniform) VXF_ALWAYS_INLINE {
        openvdb::Vec3f result;
        const float dHere = deep ? -1.0f : distance[p];
        if (dHere >= 0.0f && dIn >= 0.0f) {
            result = psiIn; // the step outside the surface: vacuum
        } else if (uniform && dHere < 0.0f && dIn < 0.0f) {
            // The common case inside: the whole step, σt the same at both ends (what the general
            // case below gives there, without its tests: J linear, no division).
            const openvdb::Vec3f& sigma = st[p];
            const openvdb::Vec3f& jHere = j[p];
            for (int ch = 0; ch < 3; ++ch) result[ch] = uniformStep(psiIn[ch], jIn[ch], jHere[ch], sigma[ch], len, uw[kGrey ? 0 : ch]);
        } else {
            if (uniform) stIn = st[p];
            // The step's part inside the surface (signed distance linear along it): all of it,
            // none, or the part next to the end inside, whose σt and J then hold over that part.
            const InsidePart part = deep ? InsidePart{} : insidePart(dIn, dHere);
            const double inside = part.fraction;
            openvdb::Vec3f sigmaStart = stIn, sigmaEnd = st[p], jStart = jIn, jEnd = j[p];
            if (part.endOutside) {
                sigmaEnd = stIn;
                jEnd = jIn;
            } else if (part.startOutside) {
                sigmaStart = st[p];
                jStart = j[p];
            }
            result = psiIn;
            if (inside > 0.0) {
                const double h = len * inside;
                for (int ch = 0; ch < 3; ++ch) {
                    const double sa = sigmaStart[ch], sb = sigmaEnd[ch];
                    // No extinction, or σt the same at both ends.
                    if ((sa <= 0.0 && sb <= 0.0) || sa == sb) {
                        result[ch] = uniformStep(psiIn[ch], jStart[ch], jEnd[ch], std::max(sa, sb), h, uw[kGrey ? 0 : ch]);
                        continue;
                    }
                    if (kGrey) {
                        // The channels share σt: the step's weights once, the rest per channel
                        // (each channel's own look-up in the kept weights cost the smoke 4%).
                        const VaryingWeights& weights = varyingWeights(sa, sb, h, vw);
                        for (int c = 0; c < 3; ++c) result[c] = float(varyingStep(psiIn[c], jStart[c], jEnd[c], weights));
                        break;
                    }
                    result[ch] = float(varyingStep(psiIn[ch], jStart[ch], jEnd[ch], varyingWeights(sa, sb, h, vw)));
                }
            }
        }
        buffer[p] = result;
        phi[v] += w * result;
        if (fluxHere) fluxHere[v] += (w * (result[0] + result[1] + result[2]) * (1.0f / 3.0f)) * worldOmega;
        const std::int32_t s = skinIndex ? skinIndex[v] : -1;
        if (s >= 0) {
            // On from the centre to the surface along ω, if ω leaves it.
            const Skin& sk = mSkin[std::size_t(s)];
            const double cosine = double(sk.normal.dot(openvdb::Vec3f(omega)));
            if (cosine > 0.0) {
                const double toSurface = double(sk.depth) / std::max(cosine, 0.05); // voxels along ω
                openvdb::Vec3f onSurface;
                for (int ch = 0; ch < 3; ++ch) {
                    const double sigma = st[p][ch], tau = sigma * toSurface;
                    onSurface[ch] = sigma > 0.0 ? float(result[ch] * std::exp(-tau) - double(j[p][ch]) / sigma * std::expm1(-tau))
                                                : float(result[ch] + double(j[p][ch]) * toSurface);
                }
                (*skinFluence)[std::size_t(s)] += w * onSurface;
            }
        }
    };
    constexpr int kSigma = kGrey ? 1 : 3; // floats of σt a voxel
    const float* bf = buffer->asPointer();
    const float* jf = j->asPointer();
    const float* sf = reinterpret_cast<const float*>(leafSigmaT);
    forRows(octantOf(omega), dominantAxis(omega), [&](int p, int v, auto axis) {
        constexpr int kPadded = decltype(axis)::kPadded, kLocal = decltype(axis)::kLocal;
        float psiIn[24], jIn[24], stIn[8 * kSigma], dIn[8];
        blendUpwindRow<3, kPadded>(bf, p, wt, off, psiIn);
        blendUpwindRow<3, kPadded>(jf, p, wt, off, jIn);
        blendUpwindRow<kSigma, kPadded>(sf, p, wt, off, stIn);
        if (deep) {
            std::fill(dIn, dIn + 8, -1.0f);
        } else {
            blendUpwindRow<1, kPadded>(distance, p, wt, off, dIn);
        }
        for (int k = 0; k < 8; ++k) {
            const int q = p + kPadded * k;
            bool uniform = true; // σt the same upwind as here: then exactly so, and the step's weights repeat
            for (int i = 0; i < 4; ++i) uniform = uniform && st[q + off[i]] == st[q];
            const openvdb::Vec3f sigmaIn = kGrey ? openvdb::Vec3f(stIn[k]) : openvdb::Vec3f(stIn + kSigma * k);
            step(q, v + kLocal * k, openvdb::Vec3f(psiIn + 3 * k), openvdb::Vec3f(jIn + 3 * k), sigmaIn, dIn[k], uniform);
        }
    });
}

} // namespace vxf::detail
