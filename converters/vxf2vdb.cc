// vxf2vdb IN.vxf OUT.vdb: text VXF (schemas/vxf-text.md) → multi-grid OpenVDB file.
#include "CliSupport.h"

#include <vxf/io/VoxelSetFile.h>
#include <vxf/io/VxfText.h>

#include <nlohmann/json.hpp>

int main(int argc, char** argv)
{
    using namespace vxf;
    CLI::App app{"Convert a text VXF file (the thesis's format, schemas/vxf-text.md) to a multi-grid .vdb.\n"
                 "Each declared column group becomes a grid (default: `color`, Vec3f).",
        "vxf2vdb"};
    std::string input, output;
    VoxelSetWriteOptions write;
    app.add_option("input", input, "Text VXF file")->required();
    app.add_option("output", output, "Output .vdb file")->required()->check(cli::OutputFile);
    app.add_flag("--half", write.half, "Store floats as 16-bit halves (lossy)");
    return cli::runMain(app, argc, argv, [&] {
        cli::refuseOutputOverInput(input, output);
        cli::TerminalProgress progress;
        VoxelSet set = readVxfText(input, &progress);
        set.setProvenance("convert", nlohmann::json{{"command", "vxf2vdb"}, {"input", input}, {"half", write.half}}.dump());
        writeVoxelSet(output, set, write);
    });
}
