// vxf — the light stage's sweeps (private to light/): directional and environment lights by one
// optical-depth sweep over the medium per direction, point and spot lights by one sweep around
// the light, the surface's rim marched along the directions that graze it. DirectLight.cc runs
// them for computeDirectLight (vxf/light/DirectLight.h says what each light type takes).
#pragma once

#include <vxf/light/DirectLight.h>
#include <vxf/light/LightSampler.h>
#include <vxf/core/RayScene.h>

#include "transport/lattice/SweepLattice.h"
#include "LeafBlocks.h"

#include <openvdb/tools/RayIntersector.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

namespace vxf::detail {

/// The rim's light (voxels whose centre lies outside the surface within half a voxel; their
/// light is taken on the surface beneath) comes from the sweep along directions that meet the
/// surface at least this steeply (|cosine| to its normal), and is marched along the others.
/// Steeply, the centre and the surface point see the light along neighbouring rays that cross
/// no surface between them: from outside, through vacuum; from inside, leaving the medium at
/// the surface the step to the centre crosses. Grazing, the two rays part where the surface
/// curves away (the terminator), and only a march from the surface point is right.
inline constexpr double kRimSweptCosine = 0.45;

/// The rim: its voxels (per-voxel indices, ascending), their medium points and the surface's
/// outward unit normals there (index space), and per lattice leaf where its voxels start in
/// them (`leafStart`, one more than the leaves; empty without a surface: no voxel is in the rim).
/// A voxel's entry is found in its leaf's few, not held per voxel (4 bytes a voxel: 0.9 GB for
/// the bunny at dim 1024).
struct Rim
{
    std::vector<std::size_t> leafStart;
    /// Voxel @a voxel's entry in `voxels`, `points` and `normals`, or −1 for a voxel not in the rim.
    std::int32_t entryOf(std::size_t voxel) const
    {
        if (leafStart.empty()) return -1;
        const std::size_t leaf = voxel / SweepLattice::kLeafVoxels;
        const auto first = voxels.begin() + std::ptrdiff_t(leafStart[leaf]), last = voxels.begin() + std::ptrdiff_t(leafStart[leaf + 1]);
        const auto at = std::lower_bound(first, last, voxel);
        return at != last && *at == voxel ? std::int32_t(at - voxels.begin()) : -1;
    }
    std::vector<std::size_t> voxels;
    std::vector<openvdb::Vec3d> points, normals;
    bool grazing(std::int32_t e, const openvdb::Vec3d& towardLight) const
    {
        return std::abs(normals[std::size_t(e)].dot(towardLight)) < kRimSweptCosine;
    }
};

/// Whether none of @a occluders (may be null) blocks sample @a s seen from world point @a x.
inline bool unoccluded(const RayScene* occluders, const Medium& medium, const openvdb::Vec3d& x, const LightSample& s)
{
    return !occluders || !occluders->occluded(x, s.direction, 1e-4 * medium.voxelSize(), s.distance);
}

/// Where rays cross a lattice's leaves: without the medium's meshes (a volume object), the
/// only way to tell the vacuum a ray from the lattice toward a light crosses. The medium lies
/// in the leaves (their voxels are its active ones and the voxel around them: every point whose
/// trilinear reads meet it), so a march need step through their spans only. OpenVDB's
/// hierarchical DDA over a mask of the leaves (VolumeRayIntersector at leaf level).
class LatticeSpans
{
public:
    using Ray = openvdb::math::Ray<double>;
    using Span = Ray::TimeSpan;

    explicit LatticeSpans(const SweepLattice& lattice)
        : mMask(openvdb::BoolGrid::create(false))
    {
        for (std::size_t n = 0; n < lattice.leafCount(); ++n) mMask->tree().touchLeaf(lattice.origin(n))->setValuesOn();
        if (mMask->empty()) return;
        mIntersector = std::make_unique<Intersector>(*mMask);
        mMask->tree().clear(); // the intersector holds its own copy of the topology
    }

    /// The spans (index units along the unit index-space @a direction from @a fromIjk) where the
    /// ray lies in a leaf, each widened by @a margin either side and merged where they meet, in
    /// order along the ray; none where it meets no leaf.
    void along(const openvdb::Vec3d& fromIjk, const openvdb::Vec3d& direction, double margin, std::vector<Span>& spans) const
    {
        spans.clear();
        if (!mIntersector) return;
        Intersector rays(*mIntersector); // a shallow copy: its own ray and accessor
        // OpenVDB's index rays take voxel v as the cube [v, v + 1); vxf's voxel centres lie on v.
        if (!rays.setIndexRay(Ray(fromIjk + openvdb::Vec3d(0.5), direction, 0.0))) return;
        rays.hits(spans);
        std::size_t kept = 0; // widened and merged in place
        for (Span span : spans) {
            span.set(std::max(0.0, span.t0 - margin), span.t1 + margin);
            if (kept > 0 && span.t0 <= spans[kept - 1].t1)
                spans[kept - 1].t1 = std::max(spans[kept - 1].t1, span.t1);
            else
                spans[kept++] = span;
        }
        spans.resize(kept);
    }

private:
    using Intersector = openvdb::tools::VolumeRayIntersector<openvdb::BoolGrid, 0>;
    openvdb::BoolGrid::Ptr mMask;
    std::unique_ptr<Intersector> mIntersector;
};

/// The rim of @a lattice's voxels (centres outside the surface within half a voxel).
Rim rimOf(const SweepLattice& lattice, const Medium& medium);
/// The light stage's medium sampler (crossings snapped to the media's meshes).
Medium::Sampler lightStageSampler(const Medium& medium, const DirectLightOptions& options);
/// Directional and environment lights: one optical-depth sweep per direction.
bool sweepable(const Light& light);
/// A sweepable light's fluence at every lattice voxel added to @a fluence (its first moment to
/// @a flux when given); each is made zero over the lattice's leaves first when empty. Lights add into one sum
/// rather than each making its own array: 12 bytes a lattice voxel and light, 24 with a flux.
/// @a spans: the lattice's, made once for its lights, for marches without the medium's meshes
/// (null with them, which tell the vacuum themselves).
void sweepLight(const LightSampler& light, const SweepLattice& lattice, const Medium& medium, const Rim& rim, const LatticeSpans* spans,
    const DirectLightOptions& options, LeafBlocks<openvdb::Vec3f>& fluence, LeafBlocks<openvdb::Vec3f>* flux);
/// Point and spot lights: one sweep around the light.
bool sweepableFromPoint(const Light& light);
/// A point or spot light's fluence at every lattice voxel, the voxels near the surface marched,
/// added to @a fluence and @a flux as sweepLight does.
void sweepPointLight(const LightSampler& light, const SweepLattice& lattice, const Medium& medium, const Rim& rim,
    const LatticeSpans* spans, const DirectLightOptions& options, LeafBlocks<openvdb::Vec3f>& fluence, LeafBlocks<openvdb::Vec3f>* flux);

} // namespace vxf::detail
