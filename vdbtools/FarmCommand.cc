// `vxf farm S.json --frames RANGE (--scheduler ADDR | --local N)`: a shot's frames on a Dask
// cluster. The submitter is Python (farm/vxf_farm, Dask distributed); this command starts it
// through farm/run, which makes its virtual environment on first use.
#include "CliSupport.h"
#include "Commands.h"

#include <vxf/core/Error.h>

#include <fmt/format.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <vector>

#include <unistd.h>

namespace vxf::cli {

namespace {

class FarmCommand : public Command
{
public:
    explicit FarmCommand(CLI::App& parent)
    {
        mApp = parent.add_subcommand("farm",
            "Render a scene's frames (vxf run --frames) on a Dask distributed cluster: --scheduler tcp://HOST:8786 or --local "
            "N workers; progress, retries of failed and lost frames, a summary naming each failed frame (docs/farm.md). "
            "Its arguments go to the Python submitter (farm/vxf_farm; `vxf farm --help` lists them), made ready on first "
            "use in a virtual environment beside the vxf binary (farm-venv; VXF_FARM_VENV moves it).");
        mApp->prefix_command(); // every argument, --help included, is the submitter's
        mApp->set_help_flag();
    }

    void run() override
    {
        const char* overridden = std::getenv("VXF_FARM");
        const std::string script = overridden ? overridden : VXF_FARM_SCRIPT;
        std::error_code error;
        if (!std::filesystem::exists(script, error)) {
            throw Error(fmt::format("{}: the farm's submitter is not there (set VXF_FARM to farm/run of vxf's source tree)", script));
        }
        const std::string self = std::filesystem::read_symlink("/proc/self/exe", error).string();
        if (!self.empty()) ::setenv("VXF_BINARY", self.c_str(), 1); // this vxf, on every worker

        std::vector<std::string> args = mApp->remaining();
        std::vector<char*> argv{const_cast<char*>(script.c_str())};
        for (std::string& a : args) argv.push_back(a.data());
        argv.push_back(nullptr);
        ::execv(script.c_str(), argv.data());
        throw Error(fmt::format("{}: cannot run it: {}", script, std::strerror(errno)));
    }
};

} // namespace

std::unique_ptr<Command> makeFarmCommand(CLI::App& parent) { return std::make_unique<FarmCommand>(parent); }

} // namespace vxf::cli
