// vxf — arithmetic with a number on a grid's active values.
#pragma once

#include <openvdb/openvdb.h>

namespace vxf::ops {

enum class ArithmeticOp { Add, Sub, Mul, Div, Pow };

/// v ← v op value, per channel, on the active values of a float or Vec3f grid (voxels and
/// tiles; tiles stay tiles, topology, inactive values and background unchanged).
/// Defined everywhere, never NaN or Inf: x / 0 = 0; pow of a negative x is the odd
/// extension −|x|^p (so pow keeps the sign, as the thesis's artist grids need); results
/// beyond the float range are clamped to ±FLT_MAX. A float grid takes the mean of @a value's
/// channels (or the value itself when they agree). Throws vxf::UsageError for other types.
void arithmetic(openvdb::GridBase& grid, ArithmeticOp op, const openvdb::Vec3d& value);

} // namespace vxf::ops
