// vxf — the sweeps' step arithmetic and upwind order (private to transport/): shared by the
// lattice's transport sweep (SweepTransport.cc) and its optical-depth sweeps (OpticalDepth.cc).
#pragma once

#include "SweepLattice.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <vector>

/// On what the sweeps call per voxel (the step lambda called from more than one loop, the
/// weights and blends): inlined into each caller (a call a voxel, its arguments spilled, cost
/// the kernel a tenth of its time).
#if defined(__GNUC__)
#define VXF_ALWAYS_INLINE __attribute__((always_inline))
#else
#define VXF_ALWAYS_INLINE
#endif

namespace vxf::detail {

/// A padded cell a sweep reads from a neighbouring leaf: its index in the padded block, the
/// neighbour (0…26 as in SweepLattice::neighbour), the voxel there, and that voxel's place
/// among the neighbour's downwind faces (downwindFaces).
struct Ghost
{
    int padded, slot, local, face;
};

/// The cells of a leaf's downwind faces along @a octant, as padded indices: per axis a, the 64
/// voxels of its last layer along the sweep, the other two axes (a + 1, a + 2 mod 3) by 8 and
/// by 1 (edges and the corner held twice or thrice). All a sweep's next leaves read of a leaf.
inline std::array<std::int16_t, SweepLattice::kFaceVoxels> downwindFaces(int octant)
{
    std::array<std::int16_t, SweepLattice::kFaceVoxels> cells;
    for (int a = 0; a < 3; ++a) {
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        for (int i = 0; i < 8; ++i) {
            for (int j = 0; j < 8; ++j) {
                int x[3];
                x[a] = (octant >> a) & 1 ? 0 : 7;
                x[b] = i;
                x[c] = j;
                cells[std::size_t(a * 64 + i * 8 + j)] = std::int16_t(SweepLattice::paddedIndex(x[0], x[1], x[2]));
            }
        }
    }
    return cells;
}

/// The cells upwind of a leaf along octant @a octant: one layer on each upwind face, edge and
/// corner (9³ − 8³ = 217), in no particular order.
inline std::vector<Ghost> upwindGhosts(int octant)
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
                // The neighbour's voxel lies on its downwind face across the first axis it is off along.
                const int a = d[0] != 0 ? 0 : (d[1] != 0 ? 1 : 2), b = (a + 1) % 3, c = (a + 2) % 3;
                ghosts.push_back({SweepLattice::paddedIndex(i, j, k), (d[0] + 1) * 9 + (d[1] + 1) * 3 + (d[2] + 1),
                    SweepLattice::localIndex(l[0], l[1], l[2]), a * 64 + l[b] * 8 + l[c]});
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

/// The series of in and own in powers of τ, to n = 6 (the terms after add less than 2e-9):
/// (−1)ⁿ/(n!·(n+2)) and (−1)ⁿ/(n!·(n+1)(n+2)), no cancellation near τ = 0.
struct StepSeries
{
    double in[7], own[7];
    constexpr StepSeries()
        : in{}
        , own{}
    {
        double factorial = 1.0;
        for (int n = 0; n < 7; ++n) {
            if (n > 0) factorial *= n;
            const double sign = n % 2 ? -1.0 : 1.0;
            in[n] = sign / (factorial * (n + 2));
            own[n] = sign / (factorial * (n + 1) * (n + 2));
        }
    }
};
inline constexpr StepSeries kStepSeries{};

inline StepWeights stepWeights(double tau)
{
    StepWeights w{};
    w.transmittance = std::exp(-tau);
    if (tau < 0.25) {
        // The series by Horner's rule: a few multiply-adds where the terms one by one took
        // 21 divisions (the smoke's steps are mostly this thin: a fifth of its sweep's time).
        w.in = kStepSeries.in[6];
        w.own = kStepSeries.own[6];
        for (int n = 5; n >= 0; --n) {
            w.in = w.in * tau + kStepSeries.in[n];
            w.own = w.own * tau + kStepSeries.own[n];
        }
    } else {
        const double e = w.transmittance, inverse = 1.0 / (tau * tau);
        w.in = (1.0 - e - tau * e) * inverse;
        w.own = (tau - 1.0 + e) * inverse;
    }
    return w;
}

/// A short characteristic of direction ω: from a voxel's centre back along −ω to the plane of
/// the previous layer of centres across the dominant axis m, whose crossing lies between the
/// four upwind voxels there (bilinear weights, all in [0, 1]: positive, no new extrema),
/// 1/|ω_m| voxels away.
struct Characteristic
{
    float weight[4];
    int offset[4]; ///< of the four upwind voxels, in padded indices
    double length; ///< voxels
};

/// The axis along which ω runs the most (its characteristic's plane lies across it).
inline int dominantAxis(const openvdb::Vec3d& omega)
{
    return std::abs(omega[0]) >= std::abs(omega[1]) ? (std::abs(omega[0]) >= std::abs(omega[2]) ? 0 : 2)
                                                    : (std::abs(omega[1]) >= std::abs(omega[2]) ? 1 : 2);
}

inline Characteristic characteristic(const openvdb::Vec3d& omega)
{
    static constexpr int stride[3] = {100, 10, 1};
    int sign[3];
    for (int a = 0; a < 3; ++a) sign[a] = omega[a] < 0.0 ? -1 : 1;
    const int m = dominantAxis(omega);
    const int b = (m + 1) % 3, c = (m + 2) % 3;
    const double am = std::abs(omega[m]);
    const double ub = std::abs(omega[b]) / am, uc = std::abs(omega[c]) / am;
    const int o0 = -sign[m] * stride[m], ob = -sign[b] * stride[b], oc = -sign[c] * stride[c];
    return {{float((1 - ub) * (1 - uc)), float(ub * (1 - uc)), float((1 - ub) * uc), float(ub * uc)}, {o0, o0 + ob, o0 + oc, o0 + ob + oc},
        1.0 / am};
}

/// opticalDepthAlong continues the outside voxels' depth through the surface where the light
/// enters it at least this steeply (cosine to the inward normal); more grazing, the plane's
/// distance along the light is too uncertain and the step's inside part is taken as it is.
/// The best of the cosines tried (docs/accuracy-notes.md, "Behind the code: SweepLattice").
inline constexpr double kContinuedCosine = 0.45;

/// The octant of direction ω: bit a set where it runs toward −a.
inline int octantOf(const openvdb::Vec3d& omega) { return (omega[0] < 0.0 ? 1 : 0) | (omega[1] < 0.0 ? 2 : 0) | (omega[2] < 0.0 ? 4 : 0); }

/// The weights of one step of length h through a constant σt: the radiance at its end is
/// transmittance·ψ_in + in·J_start + own·J_end for J linear along it (stepWeights' in and own
/// times h; where σt ≤ 0, J integrated as it is: 1, h/2, h/2). In single precision, as ψ and J
/// are held: the step's own arithmetic then costs three multiply-adds a channel.
struct UniformWeights
{
    float transmittance = 1.0f, in = 0.0f, own = 0.0f;
    double sigma = -1.0, h = -1.0; ///< what they were computed for
};

/// @a weights for a step of length @a h through σt = @a sigma, recomputed only when either
/// changes (a uniform medium's steps share them: one exp a direction and leaf, not one a voxel;
/// a pure function of the two, so the result does not depend on which voxel came before).
VXF_ALWAYS_INLINE inline const UniformWeights& uniformWeights(double sigma, double h, UniformWeights& weights)
{
    if (sigma == weights.sigma && h == weights.h) return weights;
    weights.sigma = sigma;
    weights.h = h;
    if (sigma <= 0.0) {
        weights.transmittance = 1.0f;
        weights.in = weights.own = float(0.5 * h);
    } else {
        const StepWeights w = stepWeights(sigma * h);
        weights.transmittance = float(w.transmittance);
        weights.in = float(h * w.in);
        weights.own = float(h * w.own);
    }
    return weights;
}

/// ψ at the end of a step of length @a h through a constant σt = @a sigma with J linear from
/// @a jStart to @a jEnd (uniformWeights, kept in @a weights).
VXF_ALWAYS_INLINE inline float uniformStep(float psiIn, float jStart, float jEnd, double sigma, double h, UniformWeights& weights)
{
    const UniformWeights& w = uniformWeights(sigma, h, weights);
    return w.transmittance * psiIn + w.in * jStart + w.own * jEnd;
}

/// ψ at the end of a step of length @a h through σt varying from @a sa to @a sb (not equal),
/// with J from @a ja to @a jb.
///
/// dψ/dτ = −ψ + S with the source function S = J/σt linear in the optical depth
/// τ = ½(σa + σb)·h: ψ = e^{−τ}ψ_in + τ(in·S_a + own·S_b), exact for those, and S_b where the step
/// is optically thick (the local equilibrium J/σt, whatever σt does along the step). An end
/// without medium (σt = 0) takes the other end's S. That model holds where J follows σt, as
/// scattered light does (J = σs·φ/4π). Emission does not (a volume light's flame where the smoke
/// thins out, an artist's edit of the source): J/σt grows without bound as σt → 0 at one end,
/// and a flame reaching a resampled smoke's edge (σt 1e-4 of the next voxel's) swept 150x too
/// much light. Along the step σt ≥ min(σa, σb), so the source adds at most what J linear along
/// it gives through that constant σt; an answer above that bound is no model of this step, and
/// J linear through the step's own τ takes its place.
/// The step's weights, @a weights kept for the next call (varyingStep: a grey medium's three
/// channels share one exp; a pure function of its arguments, so nothing depends on the order).
struct VaryingWeights
{
    double sa = -1.0, sb = -1.0, h = -1.0; ///< what they were computed for
    double tau = 0.0;
    double inverseA = 0.0, inverseB = 0.0; ///< 1/σt at either end (0 without extinction)
    StepWeights w{};
};
/// @a weights for a step of length @a h through σt from @a sa to @a sb, recomputed only when one
/// of the three changes (a pure function of them: nothing depends on the order of the calls).
inline const VaryingWeights& varyingWeights(double sa, double sb, double h, VaryingWeights& weights)
{
    if (sa != weights.sa || sb != weights.sb || h != weights.h) {
        weights.sa = sa;
        weights.sb = sb;
        weights.h = h;
        weights.tau = 0.5 * (sa + sb) * h;
        weights.w = stepWeights(weights.tau);
        // Divided once a step, not once a channel (a grey medium's three share them): the
        // divisions were a fifth of the smoke's sweep.
        weights.inverseA = sa > 0.0 ? 1.0 / sa : 0.0;
        weights.inverseB = sb > 0.0 ? 1.0 / sb : 0.0;
    }
    return weights;
}

/// ψ at the end of the step varyingWeights made @a weights for, J from @a ja to @a jb.
inline double varyingStep(double psiIn, double ja, double jb, const VaryingWeights& weights)
{
    const double sa = weights.sa, sb = weights.sb, h = weights.h;
    double Sa = ja * weights.inverseA, Sb = jb * weights.inverseB;
    if (sa <= 0.0) Sa = Sb;
    if (sb <= 0.0) Sb = Sa;
    const double tau = weights.tau;
    const StepWeights& sw = weights.w;
    double added = tau * (sw.in * Sa + sw.own * Sb);
    // The bound at σt = 0 first (no exp): scattered light stays far below it.
    if (std::abs(added) > 0.5 * h * (std::abs(ja) + std::abs(jb))) {
        const StepWeights thinnest = stepWeights(std::max(std::min(sa, sb), 0.0) * h);
        if (std::abs(added) > h * (thinnest.in * std::abs(ja) + thinnest.own * std::abs(jb))) added = h * (sw.in * ja + sw.own * jb);
    }
    return sw.transmittance * psiIn + added;
}

/// A leaf's padded σt as Vec3f, stored grey (one float a voxel) or per channel: st[q].
template <typename Sigma>
struct PaddedSigma;
template <>
struct PaddedSigma<float>
{
    const float* values;
    openvdb::Vec3f operator[](int q) const { return openvdb::Vec3f(values[q]); }
};
template <>
struct PaddedSigma<openvdb::Vec3f>
{
    const openvdb::Vec3f* values;
    const openvdb::Vec3f& operator[](int q) const { return values[q]; }
};

/// A leaf's voxels a row at a time, for a sweep along a direction of dominant axis
/// @a major in @a octant: the 8 layers across @a major in upwind order, each as 8 rows of 8
/// voxels that read only the layer before (a short characteristic starts on it), so a row's
/// voxels are blended side by side, the compiler's vectors over their floats. A row runs along
/// z (stride 1 in the padded block and the leaf: major x or y) or along y (stride 10 and 8:
/// major z). visit(p, v, axis) with the padded and leaf index of the row's first voxel and
/// RowAxis<2> or RowAxis<1>.
template <int kAxis>
struct RowAxis
{
    static constexpr int kPadded = kAxis == 2 ? 1 : 10, kLocal = kAxis == 2 ? 1 : 8; ///< strides between a row's voxels
};

template <typename Visit>
inline void forRows(int octant, int major, Visit&& visit)
{
    const int along = major == 2 ? 1 : 2, across = 3 - major - along;
    const bool backward = (octant >> major) & 1;
    const auto layers = [&](auto axis) {
        for (int layer = 0; layer < 8; ++layer) {
            for (int i = 0; i < 8; ++i) {
                int x[3] = {0, 0, 0};
                x[major] = backward ? 7 - layer : layer;
                x[across] = i;
                visit(SweepLattice::paddedIndex(x[0], x[1], x[2]), SweepLattice::localIndex(x[0], x[1], x[2]), axis);
            }
        }
    };
    if (along == 2) {
        layers(RowAxis<2>{});
    } else {
        layers(RowAxis<1>{});
    }
}

/// The blend of the four upwind values a row's voxels read, @a kWidth floats a voxel (3: ψ or
/// J; 1: grey σt or the distance) at padded stride @a kStride: ((0 + w₀a₀) + w₁a₁ + w₂a₂) + w₃a₃,
/// in the order the voxel-by-voxel loop added them (the same bits).
template <int kWidth, int kStride>
VXF_ALWAYS_INLINE inline void blendUpwindRow(const float* values, int p, const float* wt, const int* off, float (&out)[8 * kWidth])
{
    const float *a0 = values + kWidth * (p + off[0]), *a1 = values + kWidth * (p + off[1]), *a2 = values + kWidth * (p + off[2]),
                *a3 = values + kWidth * (p + off[3]);
    if constexpr (kStride == 1) {
        // The same sums as below, as one flat loop: the form the compiler vectorizes.
        for (int e = 0; e < 8 * kWidth; ++e) out[e] = ((0.0f + wt[0] * a0[e]) + wt[1] * a1[e] + wt[2] * a2[e]) + wt[3] * a3[e];
    } else {
        for (int k = 0; k < 8; ++k) {
            for (int c = 0; c < kWidth; ++c) {
                const int e = kWidth * kStride * k + c;
                out[kWidth * k + c] = ((0.0f + wt[0] * a0[e]) + wt[1] * a1[e] + wt[2] * a2[e]) + wt[3] * a3[e];
            }
        }
    }
}

/// The part of a short characteristic's step inside the surface, from the signed distances at
/// its start (the upwind crossing) and its end (the centre), linear along it: all of it, none,
/// or the part next to the end inside, whose values then hold over that part.
struct InsidePart
{
    double fraction = 1.0;
    bool startOutside = false, endOutside = false;
};

inline InsidePart insidePart(float dStart, float dEnd)
{
    if (dEnd >= 0.0f && dStart >= 0.0f) return {0.0, true, true};
    if (dEnd >= 0.0f) return {double(dStart) / double(dStart - dEnd), false, true};
    if (dStart >= 0.0f) return {double(dEnd) / double(dEnd - dStart), true, false};
    return {};
}

template <typename Visit>
void SweepLattice::leavesInUpwindOrder(int octant, const Visit& visit) const
{
    const std::vector<std::int32_t>& order = mOrder[octant];
    const std::vector<std::size_t>& fronts = mWavefronts[octant];
    for (std::size_t f = 0; f + 1 < fronts.size(); ++f) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(fronts[f], fronts[f + 1], 1), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t k = r.begin(); k != r.end(); ++k) visit(std::size_t(order[k]));
        });
    }
}

template <typename Visit>
void SweepLattice::inUpwindOrder(const openvdb::Vec3d& omega, const Depths& values, const Visit& visit, const EnteringDepth& outside) const
{
    const int octant = octantOf(omega);
    const std::vector<Ghost> upwind = upwindGhosts(octant);
    const std::array<UpwindVoxel, kLeafVoxels>& voxels = upwindVoxels(octant, dominantAxis(omega));
    tbb::enumerable_thread_specific<std::vector<openvdb::Vec3f>> buffers(kPaddedVoxels, openvdb::Vec3f(0.0f));
    leavesInUpwindOrder(octant, [&](std::size_t n) {
        openvdb::Vec3f* buffer = buffers.local().data();
        std::optional<SweptSoFar> swept; // (for `outside`, made at the leaf's first ghost without a leaf)
        float least = std::numeric_limits<float>::infinity();
        for (const Ghost& g : upwind) {
            const int leaf = mNeighbours[n * 27 + g.slot];
            if (leaf >= 0) {
                buffer[g.padded] = values[std::size_t(leaf) * kLeafVoxels + g.local];
            } else if (outside) {
                if (!swept) swept.emplace(*this, values, octant, frontKey(n, octant));
                buffer[g.padded] = outside(mOrigins[n].offsetBy(g.padded / 100 - 1, g.padded / 10 % 10 - 1, g.padded % 10 - 1), *swept);
            } else {
                buffer[g.padded] = openvdb::Vec3f(0.0f);
            }
            const openvdb::Vec3f& ghost = buffer[g.padded];
            least = std::min({least, ghost[0], ghost[1], ghost[2]});
        }
        visit(n, buffer, voxels.data(), least);
    });
}

} // namespace vxf::detail
