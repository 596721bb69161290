#include "LightSweeps.h"

#include <vxf/core/GridRoles.h>
#include <vxf/core/GridStats.h>
#include <vxf/core/MemoryBudget.h>
#include <vxf/light/VolumeEmission.h>
#include <vxf/transport/Phase.h>

#include "transport/lattice/SweepLattice.h"

#include <vxf/core/Hash.h>

#include <openvdb/tools/Morphology.h>
#include <openvdb/tree/LeafManager.h>

#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>

namespace vxf::detail {

namespace {

/// The sums a sweep adds its light to, made zero over @a lattice's leaves when they are empty.
void sizeSums(const SweepLattice& lattice, LeafBlocks<openvdb::Vec3f>& fluence, LeafBlocks<openvdb::Vec3f>* flux)
{
    if (fluence.empty()) fluence.assign(lattice.leafCount(), openvdb::Vec3f(0.0f));
    if (flux && flux->empty()) flux->assign(lattice.leafCount(), openvdb::Vec3f(0.0f));
}

} // namespace

/// The rim of @a lattice's voxels: centres outside the surface within half a voxel, where
/// Medium::Sampler::mediumPoint is the surface beneath (with its normal there).
Rim rimOf(const detail::SweepLattice& lattice, const Medium& medium)
{
    Rim rim;
    if (!medium.surface()) return rim;
    // Per leaf in parallel, then numbered in leaf order (the same for any thread count).
    struct Found
    {
        std::uint32_t voxel;
        openvdb::Vec3d point, normal;
    };
    std::vector<std::vector<Found>> perLeaf(lattice.leafCount());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lattice.leafCount()), [&](const tbb::blocked_range<std::size_t>& r) {
        Medium::Sampler sampler(medium);
        for (std::size_t n = r.begin(); n != r.end(); ++n) {
            if (lattice.deep(n)) continue; // (every centre inside by more than half a voxel)
            for (int v = 0; v < detail::SweepLattice::kLeafVoxels; ++v) {
                const openvdb::Coord ijk = lattice.origin(n).offsetBy(v >> 6, (v >> 3) & 7, v & 7);
                const openvdb::Vec3d point = sampler.mediumPoint(ijk);
                if (point == ijk.asVec3d()) continue;
                openvdb::Vec3d normal;
                if (sampler.surfaceNormal(ijk.asVec3d(), normal)) perLeaf[n].push_back({std::uint32_t(v), point, normal});
            }
        }
    });
    rim.leafStart.assign(perLeaf.size() + 1, 0);
    for (std::size_t n = 0; n < perLeaf.size(); ++n) {
        rim.leafStart[n] = rim.voxels.size();
        for (const Found& f : perLeaf[n]) { // (in the voxels' order)
            const std::size_t i = n * detail::SweepLattice::kLeafVoxels + f.voxel;
            rim.voxels.push_back(i);
            rim.points.push_back(f.point);
            rim.normals.push_back(f.normal);
        }
    }
    rim.leafStart.back() = rim.voxels.size();
    return rim;
}

/// Where light reaching the lattice across vacuum left the medium (a mesh hit toward the
/// light), the sweep's depth is read at the first point back along the ray, a voxel at a time
/// up to kSweptReadBack voxels, that lies kSweptReadOff voxels or more outside the surface: the
/// eight voxels interpolated there all outside it (within √3/2 of the point), where the depth
/// is the exit's, carried through vacuum.
constexpr double kSweptReadBack = 4.0, kSweptReadOff = 1.0;
/// A march from the rim along a direction grazing the surface hands the rest of its way to the
/// sweep's depth once it lies this many voxels or more outside the surface (kInsideHandOff
/// inside it): out of the smeared terminator, where the sweep is as right as anywhere. The
/// accuracy bench's translucent bunny (dim 64): 1.707% with every grazing direction marched
/// whole, 1.707% handing off from 2 voxels, 1.709% from 1; the sky of 64 directions at dim 256:
/// the rim's light within 0.58% (L1) of the whole marches at 2 voxels, 1.1% at 1, and within
/// 0.006% handing off at 2 voxels inside only: the error is the outside's (accuracy-notes (n));
/// 21.3 → 18.9 s (17.6 s at 1).
constexpr double kRimHandOff = 2.0;
/// Inside the surface a march hands off a voxel deep: the sweep's depth a voxel under the
/// surface is as right as two voxels under it, and a grazing ray reaches it in half the steps
/// (bench/accuracy/probe's errors the same or lower: docs/accuracy-notes.md (ao)).
constexpr double kInsideHandOff = 1.0;

/// Whether a march at signed distance @a distance (voxels) from the surface is clear of it:
/// kInsideHandOff inside, kRimHandOff outside.
bool clearOfSurface(double distance) { return distance < 0.0 ? -distance >= kInsideHandOff : distance >= kRimHandOff; }

/// A march's hand-off to what @a swept holds, once clear of the surface (the rim's grazing
/// marches, and light entering the lattice across vacuum).
MarchHandOff sweptClearOfSurface(const detail::SweepLattice::SweptSoFar& swept)
{
    return [&swept](const openvdb::Vec3d& at, double distance, openvdb::Vec3f& depth) {
        return clearOfSurface(distance) && swept.sample(at, depth);
    };
}

/// Optical depths in place of a march's transmittance, and back: a march stops (T = 0) where
/// every channel's depth passes the cutoff's, which a depth then stands for by `blocked`.
struct MarchedDepths
{
    explicit MarchedDepths(const MarchOptions& march)
        : cutoff(-std::log(std::max(march.cutoff, std::numeric_limits<double>::min())))
        , blocked(float(std::max(2.0 * cutoff, 50.0)))
    {
    }
    /// The optical depth of a march's transmittance @a t (a march stopped at the cutoff: beyond it).
    openvdb::Vec3f depthOf(const openvdb::Vec3d& t) const
    {
        openvdb::Vec3f depth;
        for (int c = 0; c < 3; ++c) depth[c] = t[c] > 0.0 ? float(-std::log(t[c])) : blocked;
        return depth;
    }
    /// The transmittance of optical depth @a tau, 0 where a march would have stopped.
    openvdb::Vec3d transmittanceOf(const openvdb::Vec3f& tau) const
    {
        if (std::min({tau[0], tau[1], tau[2]}) > cutoff) return openvdb::Vec3d(0.0);
        // In float, as τ is held (a sweep's every voxel and direction asks); once where grey.
        if (tau[0] == tau[1] && tau[1] == tau[2]) return openvdb::Vec3d(std::exp(-tau[0]));
        return openvdb::Vec3d(std::exp(-tau[0]), std::exp(-tau[1]), std::exp(-tau[2]));
    }
    double cutoff;
    float blocked;
};

/// τ from @a fromIjk along the unit index-space @a direction for @a length (index units),
/// marched through @a leaves' spans only (the medium's: the vacuum between them holds none) and
/// handed to @a handOff where it takes the rest of the way; @a spans is scratch.
openvdb::Vec3f depthThroughLeaves(Medium::Sampler& sampler, const Medium& medium, const LatticeSpans& leaves, const openvdb::Vec3d& fromIjk,
    const openvdb::Vec3d& direction, double length, const MarchOptions& march, const MarchedDepths& depths, const MarchHandOff& handOff,
    std::vector<LatticeSpans::Span>& spans)
{
    leaves.along(fromIjk, direction, kVacuumMargin, spans);
    bool handedOff = false;
    const MarchHandOff noting = [&](const openvdb::Vec3d& at, double distance, openvdb::Vec3f& rest) {
        return handedOff = handOff(at, distance, rest);
    };
    openvdb::Vec3f depth(0.0f);
    for (const LatticeSpans::Span& span : spans) {
        if (span.t0 >= length) break;
        const openvdb::Vec3d t =
            transmittance(sampler, medium, fromIjk + direction * span.t0, fromIjk + direction * std::min(span.t1, length), march, noting);
        depth += depths.depthOf(t);
        if (handedOff || std::min({depth[0], depth[1], depth[2]}) > depths.cutoff) break;
    }
    return depth;
}

/// A sampler of @a medium whose marches take the surface's crossings on options.boundary, and
/// do not ask the meshes for crossings the level set missed within a step: an Embree ray for
/// every step near the surface, 0.66 of the light stage's 7.1 CPU seconds on the thick bunny at
/// dim 256, for no measurable change in bench/accuracy/probe's errors (docs/accuracy-notes.md
/// (ao)). The placing of the crossings is kept: without it the thick bunny at dim 64 came 4.51
/// → 4.83% off.
Medium::Sampler lightStageSampler(const Medium& medium, const DirectLightOptions& options)
{
    Medium::Sampler sampler(medium);
    sampler.snapCrossingsTo(options.boundary, Medium::Sampler::MissedCrossings::Ignored);
    return sampler;
}

/// Whether sweepLight handles @a light (the others are marched voxel by voxel).
bool sweepable(const Light& light) { return light.type == Light::Type::Directional || light.type == Light::Type::Environment; }

/// Light sample @a s, through one direction's optical depths @a tau (travelling along the unit
/// index-space @a travel), added to the sums @a phi (and @a flux) at every voxel of @a lattice
/// it reaches, a leaf at a time (its rim entries, most leaves have none, and its sums' block
/// looked up once): not at the rim voxels the direction grazes (marched), nor where one of
/// @a occluders blocks it.
void addSweptSample(const LightSample& s, const openvdb::Vec3d& travel, const detail::SweepLattice& lattice,
    const detail::SweepLattice::Depths& tau, const MarchedDepths& depths, const Rim& rim, const Medium& medium, const RayScene* occluders,
    LeafBlocks<openvdb::Vec3f>& phi, LeafBlocks<openvdb::Vec3f>* flux)
{
    constexpr int kLeafVoxels = detail::SweepLattice::kLeafVoxels;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lattice.leafCount()), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t n = r.begin(); n != r.end(); ++n) {
            const std::size_t first = n * kLeafVoxels;
            const bool rimmed = !rim.leafStart.empty() && rim.leafStart[n] != rim.leafStart[n + 1];
            openvdb::Vec3f* phiBlock = &phi[first];
            openvdb::Vec3f* fluxBlock = flux ? &(*flux)[first] : nullptr;
            for (int v = 0; v < kLeafVoxels; ++v) {
                const std::size_t i = first + std::size_t(v);
                const openvdb::Vec3d t = depths.transmittanceOf(tau[i]);
                if (t == openvdb::Vec3d(0.0)) continue;
                if (rimmed) {
                    const std::int32_t e = rim.entryOf(i);
                    if (e >= 0 && rim.grazing(e, -travel)) continue;
                }
                if (occluders) {
                    const openvdb::Coord ijk = lattice.origin(n).offsetBy(v >> 6, (v >> 3) & 7, v & 7);
                    if (!unoccluded(occluders, medium, medium.transform().indexToWorld(ijk), s)) continue;
                }
                phiBlock[v] += openvdb::Vec3f(s.fluence * t);
                if (fluxBlock) fluxBlock[v] -= openvdb::Vec3f(greyOf(s.fluence * t) * s.direction);
            }
        }
    });
}

/// The fluence of a directional or environment light at the centre of every voxel of @a lattice
/// (per voxel), its transmittance by one optical-depth sweep per direction
/// (SweepLattice::opticalDepthAlong); at @a rim voxels, along the directions grazing the
/// surface there, its transmittance from the medium point, marched until the ray is clear of
/// the surface and swept beyond. Where every channel's transmittance is
/// below options.march.cutoff the light counts as blocked, as a march stops there; occluder
/// meshes are still asked per voxel and sample. With @a flux, also the light's grey first
/// moment per voxel (lightFluence).
void sweepLight(const LightSampler& light, const detail::SweepLattice& lattice, const Medium& medium, const Rim& rim,
    const LatticeSpans* spans, const DirectLightOptions& options, LeafBlocks<openvdb::Vec3f>& phi, LeafBlocks<openvdb::Vec3f>* flux)
{
    const openvdb::math::Transform& xform = medium.transform();
    const MarchedDepths depths(options.march);
    // One sampler per thread for the entering depths' marches (a sampler registers accessors).
    tbb::enumerable_thread_specific<Medium::Sampler> samplers([&] { return lightStageSampler(medium, options); });
    const double minDistance = 0.5 * medium.voxelSize();
    sizeSums(lattice, phi, flux);
    detail::SweepLattice::Depths tau;
    const openvdb::Vec3d anywhere = xform.indexToWorld(medium.activeBounds().getCenter());

    const bool surface = medium.surface() != nullptr;
    tbb::enumerable_thread_specific<std::vector<LatticeSpans::Span>> spanLists;

    std::vector<LightSample> samples;
    for (std::size_t d = 0; d < light.count(); ++d) {
        light.sample(anywhere, 0, minDistance, samples, d, d + 1);
        if (samples.empty()) continue; // carries nothing
        const LightSample s = samples.front();
        // The light travels along −s.direction; in index space (the transform may scale).
        const openvdb::Vec3d travel = (xform.worldToIndex(anywhere - s.direction) - xform.worldToIndex(anywhere)).unit();
        // Light arriving at the lattice from a voxel of no leaf: the depth on its way there
        // (other parts of the medium, across vacuum, shadow it). With the medium's meshes at
        // hand, a ray toward the light that meets none crosses no medium; one that does left
        // the medium where it meets it, and from there on through vacuum carries the depth the
        // sweep already holds (an earlier wavefront's), read kSweptReadOff voxels off the
        // surface; where the sweep has none there yet, marched from two voxels before the hit
        // until clear of the surface (clearOfSurface), where the sweep's depth takes over as for
        // the rim (these marches had run through the medium to the cutoff).
        const auto entering = [&](const openvdb::Coord& ijk, const detail::SweepLattice::SweptSoFar& swept) {
            openvdb::Vec3d from = ijk.asVec3d();
            if (options.boundary) {
                const openvdb::Vec3d world = xform.indexToWorld(from);
                const auto hit = options.boundary->intersect(world, s.direction);
                if (!hit) return openvdb::Vec3f(0.0f);
                const double distance = (xform.worldToIndex(world + s.direction * hit->distance) - from).length();
                for (double back = 1.0; back <= kSweptReadBack && back < distance - 1.0; back += 1.0) {
                    const openvdb::Vec3d at = from - travel * (distance - back);
                    if (samplers.local().signedDistance(at) < kSweptReadOff) continue;
                    openvdb::Vec3f depth;
                    if (swept.sample(at, depth)) return depth;
                    break;
                }
                const double ahead = distance - 2.0;
                if (ahead > 0.0) from -= travel * ahead;
            }
            if (spans) {
                // Without meshes, through the lattice's leaves only (LatticeSpans). Without a
                // surface either, handing off once kRimHandOff voxels of medium are marched (out
                // of the smeared edge of the shadow the ray left, which a soft edge spreads over
                // voxels; bench/accuracy's fog: the `direct` grid 3.18% off the marched one
                // before, 3.22% so, 3.24% after one voxel, 3.35% handing off at once; the light
                // stage 12.5 → 7.9 s, 6.4 at once).
                int marchedInMedium = 0;
                const MarchHandOff handOff =
                    surface ? sweptClearOfSurface(swept) : MarchHandOff([&](const openvdb::Vec3d& at, double, openvdb::Vec3f& rest) {
                        if (samplers.local().sigmaT(at) != openvdb::Vec3d(0.0)) ++marchedInMedium;
                        return marchedInMedium >= kRimHandOff && swept.sample(at, rest);
                    });
                return depthThroughLeaves(samplers.local(), medium, *spans, from, -travel, std::numeric_limits<double>::infinity(),
                    options.march, depths, handOff, spanLists.local());
            }
            return depths.depthOf(
                transmittanceToBoundary(samplers.local(), medium, from, -travel, options.march, sweptClearOfSurface(swept)));
        };
        // Leaves in the dark (every upwind depth beyond the cutoff) are not swept.
        lattice.opticalDepthAlong(travel, tau, entering, float(depths.cutoff));
        addSweptSample(s, travel, lattice, tau, depths, rim, medium, options.occluders, phi, flux);
        // The rim along the directions grazing it: marched from the medium point toward the
        // light until the ray is clear of the surface (clearOfSurface: it left the medium, or
        // went into it), and on from there with the sweep's depth. A ray leaving the
        // surface outward crosses vacuum up to the next of the medium's meshes ahead
        // (vacuumAhead): none, and the light arrives whole; else the march starts
        // kVacuumMargin voxels before it.
        const detail::SweepLattice::SweptSoFar swept(lattice, tau);
        const MarchHandOff handOff = sweptClearOfSurface(swept);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rim.voxels.size()), [&](const tbb::blocked_range<std::size_t>& r) {
            Medium::Sampler& sampler = samplers.local();
            for (std::size_t e = r.begin(); e != r.end(); ++e) {
                if (!rim.grazing(std::int32_t(e), -travel)) continue;
                const openvdb::Vec3d& x = rim.points[e];
                openvdb::Vec3d from = x;
                double skip = 0.0;
                if (options.boundary && rim.normals[e].dot(travel) < 0.0) {
                    const openvdb::Vec3d world = xform.indexToWorld(x);
                    skip = vacuumAhead(*options.boundary, world, s.direction, kVacuumMargin * medium.voxelSize());
                    if (skip > 0.0 && std::isfinite(skip)) from = xform.worldToIndex(world + s.direction * skip);
                }
                const openvdb::Vec3d t = std::isinf(skip) ? openvdb::Vec3d(1.0)
                                                          : transmittanceToBoundary(sampler, medium, from, -travel, options.march, handOff);
                if (t != openvdb::Vec3d(0.0) && unoccluded(options.occluders, medium, xform.indexToWorld(x), s)) {
                    phi[rim.voxels[e]] += openvdb::Vec3f(s.fluence * t);
                    if (flux) (*flux)[rim.voxels[e]] -= openvdb::Vec3f(greyOf(s.fluence * t) * s.direction);
                }
            }
        });
    }
}

/// Whether sweepPointLight handles @a light: one point whose light every voxel sees along its
/// own ray (point and spot lights; an area light's samples are many points).
bool sweepableFromPoint(const Light& light) { return light.type == Light::Type::Point || light.type == Light::Type::Spot; }

/// A point light's voxels within this many voxels inside the surface are marched to
/// the light (handing off to the sweep's depth once clear of the surface, clearOfSurface),
/// the others swept (SweepLattice::opticalDepthFrom), their depth blended from voxels nearer the
/// light. Near the surface the light falls steeply, and in a thick medium almost all of it is
/// there: the thick bunny at dim 64 came out 6.1% off the reference swept whole, 3.9% marched.
constexpr double kPointMarchedBand = 3.0;
static_assert(kPointMarchedBand < detail::SweepLattice::kDistanceHeld, "the lattice holds the distances the band is chosen by");
/// Outside the surface (vacuum: the light does not fall there) the band is narrower: it holds
/// what the medium reads of the light (a point inside the surface interpolates voxels within √3
/// of it); a march that left the surface and finds the voxels it would read not all marched asks
/// the meshes once what lies ahead. Beyond the band the sweep's blend smears the edges of
/// shadows cast across vacuum, as it did beyond 3 voxels. bench/accuracy/probe's thick bunny
/// the same to its digits (4.488 / 3.720 / 3.839%), the light stage at dim 256 5.73 → 5.53 CPU s
/// (docs/accuracy-notes.md (ao)).
constexpr double kPointMarchedOutside = 2.0;

/// Whether a point light marches a voxel at signed distance @a distance (voxels) from the surface.
bool inPointBand(float distance) { return distance < 0.0f ? -distance < kPointMarchedBand : distance < kPointMarchedOutside; }

/// A march from a point light's band voxel that has left the medium hands off to the depths of
/// marched voxels only where their eight spread over at most this: across a shadow's edge
/// (another part of the medium between the light and some of them) it marches on.
constexpr float kVacuumSpread = 0.05f;

/// The fluence of a point or spot light at every voxel of @a lattice (per voxel), at its
/// medium point (Medium::Sampler::mediumPoint), as lightFluence gives it, the transmittance from
/// one optical-depth sweep around the light (SweepLattice::opticalDepthFrom): voxels within
/// kPointMarchedBand inside the surface and kPointMarchedOutside outside it, and those the sweep
/// cannot blend, marched to the light, handing the rest of the way to the sweep once clear of
/// the surface; the rim marched from its medium point the same way. Without a surface (a
/// density grid's medium) every voxel the sweep can blend is swept. With @a flux, also the
/// light's grey first moment per voxel.
void sweepPointLight(const LightSampler& light, const detail::SweepLattice& lattice, const Medium& medium, const Rim& rim,
    const LatticeSpans* leaves, const DirectLightOptions& options, LeafBlocks<openvdb::Vec3f>& phi, LeafBlocks<openvdb::Vec3f>* flux)
{
    using detail::SweepLattice;
    const openvdb::math::Transform& xform = medium.transform();
    const MarchedDepths depths(options.march);
    const bool surface = medium.surface() != nullptr;
    tbb::enumerable_thread_specific<Medium::Sampler> samplers([&] { return lightStageSampler(medium, options); });
    const openvdb::Vec3d lightIjk = xform.worldToIndex(light.light().position);
    // How far (index units) the segment from @a fromIjk to the light runs before it meets one of
    // the medium's meshes: +∞ when it meets none (then it crosses no medium), −1 without meshes.
    const auto clearRun = [&](const openvdb::Vec3d& fromIjk) {
        if (!options.boundary) return -1.0;
        const openvdb::Vec3d world = xform.indexToWorld(fromIjk);
        const openvdb::Vec3d toLight = light.light().position - world;
        const double length = toLight.length();
        const auto hit = length > 0.0 ? options.boundary->intersect(world, toLight / length, 0.0, length) : std::nullopt;
        if (!hit) return std::numeric_limits<double>::infinity();
        return (xform.worldToIndex(world + toLight * (hit->distance / length)) - fromIjk).length();
    };
    // τ from @a from to the light, marched until clear of the surface (clearOfSurface) and read
    // from what @a swept holds there on: inside the medium whatever it holds, outside only the
    // depths of marched voxels (or zeros) that agree to kVacuumSpread. The sweep smears the
    // shadows other parts of the medium cast across vacuum (τ is constant along a ray there, and
    // a blend of upwind depths widens its edges a little at every step); read from blended
    // voxels, a march that left the bunny near a silhouette at dim 256 came out 20-fold dark.
    std::function<openvdb::Vec3f(const openvdb::Vec3d&, const SweepLattice::SweptSoFar&)> marchedDepth;
    // Without meshes (a volume object), the marches cross the vacuum between the lattice's
    // leaves at once (@a leaves): the light reaching the lattice across vacuum is marched to the
    // light from there.
    tbb::enumerable_thread_specific<std::vector<LatticeSpans::Span>> spanLists;
    marchedDepth = [&](const openvdb::Vec3d& from, const SweepLattice::SweptSoFar& swept) {
        bool askedMeshes = false;
        const MarchHandOff handOff = [&](const openvdb::Vec3d& at, double distance, openvdb::Vec3f& depth) {
            if (!surface) return swept.sample(at, depth);
            if (!clearOfSurface(distance)) return false;
            if (distance < 0.0) return swept.sample(at, depth);
            if (swept.sample(at, depth, true, kVacuumSpread)) return true;
            // Outside, where the sweep holds nothing to read (beyond the lattice, or across a
            // shadow's edge): the meshes say whether any medium lies ahead, once a march.
            // None: nothing more to cross. One: the way there is vacuum, and the march goes
            // on from kVacuumMargin voxels before it (the depth from there is the rest's; the
            // bunny at dim 256: 110k band marches had stepped 20-40 voxels across the gap from
            // the body to the ears, 0.23 of the light's 2.3 s).
            if (askedMeshes) return false;
            askedMeshes = true;
            const double run = clearRun(at);
            if (run == std::numeric_limits<double>::infinity()) {
                depth = openvdb::Vec3f(0.0f);
                return true;
            }
            if (run <= kVacuumMargin) return false;
            depth = marchedDepth(at + (lightIjk - at).unit() * (run - kVacuumMargin), swept);
            return true;
        };
        if (leaves) {
            const openvdb::Vec3d toLight = lightIjk - from;
            const double length = toLight.length();
            if (!(length > 0.0)) return openvdb::Vec3f(0.0f);
            return depthThroughLeaves(
                samplers.local(), medium, *leaves, from, toLight / length, length, options.march, depths, handOff, spanLists.local());
        }
        return depths.depthOf(transmittance(samplers.local(), medium, from, lightIjk, options.march, handOff));
    };
    detail::SweepLattice::Depths tau;
    std::vector<std::uint8_t> state;
    lattice.opticalDepthFrom(
        lightIjk, tau, state,
        [&](const openvdb::Coord& ijk, float distance, bool mustMarch, const SweepLattice::SweptSoFar& swept, openvdb::Vec3f& depth) {
            const bool band = surface && inPointBand(distance);
            if (!mustMarch && !band) return false;
            openvdb::Vec3d from = ijk.asVec3d();
            if (!band && distance > 0.0f) {
                // Light reaching the lattice across vacuum (no leaf upwind): it crossed no medium
                // before the first mesh toward the light, and is marched from two voxels before it.
                const double run = clearRun(from);
                if (run == std::numeric_limits<double>::infinity()) {
                    depth = openvdb::Vec3f(0.0f);
                    return true;
                }
                if (run > 2.0) from += (lightIjk - from).unit() * (run - 2.0);
            }
            depth = marchedDepth(from, swept);
            return true;
        },
        float(depths.cutoff));
    const SweepLattice::SweptSoFar done(lattice, tau, &state);

    const double minDistance = 0.5 * medium.voxelSize();
    sizeSums(lattice, phi, flux);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lattice.leafCount()), [&](const tbb::blocked_range<std::size_t>& r) {
        std::vector<LightSample> samples;
        for (std::size_t n = r.begin(); n != r.end(); ++n) {
            for (int v = 0; v < SweepLattice::kLeafVoxels; ++v) {
                const std::size_t i = n * SweepLattice::kLeafVoxels + std::size_t(v);
                const openvdb::Coord ijk = lattice.origin(n).offsetBy(v >> 6, (v >> 3) & 7, v & 7);
                const std::int32_t e = rim.entryOf(i);
                const openvdb::Vec3d point = e >= 0 ? rim.points[std::size_t(e)] : ijk.asVec3d();
                const openvdb::Vec3f depth = e >= 0 ? marchedDepth(point, done) : tau[i];
                const openvdb::Vec3d t = depths.transmittanceOf(depth);
                if (t == openvdb::Vec3d(0.0)) continue;
                const openvdb::Vec3d xWorld = xform.indexToWorld(point);
                light.sample(xWorld, coordKey(ijk), minDistance, samples);
                for (const LightSample& s : samples) {
                    if (!unoccluded(options.occluders, medium, xWorld, s)) continue;
                    const openvdb::Vec3d f = s.fluence * t;
                    phi[i] += openvdb::Vec3f(f);
                    if (flux) (*flux)[i] -= openvdb::Vec3f(greyOf(f) * s.direction);
                }
            }
        }
    });
}

} // namespace vxf::detail
