// vxf — the source of single scattering, J = σs·φ/4π of a fluence grid, read inside the surface.
#pragma once

#include <vxf/core/GridLookup.h>
#include <vxf/transport/Medium.h>

#include <memory>
#include <optional>

namespace vxf {

/// J = σs·φ/4π of the lights' fluence (the `direct` grid) at any point inside the medium,
/// for marches that read single scattering from the grid instead of marching to the lights.
///
/// A boundary voxel's σs is its volume fraction f of the interior value, and its φ was taken
/// at its centre, which may lie outside the surface. Interpolating σs·φ there and dividing by
/// the interpolated f (Medium::Sampler::interiorScale, as the scatter passes read their
/// sources) is exact for a uniform field. But light entering a thick medium falls by e over a
/// mean free path, a voxel or two: the whole voxel under the surface then outweighs the
/// boundary voxel and pulls the value just inside down, where the camera sees most; and
/// trilinear interpolation of a convex fall-off overshoots between voxels. The thick bunny's
/// single scattering read so came out several percent dark (docs/accuracy-notes.md, "Behind the
/// code: InteriorField").
///
/// With a surface, J is first made a smooth field on the lattice that continues the interior
/// one:
/// - voxels wholly inside (signed distance φs ≤ −½ voxel) keep σs·φ/4π;
/// - voxels whose centre is inside (−½ < φs ≤ 0) hold it divided by f = ½ − φs, the
///   interior value at the centre;
/// - voxels whose centre is outside, within kReach voxels (every voxel a lookup inside the
///   surface reads), hold the interior field continued outward along the surface normal n:
///   from its values at q1 = c − (φs + 1)n and q2 = c − (φs + 2)n, one and two voxels beneath
///   the surface, log-linearly, J(c) = J(q1)·(J(q1)/J(q2))^(φs + 1), the log-slope clamped to
///   ±kMaxLogSlope per voxel (J(q1) where q2 is not inside or a value is not positive). Where
///   J rises outward (the light comes in through this side), c's own fluence with the
///   interior σs bounds it from below: the medium continued could only dim what reaches c.
///   That matters at the terminator, where the path of grazing light to the surface grows as
///   the square root of the depth and the log-linear continuation alone came out low;
/// and J is read by geometric (log-trilinear) interpolation where the eight values of a
/// channel are positive, linear otherwise. Both are exact for light falling off exponentially
/// in any direction.
///
/// The scatter passes' sources and multiple scattering are not read so: the scattered fluence
/// near a lit surface rises inward and is neither exponential nor linear there. Read this way
/// (continued and interpolated log-linearly, or linearly) they moved the thick bunny's image
/// away from the reference (docs/accuracy-notes.md, "Behind the code: InteriorField").
///
/// Without a surface J is read as it is (trilinear): the density's own ramp carries the edge.
/// Immutable after construction and shared by threads; each thread reads through a Sampler.
class InteriorField
{
public:
    /// From fluence @a phi (W/m², Vec3f) on the medium's lattice.
    InteriorField(const Medium& medium, const openvdb::Vec3SGrid& phi);

    /// The lattice values the interpolation reads: J, continued outward near the surface.
    const openvdb::Vec3SGrid& values() const { return *mValues; }

    /// Per-thread lookups.
    class Sampler
    {
    public:
        explicit Sampler(const InteriorField& field);
        /// J at index-space point @a ijk inside the surface (1/world unit, radiance per length).
        openvdb::Vec3d sample(const openvdb::Vec3d& ijk) const;

    private:
        GridLookup<openvdb::Vec3SGrid> mValues;
        std::optional<GridLookup<openvdb::Vec3SGrid>> mLogs;
    };

    /// Voxels whose centre lies this far outside the surface or less are continued (a lookup
    /// at a point inside reads voxels up to √3 voxels away).
    static constexpr double kReach = 2.0;
    /// The steepest continuation, in e-folds per voxel (light entering at a grazing angle
    /// falls faster along the normal than along its path; a poor normal must not blow up).
    static constexpr double kMaxLogSlope = 3.0;

private:
    /// With a surface: the interior values, their continuation outward, then the logarithms.
    void continueOutward(const Medium& medium, const openvdb::Vec3SGrid& phi);

    openvdb::Vec3SGrid::Ptr mValues;
    openvdb::Vec3SGrid::Ptr mLogs; ///< ln J per channel, −∞ where J ≤ 0 (null: no surface)
    std::shared_ptr<const DenseCopy<openvdb::Vec3SGrid>> mValuesDense, mLogsDense;
};

/// J = σs·φ/(4π) per voxel on @a phi's topology, σs the voxel's own (active tiles: at their
/// centre; inactive values too, which trilinear lookups read), named "scatter_source": the source
/// a fluence gives the next scatter pass, and the emission the render reads from the `scatter` grid.
openvdb::Vec3SGrid::Ptr sourceFromFluence(const Medium& medium, const openvdb::Vec3SGrid& phi);

} // namespace vxf
