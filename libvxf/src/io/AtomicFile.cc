#include <vxf/io/AtomicFile.h>

#include <vxf/core/Error.h>

#include <fmt/format.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <system_error>

#include <signal.h>
#include <unistd.h>

namespace vxf {

namespace {

namespace fs = std::filesystem;

/// This machine's name as a temporary's name carries it (a folder shared by a farm's machines
/// holds temporaries of processes this one cannot see).
const std::string& hostTag()
{
    static const std::string tag = [] {
        char name[256] = {};
        if (::gethostname(name, sizeof name - 1) != 0 || name[0] == '\0') return std::string("host");
        std::string out(name);
        for (char& c : out) c = c == '-' || c == '.' || c == '/' ? '_' : c;
        return out;
    }();
    return tag;
}

/// Remove the temporaries of @a target left by processes of this machine that no longer run
/// (killed by SIGKILL, a crash, a power cut: no handler removed them). Another process's live
/// temporary, another machine's, and anything that is not a temporary of this target stay.
void removeStaleTemporaries(const fs::path& dir, const std::string& name)
{
    const std::string prefix = fmt::format(".{}.tmp-{}-", name, hostTag());
    std::error_code ec;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
        const std::string entry = it->path().filename().string();
        if (entry.compare(0, prefix.size(), prefix) != 0) continue;
        const std::string rest = entry.substr(prefix.size()); // PID-N
        const std::size_t dash = rest.find('-');
        if (dash == 0 || dash == std::string::npos || rest.find_first_not_of("0123456789-") != std::string::npos) continue;
        const long pid = std::strtol(rest.substr(0, dash).c_str(), nullptr, 10);
        if (pid <= 0 || pid == long(::getpid())) continue;
        if (::kill(pid_t(pid), 0) != 0 && errno == ESRCH) fs::remove(it->path(), ec);
        ec.clear();
    }
}

} // namespace

void writeAtomically(const std::string& path, const std::function<void(const std::string&)>& write)
{
    static std::atomic<unsigned> counter{0};
    const fs::path target(path);
    if (target.filename().empty()) throw Error(fmt::format("{}: not a file name", path));
    const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) {
        throw Error(fmt::format("{}: cannot write: directory '{}' does not exist", path, dir.string()));
    }
    removeStaleTemporaries(dir, target.filename().string());
    const fs::path tmp = dir / fmt::format(".{}.tmp-{}-{}-{}", target.filename().string(), hostTag(), ::getpid(), counter.fetch_add(1));
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
