// bench/ops: every artist operator of the registry on one voxel set, in process (no file I/O
// in the timings): seconds and active voxels per second, best of N runs on fresh copies.
//
// Usage: bench_ops SET.vdb RUNS   (SET holds `density` and `surface`; see bench/ops/run)
#include <vxf/io/VoxelSetFile.h>
#include <vxf/pipeline/Operators.h>

#include <fmt/format.h>
#include <tbb/info.h>

#include <chrono>
#include <iostream>
#include <map>

using nlohmann::json;

int main(int argc, char** argv)
{
    if (argc != 3) {
        std::cerr << "usage: bench_ops SET.vdb RUNS\n";
        return 2;
    }
    openvdb::initialize();
    const int runs = std::max(1, std::atoi(argv[2]));
    vxf::VoxelSet base = vxf::readVoxelSet(argv[1]);
    // Work on leaf voxels, as an artist's grid after the light stage has them (no tiles).
    auto density = base.get<openvdb::FloatGrid>("density");
    density->tree().voxelizeActiveTiles();
    const openvdb::Index64 voxels = density->activeVoxelCount();
    {
        // A colour grid over the same voxels, and a second one to blend with.
        const auto& gradient = vxf::findOperator("gradient");
        const auto args = vxf::ops::checkArgs(
            gradient, {{"kind", "radial"}, {"radius", 1.0}, {"colors", {{1, 0.5, 0.2}, {0.1, 0.2, 1}}}, {"out", "color"}});
        vxf::ops::OpContext context{base, args, nullptr};
        gradient.run(context);
        auto second = base.find("color")->deepCopyGrid();
        second->setName("color2");
        base.put(second);
        const auto& select = vxf::findOperator("select");
        const auto sargs =
            vxf::ops::checkArgs(select, {{"grid", "density"}, {"shape", "range"}, {"low", 0.5}, {"high", 0.9}, {"out", "mask"}});
        vxf::ops::OpContext scontext{base, sargs, nullptr};
        select.run(scontext);
    }
    // Parameters per operator (the rest take their defaults).
    const std::map<std::string, json> params = {
        {"add", {{"grid", "color"}, {"value", 0.5}}},
        {"sub", {{"grid", "color"}, {"value", 0.5}}},
        {"mul", {{"grid", "color"}, {"value", json::array({1.0, 0.5, 2.0})}}},
        {"div", {{"grid", "color"}, {"value", 3.0}}},
        {"pow", {{"grid", "color"}, {"value", 2.2}}},
        {"blend", {{"grid", "color"}, {"with", "color2"}, {"mode", "mix"}, {"weight", 0.3}}},
        {"blur", {{"grid", "color"}, {"radius", 2}}},
        {"blur_special", {{"grid", "color"}, {"region", "density"}, {"selection", "mask"}, {"smoothing", 2}}},
        {"normalize", {{"grid", "color"}}},
        {"denormalize", {{"grid", "color"}}},
        {"gradient", {{"kind", "directional"}, {"from", {-0.1, 0, 0}}, {"to", {0.1, 0, 0}}, {"colors", {0, 1}}}},
        {"remove", {{"grid", "color"}, {"with", "mask"}}},
        {"include", {{"grid", "color"}, {"with", "mask"}}},
        {"select", {{"grid", "density"}, {"shape", "range"}, {"low", 0.2}, {"high", 0.6}, {"out", "sel"}}},
        {"edit", {{"grid", "color"}, {"selection", "mask"}, {"hue_shift", 30.0}}},
        {"diff", {{"grid", "color"}, {"with", "color2"}}},
        {"split", {{"grid", "color"}}},
        {"rename", {{"grid", "color"}, {"to", "colour"}}},
        {"copy", {{"grid", "color"}, {"to", "color3"}}},
    };
    std::cout << fmt::format("| operator | parameters | seconds (best of {}) | active voxels per second |\n|---|---|---:|---:|\n", runs);
    for (const auto& op : vxf::operators()) {
        const auto found = params.find(op.name);
        if (found == params.end()) continue; // pipeline stages and multi-grid setups (merge, apply_diff) are not timed here
        const auto args = vxf::ops::checkArgs(op, found->second);
        double best = 1e30;
        for (int r = 0; r < runs; ++r) {
            vxf::VoxelSet set(base.transformPtr());
            for (const auto& g : base.grids()) set.putAsIs(g->deepCopyGrid());
            if (op.name == "denormalize") {
                const auto& normalize = vxf::findOperator("normalize");
                const auto nargs = vxf::ops::checkArgs(normalize, {{"grid", "color"}});
                vxf::ops::OpContext n{set, nargs, nullptr};
                normalize.run(n);
            }
            vxf::ops::OpContext context{set, args, nullptr};
            const auto start = std::chrono::steady_clock::now();
            op.run(context);
            best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        }
        std::cout << fmt::format("| `{}` | `{}` | {:.4f} | {:.1f}M |\n", op.name, found->second.dump(), best, double(voxels) / best / 1e6);
    }
    std::cout << fmt::format("\n{} active voxels (leaf voxels: the density's interior tiles voxelized), `mask` {} of them, {} threads.\n",
        voxels, base.find("mask")->activeVoxelCount(), tbb::info::default_concurrency());
    return 0;
}
