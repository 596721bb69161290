#include <vxf/io/ContentHash.h>

#include <vxf/core/Error.h>
#include <vxf/io/InputFile.h>

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
    requireRegularFile(path);
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(fmt::format("{}: cannot open", path));
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::string fileFingerprint(const std::string& path)
{
    if (path.rfind("builtin:", 0) == 0) return path;
    // Streamed a MiB at a time (the same hash as of the whole): a 600 MB occluder cost 1.14 GB
    // when it was read whole.
    requireRegularFile(path);
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(fmt::format("{}: cannot open", path));
    std::uint64_t h = 0xcbf29ce484222325ull;
    std::string chunk(std::size_t(1) << 20, '\0');
    while (in) {
        in.read(chunk.data(), std::streamsize(chunk.size()));
        const std::streamsize got = in.gcount();
        if (got <= 0) break;
        h = fnv1a(chunk.substr(0, std::size_t(got)), h);
    }
    if (in.bad()) throw Error(fmt::format("{}: cannot read", path));
    return fmt::format("{:016x}", h);
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
