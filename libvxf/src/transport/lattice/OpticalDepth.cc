// vxf — the lattice's optical-depth sweeps: along a direction (directional and environment
// lights) and from a point (point and spot lights), for the light stage.
#include "SweepSteps.h"

#include <vxf/core/Error.h>
#include <vxf/core/Hash.h>

#include <openvdb/tree/LeafManager.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <unordered_map>

namespace vxf::detail {

namespace {

/// The upwind blend of τ less what it overstates where σt ramps: the blend is linear across
/// the upwind face, and τ is not where the light crosses a slope of σt (a soft edge: a fog's
/// density ramping across a surface's band). Through a planar ramp, σt = f(n·x), τ at x is
/// dx·F(n·x)/(n·ω) (F' = f), whose Hessian dx·g gᵀ/(g·ω) (g = ∇σt per voxel) depends on the
/// slope alone; the bilinear blend of a function with Hessian H over upwind centres δ_k from
/// the crossing overstates it by ½ Σ w_k δ_kᵀ H δ_k = dx·Σ w_k (g·δ_k)² / (2 g·ω). With σt
/// linear there, g·δ_k is σt_k less the blend of σt at the crossing and g·ω the step's rise of
/// σt over its @a length, so the overstatement is ½·length·dx·rise·r, r = Var_w(σt_k)/rise²:
/// read from the step's own σt, where it is a sweep's five values. Where the slope runs across
/// the light (r large, rise small) the plane is no guide, nor across a step of σt (a voxel's
/// ramp between its kinks): r is held to kRampRatio, and the result to the upwind depths'
/// range (a blend, never beyond it). Uniform σt: unchanged, to the bit. The `direct` grid
/// against `--march`'s, density-weighted (its voxels' L1): bench/accuracy's fog lit by its sun
/// 0.967 → 0.993 (3.70 → 2.22%), its smoke 0.982 → 0.995 (1.85 → 1.07%), a sphere of density
/// 0 or 1 0.921 → 1.002 (9.15 → 7.26%); a larger cap brought the fog nearer 1 in sum (8: 1.000)
/// but every L1 further off, the sphere's to 9.38% (docs/accuracy-notes.md (ap)).
constexpr double kRampRatio = 1.0;

float rampCorrected(
    float tauIn, float stIn, float here, const float (&weight)[4], const float (&sigma)[4], const float (&tau)[4], double stepLength)
{
    double variance = 0.0;
    float least = std::numeric_limits<float>::max(), most = -least;
    for (int k = 0; k < 4; ++k) {
        if (!(weight[k] > 0.0f)) continue;
        const double d = double(sigma[k]) - double(stIn);
        variance += double(weight[k]) * d * d;
        least = std::min(least, tau[k]);
        most = std::max(most, tau[k]);
    }
    const double rise = double(here) - double(stIn);
    if (!(variance > 0.0) || rise == 0.0) return tauIn;
    const double ratio = std::min(variance / (rise * rise), kRampRatio);
    return std::clamp(float(double(tauIn) - 0.5 * stepLength * rise * ratio), least, most);
}

} // namespace

openvdb::Vec3f SweepLattice::depthStep(std::size_t leaf, int p, const openvdb::Vec3d& omega, const float (&weight)[4],
    const int (&offset)[4], double length, const openvdb::Vec3f (&tauUpwind)[4]) const
{
    openvdb::Vec3f tauIn(0.0f), stIn(0.0f), sigma[4];
    for (int k = 0; k < 4; ++k) {
        sigma[k] = paddedSigmaT(leaf, p + offset[k]);
        tauIn += weight[k] * tauUpwind[k];
        stIn += weight[k] * sigma[k];
    }
    const openvdb::Vec3f here = paddedSigmaT(leaf, p);
    const float* distance = distanceBlock(leaf);
    if (!distance) {
        // No surface, or deep inside it: every step whole (as insidePart of two negative
        // distances), the blend less what a ramp of σt makes it overstate (rampCorrected).
        const bool uniform = sigma[0] == here && sigma[1] == here && sigma[2] == here && sigma[3] == here;
        if (!uniform) {
            const auto grey = [](const openvdb::Vec3f& v) { return v[0] == v[1] && v[1] == v[2]; };
            bool same = grey(here);
            for (int k = 0; k < 4; ++k) same = same && grey(sigma[k]) && grey(tauUpwind[k]);
            for (int c = 0; c < 3; ++c) {
                if (same && c > 0) {
                    tauIn[c] = tauIn[0];
                    continue;
                }
                const float s[4] = {sigma[0][c], sigma[1][c], sigma[2][c], sigma[3][c]};
                const float t[4] = {tauUpwind[0][c], tauUpwind[1][c], tauUpwind[2][c], tauUpwind[3][c]};
                tauIn[c] = rampCorrected(tauIn[c], stIn[c], here[c], weight, s, t, length * mVoxelSize);
            }
        }
        return tauIn + float(0.5 * length * mVoxelSize) * (stIn + here);
    }
    float dIn = 0.0f;
    bool outside = false, inside = false; // upwind voxels on either side of the surface
    for (int k = 0; k < 4; ++k) {
        const int q = p + offset[k];
        dIn += weight[k] * distance[q];
        if (weight[k] > 0.0f) (distance[q] >= 0.0f ? outside : inside) = true;
    }
    const float dHere = distance[p];
    // Light entering through the surface between the upwind voxels: τ rises linearly from the
    // surface, 0 before it, and blending across that kink overstates it (the first voxel inside
    // came out 16% dark at 0.77 mean free paths per voxel). The outside voxels' τ is continued
    // through the surface instead, as far as a plane (the level set's normal here) puts it,
    // with this voxel's σt, and the step taken whole.
    double cosine = 0.0;
    if (outside && inside && dHere < 0.0f) {
        const openvdb::Vec3d normal(
            distance[p + 100] - distance[p - 100], distance[p + 10] - distance[p - 10], distance[p + 1] - distance[p - 1]);
        if (normal.length() > 1e-6) cosine = -omega.dot(normal.unit());
    }
    openvdb::Vec3f result = tauIn;
    if (cosine > kContinuedCosine) {
        result = openvdb::Vec3f(float(length * mVoxelSize) * here);
        for (int k = 0; k < 4; ++k) {
            const int q = p + offset[k];
            openvdb::Vec3f t = tauUpwind[k];
            if (distance[q] >= 0.0f) t -= float(distance[q] / cosine * mVoxelSize) * here;
            result += weight[k] * t;
        }
        for (int ch = 0; ch < 3; ++ch) result[ch] = std::max(result[ch], 0.0f);
    } else {
        const InsidePart part = insidePart(dIn, dHere);
        if (part.fraction > 0.0) {
            const openvdb::Vec3f sigmaStart = part.startOutside ? here : stIn, sigmaEnd = part.endOutside ? stIn : here;
            result += float(0.5 * length * part.fraction * mVoxelSize) * (sigmaStart + sigmaEnd);
        }
    }
    return result;
}

void SweepLattice::opticalDepthAlong(const openvdb::Vec3d& omega, Depths& tau, const EnteringDepth& entering, float opaque) const
{
    requireFine("opticalDepthAlong");
    tau.assignZero(*this);
    const Characteristic c = characteristic(omega);
    const float halfStep = float(0.5 * c.length * mVoxelSize);
    inUpwindOrder(
        omega, tau,
        [&](std::size_t n, openvdb::Vec3f* buffer, const UpwindVoxel* voxels, float leastUpwind) {
            const std::size_t first = n * kLeafVoxels;
            if (leastUpwind > opaque && (mUniform[n] || !distanceBlock(n))) {
                for (int v = 0; v < kLeafVoxels; ++v) tau.set(first + std::size_t(v), openvdb::Vec3f(leastUpwind));
                return;
            }
            if (mUniform[n]) {
                // One σt over the padded block: every step adds the same (its upwind blend of σt
                // the same sum at every voxel), the block's σt not read (it is most of a sweep's
                // memory traffic).
                const openvdb::Vec3f sigmaT = paddedSigmaT(n, 0);
                openvdb::Vec3f stIn(0.0f);
                for (int k = 0; k < 4; ++k) stIn += c.weight[k] * sigmaT;
                const openvdb::Vec3f own = halfStep * (stIn + sigmaT);
                // A row at a time (forRows): the upwind blends of a row's 8 voxels side by side.
                forRows(octantOf(omega), dominantAxis(omega), [&](int p, int v, auto axis) {
                    constexpr int kPadded = decltype(axis)::kPadded, kLocal = decltype(axis)::kLocal;
                    float tauIn[24];
                    blendUpwindRow<3, kPadded>(buffer->asPointer(), p, c.weight, c.offset, tauIn);
                    for (int k = 0; k < 8; ++k) {
                        const openvdb::Vec3f result = openvdb::Vec3f(tauIn + 3 * k) + own;
                        buffer[p + kPadded * k] = result;
                        tau.set(first + std::size_t(v + kLocal * k), result);
                    }
                });
                return;
            }
            for (int voxel = 0; voxel < kLeafVoxels; ++voxel) {
                const int p = voxels[voxel].padded;
                const openvdb::Vec3f upwind[4] = {
                    buffer[p + c.offset[0]], buffer[p + c.offset[1]], buffer[p + c.offset[2]], buffer[p + c.offset[3]]};
                const openvdb::Vec3f result = depthStep(n, p, omega, c.weight, c.offset, c.length, upwind);
                buffer[p] = result;
                tau.set(first + std::size_t(voxels[voxel].local), result);
            }
        },
        entering);
}

int SweepLattice::octantAround(const openvdb::Coord& ijk, const openvdb::Vec3d& point)
{
    return (ijk[0] < point[0] ? 1 : 0) | (ijk[1] < point[1] ? 2 : 0) | (ijk[2] < point[2] ? 4 : 0);
}

float SweepLattice::darkLeafDepth(std::size_t leaf, int octant, const openvdb::Vec3d& point, const Depths& tau) const
{
    // (Deep: every step whole, its own depth σt·length·dx added to the blend.)
    if (!mUniform[leaf]) return -1.0f;
    // The leaf and its ghost layer (on the side toward the point: +8 where the leaf lies below
    // it) all in the octant, and the leaf's nearest voxel centre R from the point.
    const openvdb::Coord& o = mOrigins[leaf];
    int ghost[3];
    double nearest = 0.0;
    for (int a = 0; a < 3; ++a) {
        const bool below = (octant >> a) & 1;
        if (below ? !(o[a] + 8 < point[a]) : !(o[a] - 1 >= point[a])) return -1.0f;
        ghost[a] = below ? 8 : -1;
        const double gap = below ? point[a] - double(o[a] + 7) : double(o[a]) - point[a];
        nearest += gap * gap;
    }
    float least = std::numeric_limits<float>::infinity();
    const auto read = [&](int x, int y, int z) {
        const std::int64_t at = voxelIndex(leaf, x, y, z);
        if (at < 0) return false;
        const openvdb::Vec3f t = tau[std::size_t(at)];
        least = std::min({least, t[0], t[1], t[2]});
        return true;
    };
    for (int i = 0; i < 8; ++i) {
        for (int j = 0; j < 8; ++j) {
            if (!read(ghost[0], i, j) || !read(i, ghost[1], j) || !read(i, j, ghost[2])) return -1.0f;
        }
        if (!read(ghost[0], ghost[1], i) || !read(ghost[0], i, ghost[2]) || !read(i, ghost[1], ghost[2])) return -1.0f;
    }
    if (!read(ghost[0], ghost[1], ghost[2])) return -1.0f;
    // A voxel's crossing lies c.length ≤ √3 short of it (crossing ≥ R − √3), its four upwind
    // centres within √2 of the crossing: each upwind depth is scaled by crossing / r ≥ ρ. The
    // step then adds σt·length·dx ≥ σt·dx. So depths ≥ V upwind give ρV + σt·dx ≥ V at every
    // voxel where V ≤ σt·dx / (1 − ρ): the least ghost's depth, capped there, bounds them all.
    const double crossing = std::sqrt(nearest) - std::sqrt(3.0);
    if (!(crossing > 0.0)) return -1.0f;
    const double rho = crossing / (crossing + std::sqrt(2.0));
    const openvdb::Vec3f sigma = paddedSigmaT(leaf, 0);
    const double step = double(std::min({sigma[0], sigma[1], sigma[2]})) * mVoxelSize;
    return float(std::min(double(least), step / (1.0 - rho)));
}

void SweepLattice::opticalDepthFrom(
    const openvdb::Vec3d& point, Depths& tau, std::vector<std::uint8_t>& state, const MarchedDepth& marched, float opaque) const
{
    requireFine("opticalDepthFrom");
    tau.assignZero(*this);
    state.assign(voxelCount(), kPending);
    for (int octant = 0; octant < 8; ++octant) {
        // The leaves holding voxels of this octant (bit a set: below the point along axis a).
        const auto holds = [&](std::size_t n) {
            for (int a = 0; a < 3; ++a) {
                const bool below = (octant >> a) & 1;
                if (below ? !(mOrigins[n][a] < point[a]) : !(mOrigins[n][a] + 7 >= point[a])) return false;
            }
            return true;
        };
        leavesInUpwindOrder(octant, [&](std::size_t n) {
            if (!holds(n)) return;
            if (std::isfinite(opaque)) {
                const float dark = darkLeafDepth(n, octant, point, tau);
                if (dark > opaque) {
                    for (std::size_t i = n * kLeafVoxels; i < (n + 1) * kLeafVoxels; ++i) {
                        tau.set(i, openvdb::Vec3f(dark));
                        state[i] = kBlended;
                    }
                    return;
                }
            }
            const SweptSoFar swept(*this, tau, octant, n, frontKey(n, octant), point, &state);
            const openvdb::Coord& o = mOrigins[n];
            const openvdb::Vec3d centre = o.asVec3d() + openvdb::Vec3d(3.5) - point;
            const std::array<UpwindVoxel, kLeafVoxels>& voxels = upwindVoxels(octant, dominantAxis(centre));
            for (const UpwindVoxel& voxel : voxels) {
                const int local = voxel.local;
                const openvdb::Coord ijk = o.offsetBy(local >> 6, (local >> 3) & 7, local & 7);
                if (octantAround(ijk, point) != octant) continue;
                const std::size_t i = n * kLeafVoxels + std::size_t(local);
                const float d = paddedDistance(n, voxel.padded);
                const openvdb::Vec3d away = ijk.asVec3d() - point;
                // A characteristic reaching back past the point's own layer (a voxel next to the
                // point) has no upwind layer to read: marched.
                bool sweepable = std::abs(away[dominantAxis(away)]) > 1.0;
                Characteristic c{};
                openvdb::Vec3f upwind[4];
                if (sweepable) {
                    c = characteristic(away.unit());
                    const double crossing = away.length() - c.length; // the crossing's distance from the point
                    for (int k = 0; k < 4 && sweepable; ++k) {
                        upwind[k] = openvdb::Vec3f(0.0f);
                        if (!(c.weight[k] > 0.0f)) continue;
                        const int q = voxel.padded + c.offset[k];
                        const int ux = q / 100 - 1, uy = q / 10 % 10 - 1, uz = q % 10 - 1;
                        const std::int64_t at = voxelIndex(n, ux, uy, uz);
                        // An upwind voxel of no leaf (light across vacuum) or across one of the
                        // point's planes not yet swept: marched.
                        if (at < 0 || octantAround(o.offsetBy(ux, uy, uz), point) > octant) {
                            sweepable = false;
                        } else {
                            // τ grows along each ray from the point, not across the fan: blended
                            // as it is, the cone σt·r is convex across the layer and every step
                            // overstates it (3.5% of the light off at 30 voxels in a uniform box).
                            // Blended as the mean σt of each ray (τ/r) times the crossing's own
                            // distance, a uniform medium's τ is exact.
                            const double r = (o.offsetBy(ux, uy, uz).asVec3d() - point).length();
                            upwind[k] = tau[std::size_t(at)] * float(crossing / r);
                        }
                    }
                }
                openvdb::Vec3f depth;
                if (marched(ijk, d, !sweepable, swept, depth)) {
                    tau.set(i, depth);
                    state[i] = kMarched;
                } else {
                    tau.set(i, depthStep(n, voxel.padded, away.unit(), c.weight, c.offset, c.length, upwind));
                    state[i] = kBlended;
                }
            }
        });
    }
}

} // namespace vxf::detail
