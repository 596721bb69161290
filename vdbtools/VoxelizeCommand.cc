// `vxf voxelize MESH -o OUT.vdb [--voxel-size S | --dim N] [--band W]`: the mesh, --voxel-size, --dim and --band are
// the voxelize operator's parameters (pipeline/Operators.cc), declared there once.
#include "CliSupport.h"
#include "Commands.h"
#include "OperatorOptions.h"

#include <vxf/core/GridStats.h>
#include <vxf/core/ProceduralMesh.h>
#include <vxf/pipeline/Operators.h>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <tbb/task_group.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <iostream>

namespace vxf::cli {

void voxelizeToFile(const VoxelizeRequest& request)
{
    TerminalProgress progress;
    const auto start = std::chrono::steady_clock::now();

    TriangleMesh mesh;
    MeshReport report;
    if (auto builtin = builtinMesh(request.mesh)) {
        mesh = std::move(*builtin);
        report.triangles = mesh.triangles.size();
        report.outwardOriented = true;
    } else if (request.mesh.rfind("builtin:", 0) == 0) {
        throw UsageError(fmt::format("unknown built-in mesh '{}' (known: {})", request.mesh, fmt::join(builtinMeshNames(), ", ")));
    } else {
        MeshReadOptions readOptions = request.meshRead;
        readOptions.checkSelfIntersections = false; // overlapped with voxelization below
        mesh = readMesh(request.mesh, readOptions, &report, &progress);
    }
    for (const auto& warning : report.warnings) warn(fmt::format("{}: {}", request.mesh, warning));
    const double meshSeconds = secondsSince(start);

    const auto voxelizeStart = std::chrono::steady_clock::now();
    VoxelSet set = voxelize(mesh, request.voxelize, &progress);
    const double voxelizeSeconds = secondsSince(voxelizeStart);

    // The self-intersection check only reports, so it runs beside the (single-threaded) write,
    // on the core the writer leaves idle, rather than competing with the voxelization.
    MeshReport intersections;
    tbb::task_group checks;
    if (request.meshRead.checkSelfIntersections && request.mesh.rfind("builtin:", 0) != 0) {
        checks.run([&] { checkSelfIntersections(mesh, intersections); });
    }
    nlohmann::json params = {
        {"command", "voxelize"},
        {"mesh", request.mesh},
        {"voxel_size", set.transform().voxelSize()[0]},
        {"band", request.voxelize.bandWidth},
        {"half", request.write.half},
        {"fill_holes", request.meshRead.fillHoles},
    };
    if (request.voxelize.dim > 0) params["dim"] = request.voxelize.dim;
    set.setProvenance("voxelize", params.dump());

    const auto writeStart = std::chrono::steady_clock::now();
    try {
        writeVoxelSet(request.output, set, request.write);
    } catch (...) {
        checks.wait();
        throw;
    }
    checks.wait();
    for (const auto& warning : intersections.warnings) warn(fmt::format("{}: {}", request.mesh, warning));
    const double writeSeconds = secondsSince(writeStart);
    if (request.quiet) return;

    const double voxelSize = set.transform().voxelSize()[0];
    std::cout << fmt::format("voxelized {} ({} triangles) -> {}\n", request.mesh, mesh.triangles.size(), request.output);
    std::cout << fmt::format("  voxel size    {:.6g} world units{}\n", voxelSize,
        request.voxelize.dim > 0 ? fmt::format(" (dim {} along the longest side)", request.voxelize.dim) : "");
    std::cout << fmt::format("  band          {} voxels each side of the surface\n", request.voxelize.bandWidth);
    openvdb::Index64 totalMemory = 0;
    for (const auto& grid : set.grids()) {
        const GridStats s = gridStats(*grid);
        totalMemory += s.memoryBytes;
        std::cout << fmt::format("  {:<13} {:<10} {:>12} active voxels, {:>8} leaves, {:>6} active tiles, {:>10}\n", grid->getName(),
            openvdb::GridBase::gridClassToString(grid->getGridClass()), s.activeVoxels, s.leafNodes, s.activeTiles,
            formatBytes(s.memoryBytes));
    }
    const auto bbox = set.find("surface")->evalActiveVoxelBoundingBox();
    const auto dim = bbox.dim();
    std::cout << fmt::format("  bounds        {} x {} x {} voxels; dense Vec3f grid of it: {}, this set in memory: {}\n", dim.x(), dim.y(),
        dim.z(), formatBytes(std::uint64_t(dim.x()) * dim.y() * dim.z() * 12), formatBytes(totalMemory));
    std::cout << fmt::format("  file          {}\n", formatBytes(std::filesystem::file_size(request.output)));
    std::cout << fmt::format("  seconds       {:.3f} total: mesh {:.3f}, voxelize {:.3f}, write (+ self-intersection check) {:.3f}\n",
        secondsSince(start), meshSeconds, voxelizeSeconds, writeSeconds);
    if (!report.stepSeconds.empty()) {
        std::cout << "  mesh steps   ";
        for (const auto& [step, seconds] : report.stepSeconds) std::cout << fmt::format(" {} {:.3f},", step, seconds);
        std::cout << "\n";
    }
}

namespace {

class VoxelizeCommand : public Command
{
public:
    explicit VoxelizeCommand(CLI::App& parent)
    {
        mApp = parent.add_subcommand("voxelize", "Voxelize a mesh into `surface` (level set) and `density` (fog volume).");
        mParams =
            std::make_unique<OperatorOptions>(*mApp, findOperator("voxelize"), true, std::map<std::string, std::string>{{"mesh", "mesh"}});
        mApp->add_option("-o,--output", mRequest.output, "Output .vdb file")->required()->check(OutputFile);
        mApp->add_flag("--half", mRequest.write.half, "Store floats as 16-bit halves");
        mApp->add_flag(
            "--no-fill-holes", [this](std::int64_t) { mRequest.meshRead.fillHoles = false; },
            "Leave holes of an open mesh open (the interior may leak)");
        mApp->add_flag(
            "--no-self-intersection-check", [this](std::int64_t) { mRequest.meshRead.checkSelfIntersections = false; },
            "Skip the self-intersection check");
        mApp->add_flag("-q,--quiet", mRequest.quiet, "No summary");
    }

    void run() override
    {
        if (mParams->has("voxel_size") && mParams->has("dim")) throw UsageError("give --voxel-size or --dim, not both");
        const ops::Args args = mParams->args();
        mRequest.mesh = args.text("mesh");
        refuseOverwrites({{"the mesh", mRequest.mesh}}, {{"-o", mRequest.output}});
        mRequest.voxelize = voxelizeOptions(args);
        voxelizeToFile(mRequest);
    }

private:
    VoxelizeRequest mRequest;
    std::unique_ptr<OperatorOptions> mParams; ///< the voxelize operator's parameters (pipeline/Operators.cc)
};

} // namespace

std::unique_ptr<Command> makeVoxelizeCommand(CLI::App& parent) { return std::make_unique<VoxelizeCommand>(parent); }

} // namespace vxf::cli
