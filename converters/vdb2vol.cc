// vdb2vol IN.vdb OUT.vol --grid NAME [--pad N]: one grid → Mitsuba's binary grid volume.
#include "CliSupport.h"

#include <vxf/io/MitsubaVolume.h>
#include <vxf/io/VoxelSetFile.h>

#include <fmt/format.h>

#include <iostream>

int main(int argc, char** argv)
{
    using namespace vxf;
    CLI::App app{"Convert one float or vec3s grid of a .vdb file to Mitsuba's binary grid volume (.vol, version 3,\n"
                 "float32, x fastest), over the grid's active bounding box, so a path tracer (Mitsuba's gridvolume)\n"
                 "sees the same medium. The .vol format is dense.",
        "vdb2vol"};
    std::string input, output, grid = "density";
    int pad = 1;
    app.add_option("input", input, ".vdb file")->required();
    app.add_option("output", output, "Output .vol file")->required()->check(cli::OutputFile);
    app.add_option("--grid", grid, "The grid to write (default density)");
    app.add_option("--pad", pad, "Voxels of padding around the active bounding box (default 1)")->check(CLI::Range(0, 1024));
    return cli::runMain(app, argc, argv, [&] {
        cli::refuseOutputOverInput(input, output);
        const VoxelSet set = readVoxelSet(input);
        auto g = set.find(grid);
        if (!g) throw UsageError(fmt::format("{}: no grid named '{}'", input, grid));
        const MitsubaVolumeInfo info = writeMitsubaVolume(output, *g, pad);
        std::cout << fmt::format("{} '{}' -> {}: {}x{}x{}, {} channel(s), bounds ({:.6g}, {:.6g}, {:.6g}) - ({:.6g}, {:.6g}, {:.6g})\n",
            input, grid, output, info.resolution.x(), info.resolution.y(), info.resolution.z(), info.channels, info.bounds.min().x(),
            info.bounds.min().y(), info.bounds.min().z(), info.bounds.max().x(), info.bounds.max().y(), info.bounds.max().z());
    });
}
