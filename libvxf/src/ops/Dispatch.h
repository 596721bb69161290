// Internal: run a generic operation on a float or Vec3f grid.
#pragma once

#include <vxf/core/Error.h>

#include <openvdb/openvdb.h>

#include <fmt/format.h>

namespace vxf::ops::detail {

/// Every grid type whose topology operators may read (not point grids).
using TopologyGridTypes = openvdb::NumericGridTypes::Append<openvdb::Vec3GridTypes>::Append<openvdb::BoolGrid, openvdb::MaskGrid>;

/// Call @a f with @a grid as FloatGrid& or Vec3SGrid&; vxf::UsageError for other types.
template<typename GridBaseT, typename F>
decltype(auto) dispatch(GridBaseT& grid, const char* op, F&& f)
{
    using FloatT = std::conditional_t<std::is_const_v<GridBaseT>, const openvdb::FloatGrid, openvdb::FloatGrid>;
    using VecT = std::conditional_t<std::is_const_v<GridBaseT>, const openvdb::Vec3SGrid, openvdb::Vec3SGrid>;
    if (auto* g = dynamic_cast<FloatT*>(&grid)) return f(*g);
    if (auto* g = dynamic_cast<VecT*>(&grid)) return f(*g);
    throw UsageError(fmt::format("{}: grid '{}' holds {} values; it works on float and vec3s grids", op, grid.getName(), grid.valueType()));
}

/// Per-channel access for float and Vec3f values.
inline int channels(float) { return 1; }
inline int channels(const openvdb::Vec3f&) { return 3; }
inline float get(float v, int) { return v; }
inline float get(const openvdb::Vec3f& v, int c) { return v[c]; }
inline float& ref(float& v, int) { return v; }
inline float& ref(openvdb::Vec3f& v, int c) { return v[c]; }

/// A value of the grid's type from an RGB colour (float grids take the first channel
/// when all three agree, else the mean).
template<typename T>
T fromColor(const openvdb::Vec3d& c)
{
    if constexpr (std::is_same_v<T, float>) {
        return (c[0] == c[1] && c[1] == c[2]) ? float(c[0]) : float((c[0] + c[1] + c[2]) / 3.0);
    } else {
        return openvdb::Vec3f(c);
    }
}

/// Clamp to the finite float range (NaN becomes 0): no operator may write NaN or Inf.
inline float finite(double v)
{
    if (std::isnan(v)) return 0.0f;
    constexpr double big = std::numeric_limits<float>::max();
    return float(std::clamp(v, -big, big));
}

} // namespace vxf::ops::detail
