#include "CliSupport.h"

#include <vxf/core/Error.h>

#include <openvdb/Exceptions.h>

#include <fmt/format.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <mutex>

#include <unistd.h>

namespace vxf::cli {

namespace {
/// A validator of numbers that satisfy @a ok, whose failure reads "Value X is not @a what".
CLI::Validator numberThat(const std::function<bool(double)>& ok, const std::string& what, const std::string& name)
{
    return CLI::Validator(
        [ok, what](std::string& text) -> std::string {
            double value = 0.0;
            if (!CLI::detail::lexical_cast(text, value) || !std::isfinite(value) || !ok(value)) {
                return "Value " + text + " is not " + what;
            }
            return {};
        },
        name);
}
} // namespace

const CLI::Validator AboveZero = numberThat([](double v) { return v > 0.0; }, "a number above zero", "POSITIVE");
const CLI::Validator ZeroOrMore = numberThat([](double v) { return v >= 0.0; }, "a number of zero or more", "NONNEGATIVE");

const CLI::Validator OutputFile(
    [](std::string& text) -> std::string {
        namespace fs = std::filesystem;
        const fs::path path(text);
        std::error_code error;
        if (text.empty() || path.filename().empty()) return "'" + text + "' names no file";
        if (fs::is_directory(path, error)) return "'" + text + "' is a folder, not a file to write";
        const fs::path folder = path.parent_path().empty() ? fs::path(".") : path.parent_path();
        if (!fs::is_directory(folder, error)) return "cannot write '" + text + "': folder '" + folder.string() + "' does not exist";
        return {};
    },
    "FILE");

bool sameFile(const std::string& a, const std::string& b)
{
    namespace fs = std::filesystem;
    std::error_code error;
    if (fs::equivalent(a, b, error)) return true;
    const fs::path first = fs::weakly_canonical(fs::absolute(a, error), error);
    const fs::path second = fs::weakly_canonical(fs::absolute(b, error), error);
    return !error && first == second;
}

void refuseOverwrites(const std::vector<NamedFile>& inputs, const std::vector<NamedFile>& outputs)
{
    const auto isFile = [](const NamedFile& f) { return !f.path.empty() && f.path.rfind("builtin:", 0) != 0; };
    for (std::size_t o = 0; o < outputs.size(); ++o) {
        const NamedFile& out = outputs[o];
        if (!isFile(out)) continue;
        for (const NamedFile& in : inputs) {
            if (isFile(in) && sameFile(in.path, out.path)) {
                throw UsageError(fmt::format("{} {} is {} {}: it would be replaced by what this command writes; write the output "
                                             "elsewhere",
                    out.label, out.path, in.label, in.path));
            }
        }
        for (std::size_t other = 0; other < o; ++other) {
            if (isFile(outputs[other]) && sameFile(outputs[other].path, out.path)) {
                throw UsageError(fmt::format("{} {} is also {} {}: give each output a file of its own", out.label, out.path,
                    outputs[other].label, outputs[other].path));
            }
        }
    }
}

void refuseOutputOverInput(const std::string& input, const std::string& output)
{
    refuseOverwrites({{"the input", input}}, {{"the output", output}});
}

namespace {
std::string gTool = "vxf";
std::string gCommand;
std::atomic<bool> gInterrupted{false};
std::atomic<int> gSignal{SIGINT}; ///< the first stopping signal received
std::mutex gDrawMutex;

/// SIGINT (Ctrl-C), SIGTERM (kill, timeout, schedulers and farms) and SIGHUP (a closed
/// terminal or session) all stop the work between steps: the command reports "interrupted",
/// writes no output and removes its temporaries. A second one leaves at once.
extern "C" void onStopSignal(int signal)
{
    if (gInterrupted.exchange(true)) std::_Exit(128 + signal);
    gSignal.store(signal);
}

/// Address space held back for the way out of an allocation that fails: under a memory limit
/// (`ulimit -v`, a farm slot's h_vmem) the unwinding itself allocates (OpenVDB's Tree::clear in
/// the destructors of meshToVolume's thread-local trees), and a second std::bad_alloc there,
/// inside a destructor, ends the process in std::terminate. The first failure frees this block
/// and throws; the unwinding then finds room, and the command reports "out of memory" (the
/// sphere at dim 8192 under `ulimit -v 3000000`: 64 MiB was not enough, the other threads
/// still voxelizing took it; 512 MiB is).
constexpr std::size_t kUnwindReserveBytes = std::size_t(512) << 20;
std::atomic<void*> gUnwindReserve{nullptr};

void releaseUnwindReserve()
{
    std::free(gUnwindReserve.exchange(nullptr));
    std::set_new_handler(nullptr);
    throw std::bad_alloc();
}

void printError(const std::string& message)
{
    std::string prefix = gTool + ": ";
    if (!gCommand.empty() && gCommand != gTool) prefix += gCommand + ": ";
    std::cerr << prefix << message << std::endl;
}
} // namespace

const std::string& currentCommand() { return gCommand; }

void addMaxMemoryOption(CLI::App& app, std::string& value)
{
    for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
        if (sub->get_name() == "info") continue;
        if (!sub->get_subcommands([](CLI::App*) { return true; }).empty()) {
            addMaxMemoryOption(*sub, value);
            continue;
        }
        sub->add_option("--max-memory", value,
            "The memory this command may use (e.g. 8G, 512M); each stage estimates its peak before it allocates and stops "
            "with the estimate above it. Default: the memory this machine has available");
    }
}

void warn(const std::string& message) { printError("warning: " + message); }

int runMain(CLI::App& app, int argc, char** argv, const std::function<void()>& run)
{
    gTool = app.get_name();
    gCommand = gTool;
    for (const int stop : {SIGINT, SIGTERM, SIGHUP}) std::signal(stop, onStopSignal);
    // Past a file size limit (ulimit -f) a write fails with EFBIG, reported as an error with
    // the previous output intact, instead of killing the process beside a half-written file.
    std::signal(SIGXFSZ, SIG_IGN);
    gUnwindReserve.store(std::malloc(kUnwindReserveBytes)); // never touched: address space, not memory
    std::set_new_handler(releaseUnwindReserve);
    try {
        try {
            app.parse(argc, argv);
        } catch (const CLI::Success& e) {
            return app.exit(e);
        } catch (const CLI::ParseError& e) {
            for (const CLI::App* sub : app.get_subcommands()) gCommand = sub->get_name();
            printError(e.what());
            std::cerr << "run '" << gTool << (gCommand != gTool ? " " + gCommand : std::string()) << " --help' for usage\n";
            return 2;
        }
        for (const CLI::App* sub : app.get_subcommands()) gCommand = sub->get_name();
        if (run) run();
        return 0;
    } catch (const CLI::ParseError& e) { // raised from a subcommand callback
        printError(e.what());
        return 2;
    } catch (const UsageError& e) {
        printError(e.what());
        return 2;
    } catch (const Interrupted&) {
        const int signal = gSignal.load();
        printError(fmt::format("interrupted ({}); no output written",
            signal == SIGTERM      ? "SIGTERM"
                : signal == SIGHUP ? "SIGHUP"
                                   : "SIGINT"));
        return 128 + signal;
    } catch (const Error& e) {
        printError(e.what());
        return 1;
    } catch (const openvdb::Exception& e) {
        printError(fmt::format("OpenVDB: {}", e.what()));
        return 1;
    } catch (const std::bad_alloc&) {
        printError("out of memory: an allocation failed beyond what the stage's estimate foresaw (lower the resolution, or "
                   "give the process more memory)");
        return 1;
    } catch (const std::exception& e) {
        printError(e.what());
        return 1;
    }
}

TerminalProgress::TerminalProgress()
    : mEnabled(::isatty(STDERR_FILENO) == 1 && !std::getenv("CI"))
{
}

void TerminalProgress::start(const char* name)
{
    std::lock_guard<std::mutex> lock(gDrawMutex);
    mName = name ? name : "";
    mLastPercent = -2;
    if (mEnabled) std::fprintf(stderr, "\r\033[K  %s…", mName.c_str());
}

void TerminalProgress::end()
{
    std::lock_guard<std::mutex> lock(gDrawMutex);
    if (mEnabled) std::fprintf(stderr, "\r\033[K");
}

bool TerminalProgress::wasInterrupted(int percent)
{
    if (mEnabled && percent >= 0 && percent != mLastPercent) {
        std::unique_lock<std::mutex> lock(gDrawMutex, std::try_to_lock);
        const auto now = std::chrono::steady_clock::now();
        if (lock.owns_lock() && now - mLastDraw > std::chrono::milliseconds(100)) {
            mLastDraw = now;
            mLastPercent = percent;
            const int filled = std::max(0, std::min(30, percent * 30 / 100));
            std::fprintf(stderr, "\r\033[K  %-28s [%s%s] %3d%%", mName.c_str(), std::string(std::size_t(filled), '#').c_str(),
                std::string(std::size_t(30 - filled), '.').c_str(), percent);
        }
    }
    return gInterrupted.load();
}

} // namespace vxf::cli
