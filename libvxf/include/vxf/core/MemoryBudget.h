// vxf — the memory a command may use, and each stage's estimate of its peak against it.
#pragma once

#include <cstdint>
#include <string>

namespace vxf {

/// The bytes this machine can give a process now: /proc/meminfo's MemAvailable, or less where
/// the process's cgroup (v2 memory.max less memory.current) or its address-space limit
/// (RLIMIT_AS, `ulimit -v`, less what it has mapped) leaves less; 0 if none can be read.
std::uint64_t availableMemory();

/// The bytes of address space the process has mapped (/proc/self/statm's size); 0 if unknown.
std::uint64_t mappedMemory();

/// The bytes of the process in memory now (/proc/self/statm's resident); 0 if unknown.
std::uint64_t residentMemory();

/// "8G", "512M", "1.5T", "64K" (binary units: G = 2^30 bytes; a trailing "B" or "iB" is
/// accepted) or a plain number of bytes. Throws vxf::UsageError naming @a text.
std::uint64_t parseMemorySize(const std::string& text);

/// The budget every stage checks its estimated peak against (`--max-memory`): the most the
/// whole process may hold. Until set (or after setMemoryBudget(0)), what was available when
/// first asked plus what the process held then (availableMemory() + residentMemory(): a stage
/// asks after it has read its input, and its estimate counts that input; unbounded if nothing
/// is known).
void setMemoryBudget(std::uint64_t bytes);
std::uint64_t memoryBudget();

/// What a stage holds whatever its size: the process, its libraries and thread pools, small
/// tables (about 60 MiB measured at dim 32; rounded up).
inline constexpr double kStageFixedBytes = 100.0 * 1024 * 1024;

/// A stage's peak estimate: a fixed part (the process, libraries, small tables) plus what it
/// holds per voxel and per pixel, measured on the bunny (docs/reports/performance.md, bench/pipeline).
struct MemoryEstimate
{
    double bytes = 0.0;
    std::string how; ///< what the estimate counts, for the message
};
MemoryEstimate stageMemory(double fixedBytes, double voxels, double bytesPerVoxel, double pixels = 0.0, double bytesPerPixel = 0.0);

/// A grid as a stage's estimate counts it: its tree's bytes in memory, and the bytes of the dense
/// copy its lookups would make of its active box (GridLookup.h; 0 where the box passes the
/// copies' limit and none is made). Known before a file is read (its grids' metadata: GridStats.h
/// footprintOf) as after.
struct GridFootprint
{
    std::string name;
    double bytes = 0.0, denseBytes = 0.0;
};

/// Throws vxf::Error when @a estimate passes the budget, before the stage allocates:
/// "STAGE needs about 9.1 GiB at its peak (…), more than the memory budget of 8 GiB (…)".
void requireMemory(const std::string& stage, const MemoryEstimate& estimate);

} // namespace vxf
