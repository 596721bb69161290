// vxf — a pass's source J = σs·φ/4π read anywhere inside the surface, continued past it.
#pragma once

#include <vxf/core/GridLookup.h>
#include <vxf/light/Medium.h>

#include <algorithm>
#include <memory>

namespace vxf {

/// J of a source made from a pass's fluence, at any point inside the medium, for the scatter
/// passes' gathers (ScatterPassOptions::source).
///
/// Without a surface J is read trilinearly as it is: the density's own ramp carries the edge.
/// With one, J is first made a field on the lattice that continues the interior one, and read
/// by the parabolas through the nearest voxel and its neighbours (QuadraticSampler's arithmetic
/// on the 3³ voxels around the nearest one):
/// - voxels whose centre is inside hold J at their centre with the interior σs (a cut voxel's
///   J is its volume fraction f = ½ − φs of that);
/// - rim voxels (centre outside by less than half a voxel) hold, divided by their f, J at their
///   nearest surface point (Medium::Sampler::mediumPoint, where the passes gather them): the
///   field's values on the surface itself;
/// - every voxel outside within kReach holds the line through J on the surface (its own, or
///   interpolated from the rim voxels around its surface point) and J a voxel beneath it,
///   continued out to its centre; where no rim voxel is near (the surface lies within half a
///   voxel of the centres inside), the line through J one and two voxels beneath it.
/// A linear field is read exactly up to the surface, and the field's curvature between voxels
/// is followed. The fraction-weighted read (σs·φ interpolated, divided by the interpolated f)
/// holds the field flat from the last centre out to the surface, which keeps too much light
/// where it rises inward, as the scattered light does towards a surface it leaves by: in
/// bench/accuracy/slab_model's geometry made a slab 20 mean free paths thick at albedo 0.99,
/// the light through it came out 22% / 10% too bright at 1.3 / 2 voxels per mean free path
/// (this read: −0.3% / −0.2%), the light reflected moved from an rms of 6.0% / 3.1% over the
/// surface's offsets in the lattice to 3.7% / 1.6%. Thick bunny, dim 64 / 96 rungs: 3.79% →
/// 3.64%, 2.33% → 2.07% against Mitsuba.
///
/// Not for the lights' source J0 nor the camera: near a lit surface and at the terminator J0
/// varies within a voxel along the surface as much as across it, and a continuation along the
/// normal misreads it (with every source read so, the thick sphere's shadowed third came out
/// +14% instead of +5% at dim 64); the camera reading the `scatter` grid so took 4% (dim 64)
/// to 8% (dim 32) off the sphere's lit side. Both keep the fraction-weighted read.
///
/// What the lines leave (2026-12-02): near a surface the scattered light does not rise
/// linearly. The first pass from a uniform source is A·φ0·(1 − E2(σt z)/2) at depth z, with an
/// infinite slope at the surface (E2' = −E1), and the converged scattered light has nearly the
/// shape G(z) = 1 − E2(σt z) there: in bench/accuracy/slab_model's fine solution (albedo 0.99,
/// half a mean free path per voxel), (J(z) − J(0)) / (J(h) − J(0)) at a quarter, half and three
/// quarters of the first voxel is 0.42, 0.68, 0.86; G(z)/G(h) gives 0.48, 0.72, 0.88, a line
/// 0.25, 0.5, 0.75. On a flat face (2 voxels per mean free path, albedo 0.99) the first pass is
/// exact to 0.1% at every depth (ScatterTest), but the second, reading the first through this
/// field, came out −6.6%, −3.9%, +1.1%, −1.5% at the surface with the face at 0, ¼, ½, ¾ of its
/// voxel (against a 1-D quadrature of the second pass): each cut of the lattice its own error,
/// the spatial pattern the thick bunny's scattered light still shows. The camera reading
/// `scatter` through this field: rim −6.6%, body −2.1% (dim 96 rung, multiple scattering
/// against Mitsuba) where the fraction-weighted read gives +5.4% and −0.1%. The lead: continue
/// between J on the surface and J a voxel beneath it along G instead of a line, with J on the
/// surface gathered for every cut voxel (not only the rim's), in the passes and the camera alike.
/// Immutable after construction and shared by threads; each thread reads through a Sampler.
class SourceField
{
public:
    /// From @a source, J per voxel on the medium's lattice (sourceFromFluence).
    SourceField(const Medium& medium, const openvdb::Vec3SGrid& source);

    /// Per-thread lookups.
    class Sampler
    {
    public:
        explicit Sampler(const SourceField& field);
        /// J at index-space point @a ijk inside the surface (1/world unit, radiance per length).
        openvdb::Vec3d sample(const openvdb::Vec3d& ijk) const
        {
            if (!mQuadratic) return openvdb::Vec3d(mValues.sampleTrilinear(ijk));
            // The parabolas through the nearest voxel and its neighbours (QuadraticSampler's
            // arithmetic; its own stencil starts at the voxel below and so leans a parabola on
            // a voxel up to two away, a one-sided fit that doubled the slab model's error).
            const openvdb::Coord nearest = openvdb::Coord::round(ijk);
            openvdb::Vec3f data[3][3][3];
            mValues.getBlock(nearest.offsetBy(-1), data);
            openvdb::Vec3d j(openvdb::tools::QuadraticSampler::triquadraticInterpolation(data, ijk - nearest.asVec3d()));
            // A parabola overshoots below zero next to a steep fall-off (σt of 1e6 per voxel),
            // and a continued line may cross zero outside: a source without negative values
            // reads none.
            for (int ch = 0; ch < 3; ++ch) {
                if (mNonNegative[ch]) j[ch] = std::max(j[ch], 0.0);
            }
            return j;
        }

    private:
        GridLookup<openvdb::Vec3SGrid> mValues;
        bool mQuadratic;
        bool mNonNegative[3];
    };

    /// Voxels whose centre lies this far outside the surface or less are continued: a
    /// triquadratic lookup at a point inside reads voxels up to 1.5 voxels away along each axis.
    static constexpr double kReach = 2.6;

private:
    openvdb::Vec3SGrid::Ptr mValues;
    std::shared_ptr<const DenseCopy<openvdb::Vec3SGrid>> mValuesDense;
    bool mQuadratic = false;
    bool mNonNegative[3] = {true, true, true}; ///< per channel: no value of the source below zero
};

} // namespace vxf
