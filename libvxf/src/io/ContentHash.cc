#include <vxf/io/ContentHash.h>

#include <vxf/core/Error.h>

#include <fmt/format.h>

#include <fstream>
#include <iterator>

namespace vxf {

std::uint64_t fnv1a(const std::string& bytes, std::uint64_t h)
{
    for (unsigned char c : bytes) {
        h ^= c;
        h *= 0x100000001b3ull;
    }
    return h;
}

std::string hashHex(const std::string& text) { return fmt::format("{:016x}", fnv1a(text)); }

std::string readFileBytes(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(fmt::format("{}: cannot open", path));
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::string fileFingerprint(const std::string& path)
{
    if (path.rfind("builtin:", 0) == 0) return path;
    return hashHex(readFileBytes(path));
}

const std::string& programFingerprint()
{
    static const std::string fingerprint = [] {
        try {
            return fileFingerprint("/proc/self/exe");
        } catch (const Error&) {
            return std::string("version " VXF_VERSION_STRING);
        }
    }();
    return fingerprint;
}

} // namespace vxf
