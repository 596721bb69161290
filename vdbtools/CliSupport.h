// vxf — shared plumbing of the command-line tools: error reporting, progress, timing.
#pragma once

#include <vxf/core/Interrupter.h>

#include <CLI/CLI.hpp>

#include <chrono>
#include <functional>
#include <string>

namespace vxf::cli {

/// Run a tool's main: parse with @a app, then call @a run. Prints errors as
/// `<tool>: <subcommand>: <message>` on stderr and returns the exit status: 0 success,
/// 1 runtime error (vxf::Error), 2 usage error (bad arguments, vxf::UsageError),
/// 130 interrupted (Ctrl-C; outputs are written atomically, so nothing half-written stays).
int runMain(CLI::App& app, int argc, char** argv, const std::function<void()>& run = {});

/// Name of the subcommand being run (for messages), "" before parsing.
const std::string& currentCommand();

/// Print a warning as `<tool>: <subcommand>: warning: <message>` on stderr.
void warn(const std::string& message);

/// Progress bar on stderr when it is a terminal (silent otherwise, e.g. in CI or pipes);
/// Ctrl-C makes wasInterrupted() return true so libvxf stops and throws vxf::Interrupted.
class TerminalProgress : public Interrupter
{
public:
    TerminalProgress();
    void start(const char* name = nullptr) override;
    void end() override;
    bool wasInterrupted(int percent = -1) override;

private:
    bool mEnabled;
    std::string mName;
    int mLastPercent = -2;
    std::chrono::steady_clock::time_point mLastDraw;
};

/// Option check: a number above zero (CLI::PositiveNumber's message quotes its range up to
/// 1.8e308); "Value 0 is not a number above zero".
extern const CLI::Validator AboveZero;

/// Option check: a number of zero or more.
extern const CLI::Validator ZeroOrMore;
/// A file to write, checked before any work: its folder exists and it is not a folder itself
/// (a missing folder was reported only after the whole computation).
extern const CLI::Validator OutputFile;

/// `--max-memory SIZE` on every subcommand of @a app that allocates (all but `info`; an
/// operator's own subcommand under `op`), into @a value: the budget each stage checks its
/// estimated peak against (core/MemoryBudget.h).
void addMaxMemoryOption(CLI::App& app, std::string& value);
/// A usage error when @a output is the file @a input (a converter would replace its own input
/// with another format).
void refuseOutputOverInput(const std::string& input, const std::string& output);

/// Seconds since @a start.
inline double secondsSince(std::chrono::steady_clock::time_point start)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace vxf::cli
