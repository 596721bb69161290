// vxf — evenly spread unit directions (spherical Fibonacci point set).
#pragma once

#include <openvdb/Types.h>

#include <vector>

namespace vxf {

/// @a count unit vectors spread evenly over the sphere (golden-angle spiral, equal-area
/// bands), deterministic. Each stands for a solid angle of 4π/count.
std::vector<openvdb::Vec3d> sphericalFibonacci(int count);

} // namespace vxf
