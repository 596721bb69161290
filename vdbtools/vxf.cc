// vxf — art-directable light transport in volumes. `vxf --help` lists the subcommands.
#include "CliSupport.h"
#include "Commands.h"

#include <vxf/core/MemoryBudget.h>
#include <vxf/core/VoxelSet.h>

int main(int argc, char** argv)
{
    using namespace vxf::cli;
    CLI::App app{"vxf: voxelize meshes into OpenVDB voxel sets, light and scatter them, let artists edit the\n"
                 "grids, render the glow. Every intermediate is a multi-grid .vdb file.",
        "vxf"};
    app.set_version_flag("--version", std::string("vxf ") + vxf::versionString());
    app.require_subcommand(1);
    std::vector<std::unique_ptr<Command>> commands;
    commands.push_back(makeVoxelizeCommand(app));
    commands.push_back(makeInfoCommand(app));
    commands.push_back(makeLightCommand(app));
    commands.push_back(makeScatterCommand(app));
    commands.push_back(makeRenderCommand(app));
    commands.push_back(makeRunCommand(app));
    commands.push_back(makeFarmCommand(app));
    commands.push_back(makeBakeCommand(app));
    commands.push_back(makeOpCommand(app));
    commands.push_back(makeGraphCommand(app));
    commands.push_back(makeViewCommand(app));
    commands.push_back(makeDemoCommand(app));
    std::string maxMemory;
    addMaxMemoryOption(app, maxMemory);
    return runMain(app, argc, argv, [&] {
        if (!maxMemory.empty()) vxf::setMemoryBudget(vxf::parseMemorySize(maxMemory));
        for (auto& command : commands) {
            if (command->selected()) command->run();
        }
    });
}
