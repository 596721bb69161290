// vxf — colour gradients over a voxel set's active voxels.
#pragma once

#include <openvdb/openvdb.h>

#include <vector>

namespace vxf::ops {

struct ColorStop
{
    double t = 0.0; ///< position along the ramp, in [0, 1], increasing
    openvdb::Vec3d color{0.0};
};

enum class GradientKind { Directional, Radial, SurfaceDistance };

struct GradientOptions
{
    GradientKind kind = GradientKind::Directional;
    openvdb::Vec3d from{0.0}, to{0.0, 0.0, 1.0}; ///< directional: t = 0 at from, 1 at to (projected)
    openvdb::Vec3d centre{0.0}; ///< radial: t = (|x − centre| / radius)^falloff
    double radius = 1.0, falloff = 1.0;
    double distance = 1.0; ///< surface distance: t = depth below the surface / distance
    std::vector<ColorStop> stops; ///< the ramp (two or more); linear between stops, clamped at the ends
};

/// The ramp's colour at @a t (linear between stops; t clamped to the first and last stop).
openvdb::Vec3d rampColor(const std::vector<ColorStop>& stops, double t);

/// A Vec3f grid with @a topology's active voxels and tiles (any type; tiles stay tiles,
/// evaluated at their centre) holding the gradient's colour. SurfaceDistance reads the
/// depth from @a surface (a level set: depth = −SDF, so it saturates at the narrow band).
/// Throws vxf::UsageError for fewer than two stops, unsorted stops, a zero-length
/// direction, a non-positive radius or distance, or a missing surface.
openvdb::Vec3SGrid::Ptr gradient(const openvdb::GridBase& topology, const openvdb::FloatGrid* surface, const GradientOptions& options);

} // namespace vxf::ops
