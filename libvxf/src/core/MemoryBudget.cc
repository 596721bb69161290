#include <vxf/core/MemoryBudget.h>

#include <vxf/core/Error.h>
#include <vxf/core/GridStats.h>

#include <fmt/format.h>

#include <atomic>
#include <cctype>
#include <cmath>
#include <fstream>
#include <limits>

#include <sys/resource.h>
#include <unistd.h>

namespace vxf {

namespace {

constexpr std::uint64_t kUnset = 0;
std::atomic<std::uint64_t> gBudget{kUnset};
std::atomic<bool> gExplicit{false};

/// A number from a cgroup file, or none for "max" or a file that is not there.
bool readCgroupValue(const std::string& path, std::uint64_t& value)
{
    std::ifstream in(path);
    std::string text;
    if (!(in >> text) || text == "max") return false;
    try {
        value = std::stoull(text);
        return true;
    } catch (const std::exception&) {
        return false;
    }
}

} // namespace

namespace {

/// Field @a field (0: size, 1: resident) of /proc/self/statm, in bytes; 0 if unknown.
std::uint64_t statmBytes(int field)
{
    std::ifstream statm("/proc/self/statm");
    std::uint64_t pages = 0;
    for (int i = 0; i <= field; ++i) {
        if (!(statm >> pages)) return 0;
    }
    return pages * std::uint64_t(::sysconf(_SC_PAGESIZE));
}

} // namespace

std::uint64_t mappedMemory() { return statmBytes(0); }

std::uint64_t residentMemory() { return statmBytes(1); }

std::uint64_t availableMemory()
{
    std::uint64_t available = 0;
    std::ifstream meminfo("/proc/meminfo");
    std::string key;
    std::uint64_t kib = 0;
    std::string unit;
    while (meminfo >> key >> kib) {
        std::getline(meminfo, unit);
        if (key == "MemAvailable:") {
            available = kib * 1024;
            break;
        }
    }
    // The cgroup the process runs in (containers, farm slots), when it is tighter.
    std::ifstream self("/proc/self/cgroup");
    std::string line;
    while (std::getline(self, line)) {
        if (line.rfind("0::", 0) != 0) continue;
        const std::string dir = "/sys/fs/cgroup" + line.substr(3);
        std::uint64_t max = 0, current = 0;
        if (readCgroupValue(dir + "/memory.max", max)) {
            readCgroupValue(dir + "/memory.current", current);
            const std::uint64_t left = max > current ? max - current : 0;
            if (available == 0 || left < available) available = left;
        }
    }
    // An address-space limit (`ulimit -v`, a farm slot's h_vmem): what it leaves beyond what the
    // process has mapped already.
    rlimit limit{};
    const std::uint64_t mapped = mappedMemory();
    if (::getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY && mapped > 0) {
        const std::uint64_t left = std::uint64_t(limit.rlim_cur) > mapped ? std::uint64_t(limit.rlim_cur) - mapped : 1;
        if (available == 0 || left < available) available = left;
    }
    return available;
}

std::uint64_t parseMemorySize(const std::string& text)
{
    std::size_t end = 0;
    double value = 0.0;
    try {
        value = std::stod(text, &end);
    } catch (const std::exception&) {
        end = 0;
    }
    std::string unit = text.substr(end);
    for (auto& c : unit) c = char(std::toupper(static_cast<unsigned char>(c)));
    if (unit.size() >= 2 && unit.compare(unit.size() - 2, 2, "IB") == 0)
        unit.resize(unit.size() - 2);
    else if (!unit.empty() && unit.back() == 'B')
        unit.pop_back();
    double scale = 0.0;
    if (unit.empty())
        scale = 1.0;
    else if (unit == "K")
        scale = 1024.0;
    else if (unit == "M")
        scale = 1024.0 * 1024.0;
    else if (unit == "G")
        scale = 1024.0 * 1024.0 * 1024.0;
    else if (unit == "T")
        scale = 1024.0 * 1024.0 * 1024.0 * 1024.0;
    const double bytes = value * scale;
    if (end == 0 || scale == 0.0 || !std::isfinite(bytes) || bytes < 1.0 || bytes >= 1.8e19) {
        throw UsageError(fmt::format("--max-memory: '{}' is not a memory size (a positive number of bytes, or with K, M, G or "
                                     "T, as 8G)",
            text));
    }
    return std::uint64_t(bytes);
}

void setMemoryBudget(std::uint64_t bytes)
{
    gBudget.store(bytes);
    gExplicit.store(bytes != kUnset);
}

std::uint64_t memoryBudget()
{
    std::uint64_t budget = gBudget.load();
    if (budget == kUnset) {
        // A stage's estimate is of the whole process's peak, what it read and made so far
        // included; what is available now is on top of what the process already holds.
        const std::uint64_t available = availableMemory();
        budget = available == 0 ? std::numeric_limits<std::uint64_t>::max() : available + residentMemory();
        std::uint64_t expected = kUnset;
        gBudget.compare_exchange_strong(expected, budget);
        budget = gBudget.load();
    }
    return budget;
}

MemoryEstimate stageMemory(double fixedBytes, double voxels, double bytesPerVoxel, double pixels, double bytesPerPixel)
{
    MemoryEstimate e;
    e.bytes = fixedBytes + voxels * bytesPerVoxel + pixels * bytesPerPixel;
    e.how = fmt::format("{:.3g} voxels × {:.0f} bytes", voxels, bytesPerVoxel);
    if (pixels > 0.0) e.how += fmt::format(" + {:.3g} pixels × {:.0f} bytes", pixels, bytesPerPixel);
    e.how += fmt::format(" + {}", formatBytes(std::uint64_t(fixedBytes)));
    return e;
}

void requireMemory(const std::string& stage, const MemoryEstimate& estimate)
{
    const std::uint64_t budget = memoryBudget();
    if (!(estimate.bytes <= double(budget))) {
        const bool huge = !(estimate.bytes < 1.8e19);
        throw Error(fmt::format("{} needs about {} at its peak ({}), more than the memory budget of {} ({}); {}", stage,
            huge ? fmt::format("{:.3g} bytes", estimate.bytes) : formatBytes(std::uint64_t(estimate.bytes)), estimate.how,
            formatBytes(budget), gExplicit.load() ? "--max-memory" : "the memory this machine has available",
            gExplicit.load() ? "raise --max-memory, or lower the resolution"
                             : "lower the resolution, free memory, or set --max-memory above the estimate (it is an "
                               "estimate, a little high for large volumes)"));
    }
}

} // namespace vxf
