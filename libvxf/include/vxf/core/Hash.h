// vxf — deterministic hashing for sample jitter (results never depend on threads or runs).
#pragma once

#include <openvdb/Types.h>

#include <cstdint>

namespace vxf {

/// SplitMix64's finalizer: a well-mixed 64-bit hash of @a x.
inline std::uint64_t mixBits(std::uint64_t x)
{
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

/// A key for a voxel coordinate.
inline std::uint64_t coordKey(const openvdb::Coord& c)
{
    return mixBits(
        std::uint64_t(std::uint32_t(c[0])) ^ mixBits(std::uint64_t(std::uint32_t(c[1])) ^ mixBits(std::uint64_t(std::uint32_t(c[2])))));
}

/// coordKey as a hash function object, for unordered containers keyed by coordinates.
struct CoordHash
{
    std::size_t operator()(const openvdb::Coord& c) const { return std::size_t(coordKey(c)); }
};

/// A number in [0, 1) determined by (@a key, @a index, @a salt).
inline double unitHash(std::uint64_t key, std::uint64_t index, std::uint64_t salt = 0)
{
    return double(mixBits(key ^ mixBits(index ^ mixBits(salt))) >> 11) * (1.0 / 9007199254740992.0);
}

} // namespace vxf
