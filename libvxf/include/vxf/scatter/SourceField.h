// vxf — a pass's source J = σs·φ/4π read anywhere inside the surface, continued past it.
#pragma once

#include <vxf/core/GridLookup.h>
#include <vxf/transport/Medium.h>

#include <algorithm>
#include <memory>
#include <optional>
#include <vector>

namespace vxf {

/// J of a source made from a pass's fluence, at any point inside the medium: the scatter
/// passes' gathers (ScatterPassOptions::source) and the camera's read of the `scatter` grid.
///
/// Without a surface J is read trilinearly as it is: the density's own ramp carries the edge.
/// With one, the scattered light is taken to rise beneath the surface as it does from a
/// uniform source, with an infinite slope on the surface itself: a pass's light at depth z
/// (voxels) is A·φ0·(1 − E2(σt z)/2) there (E2' = −E1), which no parabola between voxel
/// centres follows. Near the surface the camera reads J from layers (Near::Layers), the passes
/// from the lattice those layers fill there (Near::Lattice); deeper, both from the lattice.
/// - The skin's voxels (centre within half a voxel of the surface, either side) hold J on the
///   surface, at their nearest surface point, where the passes gather them
///   (Medium::Sampler::skinPoint); divided by their volume fraction f = ½ − φs.
/// - Every voxel within kLayerInside inside (Near::Lattice: half a voxel, the skin) / kReach
///   outside of the surface has a Layer: along the normal at its surface point J(z) = Js + slope·z
///   + rise·(1 − E2(σt·dx·z)), through J on the surface (the skin around the point) and J at
///   kAnchorA and kAnchorB beneath it over the voxels half a voxel deep or more, each anchor
///   matched as the lattice holds it (the shapes averaged over the same corners at their own
///   depths, not taken at the point).
/// - Near::Layers: a point shallower than kModelDepth reads the layers around it (their
///   coefficients weighted trilinearly), one deeper than kModelDepth + kBlendWidth the lattice by
///   the parabolas through the nearest voxel and its neighbours (QuadraticSampler's arithmetic on
///   the 3³ voxels around the nearest one), linearly blended between. In the lattice a skin voxel
///   inside holds its layer at its centre, one outside (and every voxel outside within kReach) the
///   line through J on the surface and J a voxel beneath it, continued outward.
/// A linear field is read as it is (z), and so is the first pass from a uniform source (the
/// rise). The layers pay through the camera; the passes read the lattice (Near::Lattice), where
/// the layers gained nothing. Not for the lights' source J0, which varies along the surface
/// within a voxel as much as across it: it keeps the fraction-weighted read. (Measured:
/// docs/accuracy-notes.md, "Behind the code: SourceField".)
/// Immutable after construction and shared by threads; each thread reads through a Sampler.
class SourceField
{
public:
    /// How points near the surface are read (with a surface; without one, trilinear either way).
    enum class Near {
        /// The layers to kModelDepth, blended into the lattice over kBlendWidth: the camera's
        /// read of the `scatter` grid (Render), where the eye sees the first voxel's light.
        Layers,
        /// The lattice alone (its skin and outside voxels filled from the layers as above): the
        /// passes' gathers, closer to the reference there than the layers and no distance read
        /// per sample (docs/accuracy-notes.md, "Behind the code: SourceField").
        Lattice
    };

    /// From @a source, J per voxel on the medium's lattice (sourceFromFluence).
    SourceField(const Medium& medium, const openvdb::Vec3SGrid& source, Near near = Near::Layers);

    /// J near the surface along the normal at a surface point, z voxels deep:
    /// J(z) = surface + slope·z + rise·(1 − E2(τz)), τ = σt·dx per channel.
    struct Layer
    {
        openvdb::Vec3f surface{0.0f}, slope{0.0f}, rise{0.0f}, tau{0.0f};
        float depth = 0.0f; ///< the voxel's own depth (voxels, negative outside)
    };

    /// Per-thread lookups.
    class Sampler
    {
    public:
        explicit Sampler(const SourceField& field);
        /// J at index-space point @a ijk inside the surface (1/world unit, radiance per length).
        openvdb::Vec3d sample(const openvdb::Vec3d& ijk) const;

    private:
        openvdb::Vec3d lattice(const openvdb::Vec3d& ijk) const;
        openvdb::Vec3d nearSurface(const openvdb::Vec3d& ijk) const; ///< Near::Layers
        const SourceField& mField;
        GridLookup<openvdb::Vec3SGrid> mValues;
        std::optional<GridLookup<openvdb::Int32Grid>> mLayerIndex;
        /// The depth of a point near the surface (Near::Layers only; its lookups' caches change).
        mutable std::optional<Medium::Sampler> mMedium;
    };

    /// Voxels whose centre lies this far outside the surface or less are continued and carry a
    /// Layer: a point within kModelDepth + kBlendWidth of the surface reads layers up to 0.87
    /// voxels away, and the lattice from 1.5 voxels deep reaches no farther out than 0.73.
    static constexpr double kReach = 1.8;
    /// Voxels: the layer model's anchors beneath the surface point (masked to voxels whose
    /// centre lies half a voxel inside or deeper, so that their trilinear reads hold no skin).
    static constexpr double kAnchorA = 1.0, kAnchorB = 2.0;
    /// Voxels of depth: points shallower than kModelDepth read the layer model alone, deeper
    /// than kModelDepth + kBlendWidth the lattice alone, linearly blended between.
    static constexpr double kModelDepth = 1.5, kBlendWidth = 1.0;
    /// Voxels whose centre lies this deep or less carry a Layer (and up to kReach outside).
    static constexpr double kLayerInside = 3.0;

private:
    const Medium& mMedium;
    openvdb::Vec3SGrid::Ptr mValues;
    std::shared_ptr<const DenseCopy<openvdb::Vec3SGrid>> mValuesDense;
    openvdb::Int32Grid::Ptr mLayerIndex; ///< index into mLayers, −1 (background) for none; null for Near::Lattice
    std::shared_ptr<const DenseCopy<openvdb::Int32Grid>> mLayerIndexDense;
    std::vector<Layer> mLayers;
    bool mQuadratic = false;
    bool mNonNegative[3] = {true, true, true}; ///< per channel: no value of the source below zero
};

} // namespace vxf
