// `vxf demo`: the main job on the embedded default scene (no downloads).
#include "CliSupport.h"
#include "Commands.h"

#include <filesystem>
#include <iostream>

namespace vxf::cli {

namespace {

class DemoCommand : public Command
{
public:
    explicit DemoCommand(CLI::App& parent)
    {
        mApp = parent.add_subcommand("demo",
            "Run the main job on the embedded default scene: voxelize the procedural candle into OUT/demo.vdb.");
        mApp->add_option("--out", mOut, "Output folder (default: out)");
        mApp->add_option("--dim", mDim, "Voxels along the candle's height (default 128)")->check(CLI::Range(8, 4096));
    }

    void run() override
    {
        std::filesystem::create_directories(mOut);
        VoxelizeRequest request;
        request.mesh = "builtin:candle";
        request.output = (std::filesystem::path(mOut) / "demo.vdb").string();
        request.voxelize.dim = mDim;
        voxelizeToFile(request);
        std::cout << "inspect it with: vxf info " << request.output << "   (or vdb_print -l, Houdini, Blender)\n";
    }

private:
    std::string mOut = "out";
    int mDim = 128;
};

} // namespace

std::unique_ptr<Command> makeDemoCommand(CLI::App& parent) { return std::make_unique<DemoCommand>(parent); }

} // namespace vxf::cli
