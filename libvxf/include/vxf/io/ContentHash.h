// vxf — stable content hashes for caches: the same bytes give the same hash on every machine.
#pragma once

#include <cstdint>
#include <string>

namespace vxf {

/// FNV-1a, 64 bit, of @a bytes (continuing from @a seed): stable across runs, builds and
/// machines (std::hash is not).
std::uint64_t fnv1a(const std::string& bytes, std::uint64_t seed = 0xcbf29ce484222325ull);

/// The whole file at @a path as bytes; vxf::Error naming the file when it cannot be read.
std::string readFileBytes(const std::string& path);

/// fnv1a of @a text as 16 hex digits.
std::string hashHex(const std::string& text);

/// The hash of a file's bytes as 16 hex digits; built-in names (builtin:…) stand for
/// themselves. Throws vxf::Error naming the file when it cannot be read.
std::string fileFingerprint(const std::string& path);

/// The hash of the running program's executable (/proc/self/exe) as 16 hex digits, computed
/// once; the version string where it cannot be read. Part of every cache key (`vxf run`'s
/// stages, `vxf graph`'s nodes), so a rebuilt or upgraded vxf does not take results an older
/// one computed with other algorithms.
const std::string& programFingerprint();

} // namespace vxf
