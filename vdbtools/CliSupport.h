// vxf — shared plumbing of the command-line tools: error reporting, progress, timing.
#pragma once

#include <vxf/core/Interrupter.h>

#include <CLI/CLI.hpp>

#include <chrono>
#include <functional>
#include <string>
#include <vector>

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
/// A file a command reads or writes, as its user named it: @a label the option or argument
/// ("-o", "--png", "the scene", "object 'ball''s mesh"), @a path the file.
struct NamedFile
{
    std::string label, path;
};

/// Whether @a a and @a b are one file: the same device and inode where both exist (hard links,
/// symbolic links, `./x` and `x`), else the same path once every link of it is resolved.
bool sameFile(const std::string& a, const std::string& b);

/// Refuses, before any work, a command whose output is one of its inputs or another of its
/// outputs (`vxf voxelize m.off -o m.off` turned the mesh into a VDB; `--png x.exr -o x.exr`
/// left a PNG in the EXR): a vxf::UsageError naming both. Empty paths and builtin: meshes are
/// no files.
void refuseOverwrites(const std::vector<NamedFile>& inputs, const std::vector<NamedFile>& outputs);

/// refuseOverwrites for a converter: @a output must not be @a input.
void refuseOutputOverInput(const std::string& input, const std::string& output);

/// Seconds since @a start.
inline double secondsSince(std::chrono::steady_clock::time_point start)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace vxf::cli
