// vxf — the operators that make colours and patterns: gradient, noise.
#include "OperatorGroups.h"

#include <vxf/core/GridRoles.h>
#include <vxf/io/VoxelSetFile.h>
#include <vxf/ops/Arithmetic.h>
#include <vxf/ops/Blend.h>
#include <vxf/ops/Blur.h>
#include <vxf/ops/Channels.h>
#include <vxf/ops/Diff.h>
#include <vxf/ops/Edit.h>
#include <vxf/ops/Fill.h>
#include <vxf/ops/Gradient.h>
#include <vxf/ops/Noise.h>
#include <vxf/ops/Normalize.h>
#include <vxf/ops/Select.h>

#include <fmt/format.h>

#include <cmath>

namespace vxf::ops {

using nlohmann::json;
using namespace params;
using namespace detail;

std::vector<Operator> colourOperators()
{
    std::vector<Operator> ops;
    ops.push_back({"gradient", "a colour gradient over the active voxels of a grid: directional, radial or distance from the surface",
        {choice("kind", "the gradient's shape", {"directional", "radial", "surface_distance"}, "directional"),
            text("topology", "the grid whose active voxels receive colours", "density"),
            when(typed("from", ParamType::Vector, "directional: where the ramp starts", json::array({0, 0, 0})), "kind=directional"),
            when(typed("to", ParamType::Vector, "directional: where it ends", json::array({0, 0, 1})), "kind=directional"),
            when(typed("centre", ParamType::Vector, "radial: centre", json::array({0, 0, 0})), "kind=radial"),
            when(number("radius", "radial: where the ramp ends", 1.0, 1e-30), "kind=radial"),
            when(number("falloff", "radial: exponent on the distance", 1.0, 1e-3, 1e3), "kind=radial"),
            when(number("distance", "surface_distance: depth where the ramp ends (within the narrow band)", 1.0, 1e-30),
                "kind=surface_distance"),
            typed("colors", ParamType::ColorList, "ramp colours, first to last", json::array({0, 1})),
            typed("positions", ParamType::NumberList, "(optional) ramp positions in [0, 1], one per colour (default: even)"),
            text("out", "the new grid's name", "gradient")},
        [](OpContext& ctx) {
            GradientOptions o;
            const std::string kind = ctx.args.text("kind");
            o.kind = kind == "radial"        ? GradientKind::Radial
                : kind == "surface_distance" ? GradientKind::SurfaceDistance
                                             : GradientKind::Directional;
            o.from = ctx.args.color("from");
            o.to = ctx.args.color("to");
            o.centre = ctx.args.color("centre");
            o.radius = ctx.args.number("radius");
            o.falloff = ctx.args.number("falloff");
            o.distance = ctx.args.number("distance");
            const auto colors = ctx.args.colors("colors");
            std::vector<double> positions;
            if (ctx.args.has("positions")) {
                positions = ctx.args.numbers("positions");
                if (positions.size() != colors.size()) {
                    throw UsageError(fmt::format("gradient: {} positions for {} colours", positions.size(), colors.size()));
                }
            }
            for (std::size_t i = 0; i < colors.size(); ++i) {
                o.stops.push_back({positions.empty() ? double(i) / double(colors.size() - 1) : positions[i], colors[i]});
            }
            auto topology = requireGrid(ctx.set, "gradient", ctx.args.text("topology"));
            openvdb::FloatGrid::Ptr surface;
            if (o.kind == GradientKind::SurfaceDistance) {
                surface = openvdb::gridPtrCast<openvdb::FloatGrid>(requireGrid(ctx.set, "gradient", "surface"));
            }
            auto g = ops::gradient(*topology, surface.get(), o);
            g->setName(ctx.args.text("out"));
            ctx.set.put(g);
            return fmt::format("{} gradient '{}' over '{}' ({})", kind, g->getName(), topology->getName(), count(*g));
        }});

    ops.back().grids = [](const Args& a) {
        GridUse use{{a.text("topology")}, {a.text("out")}};
        if (a.text("kind") == "surface_distance") use.reads.insert(grids::kSurface);
        return use;
    };
    ops.push_back({"noise",
        "fractal gradient noise (Perlin) over a grid's active voxels: set, added or multiplied, to break up a flat colour or density",
        {gridParam("a vec3s or float grid"), text("selection", "(optional) bool grid (vxf op select); default: every active voxel"),
            number("frequency", "cycles per world unit (first octave)", 4.0, 1e-30),
            integer("octaves", "octaves, each twice the frequency", 4, 1, 12),
            number("lacunarity", "frequency ratio between octaves", 2.0, 1.0, 8.0),
            number("gain", "amplitude ratio between octaves", 0.5, 0.0, 1.0), number("amplitude", "the noise's scale (|noise| <= 1)", 1.0),
            number("offset", "added to the scaled noise", 0.0), integer("seed", "the pattern", 0, 0, 1000000),
            typed("shift", ParamType::Vector, "where the pattern starts (world)", json::array({0, 0, 0})),
            choice("mode", "set: v = offset + amplitude·n; add: v + that; multiply: v·that", {"set", "add", "multiply"}, "add"),
            flag("per_channel", "vec3s: an independent noise per channel"), outParam()},
        [](OpContext& ctx) {
            const auto grid = target(ctx, "noise");
            NoiseOptions o;
            o.frequency = ctx.args.number("frequency");
            o.octaves = int(ctx.args.integer("octaves"));
            o.lacunarity = ctx.args.number("lacunarity");
            o.gain = ctx.args.number("gain");
            o.amplitude = ctx.args.number("amplitude");
            o.offset = ctx.args.number("offset");
            o.seed = std::uint32_t(ctx.args.integer("seed"));
            o.shift = ctx.args.color("shift");
            const std::string mode = ctx.args.text("mode");
            o.mode = mode == "set" ? NoiseMode::Set : mode == "multiply" ? NoiseMode::Multiply : NoiseMode::Add;
            o.perChannel = ctx.args.flag("per_channel");
            openvdb::BoolGrid::Ptr keep;
            const openvdb::BoolGrid* selection = optionalSelection(ctx, "noise", "selection", keep);
            if (auto colour = openvdb::gridPtrCast<openvdb::Vec3SGrid>(grid)) {
                ops::noise(*colour, o, selection);
            } else if (auto number = openvdb::gridPtrCast<openvdb::FloatGrid>(grid)) {
                ops::noise(*number, o, selection);
            } else {
                throw UsageError(
                    fmt::format("noise: grid '{}' is a {} grid; noise takes vec3s or float grids", grid->getName(), grid->valueType()));
            }
            return fmt::format("{} noise on '{}' ({})", mode, grid->getName(), count(*grid));
        }});
    return ops;
}

} // namespace vxf::ops
