// vxf — normalize a grid to [0, 1] and restore it.
#pragma once

#include <openvdb/openvdb.h>

namespace vxf::ops {

/// Grid metadata keys normalize() records and denormalize() reads.
inline constexpr const char* kNormalizeOffsetKey = "vxf:normalize_offset";
inline constexpr const char* kNormalizeScaleKey = "vxf:normalize_scale";

struct NormalizeOptions
{
    bool clampNegatives = false; ///< clamp negative values to 0 first (then the offset is 0)
    /// Scale by a power of two (the smallest ≥ the range), so the round trip is bit-exact:
    /// the largest value lands in (0.5, 1]. Off: the largest value lands on 1 exactly and the
    /// round trip is exact to one unit in the last place.
    bool exact = true;
};

/// v ← (v − offset)/scale on the active values (every channel alike, so hues keep their
/// ratios): offset = the minimum when it is negative, else 0 (zero stays zero, as light
/// values need); scale = maximum − offset (rounded up to a power of two when exact), or 1 for
/// an all-zero or constant grid (never a division by zero). Records offset and scale in the
/// grid's metadata. Each value is chosen, among its nearest floats, as one denormalize() maps
/// back to it where one exists. With offset 0 and exact, the round trip is bit-exact; with a
/// negative offset, values much smaller than the range lose the bits a float of the range
/// cannot hold. Topology unchanged; tiles stay tiles.
void normalize(openvdb::GridBase& grid, const NormalizeOptions& options = {});

/// v ← v·scale + offset from the metadata normalize() recorded, which it then removes.
/// Throws vxf::UsageError naming the grid when the metadata is absent.
void denormalize(openvdb::GridBase& grid);

} // namespace vxf::ops
