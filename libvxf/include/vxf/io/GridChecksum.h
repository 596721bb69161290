// vxf — a checksum of a grid's data, written beside it so that a damaged file is found on read.
#pragma once

#include <openvdb/Grid.h>

#include <cstdint>
#include <optional>
#include <string>

namespace vxf {

/// Grid metadata key of the checksum vxf writes (16 hex digits).
inline constexpr const char* kChecksumMetaKey = "vxf:checksum";

/// A 64-bit hash of @a grid's data as a file holds it: its background, its active tiles (level,
/// origin, value) and its leaves (origin, active voxels' offsets and values), in the tree's
/// order; @a asHalf hashes float values rounded to 16-bit halves, as a grid saved as half reads
/// back. Independent of the thread count. Float, double, int32, int64, bool and vec3 grids;
/// std::nullopt for other types (points), which carry no checksum. O(active values), parallel
/// over leaves.
std::optional<std::uint64_t> gridChecksum(const openvdb::GridBase& grid, bool asHalf);

/// @a checksum as written in the metadata.
std::string checksumText(std::uint64_t checksum);

} // namespace vxf
