// vxf — a brush stroke: paint a value onto the voxels around a path of points.
#pragma once

#include <openvdb/openvdb.h>

#include <cstdint>
#include <vector>

namespace vxf::ops {

enum class PaintMode {
    Mix, ///< v + w·(value − v): toward the value
    Add ///< v + w·value
};

struct PaintOptions
{
    std::vector<openvdb::Vec3d> points; ///< the stroke: the brush's centres (world)
    double radius = 0.1; ///< the brush's radius (world, > 0)
    /// The brush's edge: w(d) = strength·(1 − (d/r)²)^falloff inside the radius, 0 beyond; 0 a
    /// hard brush, 1 a smooth one, larger ones softer.
    double falloff = 1.0;
    double strength = 1.0; ///< [0, 1]
    openvdb::Vec3d value{1.0}; ///< the colour, or a float grid's number (the first channel)
    PaintMode mode = PaintMode::Mix;
};

/// Paint the active voxels (tiles too, voxel by voxel) whose centres lie within the brush of any
/// point of the stroke, each by the largest weight any point gives it (a stroke paints a voxel
/// once, however densely its points lie); voxels outside every brush, and inactive ones, are
/// untouched. Values stay finite. Returns how many voxels it painted. Throws vxf::UsageError
/// for no points, a radius ≤ 0, a negative falloff or a strength outside [0, 1].
std::uint64_t paint(openvdb::Vec3SGrid& grid, const PaintOptions& options);
std::uint64_t paint(openvdb::FloatGrid& grid, const PaintOptions& options);

} // namespace vxf::ops
