#include <vxf/core/SphericalFibonacci.h>

#include <cmath>

namespace vxf {

std::vector<openvdb::Vec3d> sphericalFibonacci(int count)
{
    std::vector<openvdb::Vec3d> directions;
    directions.reserve(std::size_t(std::max(count, 0)));
    const double goldenAngle = M_PI * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < count; ++i) {
        const double z = 1.0 - (2.0 * i + 1.0) / count; // centres of equal-area bands
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double phi = goldenAngle * i;
        directions.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
    }
    return directions;
}

} // namespace vxf
