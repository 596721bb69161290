#include <vxf/io/AtomicFile.h>

#include <vxf/core/Error.h>

#include <fmt/format.h>

#include <atomic>
#include <filesystem>
#include <system_error>

#include <unistd.h>

namespace vxf {

void writeAtomically(const std::string& path, const std::function<void(const std::string&)>& write)
{
    namespace fs = std::filesystem;
    static std::atomic<unsigned> counter{0};
    const fs::path target(path);
    if (target.filename().empty()) throw Error(fmt::format("{}: not a file name", path));
    const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) {
        throw Error(fmt::format("{}: cannot write: directory '{}' does not exist", path, dir.string()));
    }
    const fs::path tmp = dir / fmt::format(".{}.tmp-{}-{}", target.filename().string(), ::getpid(),
                                   counter.fetch_add(1));
    try {
        write(tmp.string());
        fs::rename(tmp, target);
    } catch (const fs::filesystem_error& e) {
        fs::remove(tmp, ec);
        throw Error(fmt::format("{}: cannot write: {}", path, e.code().message()));
    } catch (...) {
        fs::remove(tmp, ec);
        throw;
    }
}

} // namespace vxf
