// vxf — a uniformly random rotation from three numbers in [0, 1) (Shoemake's quaternions).
#pragma once

#include <openvdb/Types.h> // openvdb::Mat3d

#include <cmath>

namespace vxf {

/// The rotation of the unit quaternion Shoemake's method makes from @a u0, @a u1, @a u2 in
/// [0, 1): uniformly distributed over rotations when they are. Deterministic.
inline openvdb::Mat3d randomRotation(double u0, double u1, double u2)
{
    const double a = std::sqrt(1.0 - u0), b = std::sqrt(u0);
    const double w = a * std::sin(2 * M_PI * u1), x = a * std::cos(2 * M_PI * u1);
    const double y = b * std::sin(2 * M_PI * u2), z = b * std::cos(2 * M_PI * u2);
    return openvdb::Mat3d(1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w), 2 * (x * y + z * w), 1 - 2 * (x * x + z * z),
        2 * (y * z - x * w), 2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y));
}

} // namespace vxf
