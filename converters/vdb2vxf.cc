// vdb2vxf IN.vdb OUT.vxf [--grid NAME ...]: OpenVDB grids → text VXF (schemas/vxf-text.md).
#include "CliSupport.h"

#include <vxf/io/VoxelSetFile.h>
#include <vxf/io/VxfText.h>

int main(int argc, char** argv)
{
    using namespace vxf;
    CLI::App app{"Convert grids of a .vdb file to text VXF (schemas/vxf-text.md): one line per voxel with its\n"
                 "index, active flag and the values of each grid. Lossless for float, vec3 and bool grids.",
        "vdb2vxf"};
    std::string input, output;
    VxfWriteOptions options;
    app.add_option("input", input, ".vdb file")->required();
    app.add_option("output", output, "Output text VXF file")->required()->check(cli::OutputFile);
    app.add_option("--grid", options.grids, "Grid to write as columns, in order (repeatable; default: all that fit)");
    return cli::runMain(app, argc, argv, [&] {
        cli::refuseOutputOverInput(input, output);
        cli::TerminalProgress progress;
        const VoxelSet set = readVoxelSet(input);
        for (const auto& warning : writeVxfText(output, set, options, &progress)) cli::warn(warning);
    });
}
