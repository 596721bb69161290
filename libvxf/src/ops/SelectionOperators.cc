// vxf — the operators on a grid's active voxels: remove, include, select, edit.
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
#include <vxf/ops/Normalize.h>
#include <vxf/ops/Paint.h>
#include <vxf/ops/Select.h>

#include <fmt/format.h>

#include <cmath>

namespace vxf::ops {

using nlohmann::json;
using namespace params;
using namespace detail;

std::vector<Operator> selectionOperators()
{
    std::vector<Operator> ops;
    ops.push_back({"remove", "deactivate the voxels of a grid that are active in another",
        {gridParam(), withParam("the grid whose active voxels are removed"), withFileParam()}, [](OpContext& ctx) {
            auto a = requireGrid(ctx.set, "remove", ctx.args.text("grid"));
            removeActive(*a, *withGrid(ctx, "remove"));
            return fmt::format("'{}' now has {}", a->getName(), count(*a));
        }});
    ops.push_back({"include", "activate the voxels of a grid that are inactive there and active in another",
        {gridParam(), withParam("the grid whose active voxels are added"), withFileParam()}, [](OpContext& ctx) {
            auto a = requireGrid(ctx.set, "include", ctx.args.text("grid"));
            includeActive(*a, *withGrid(ctx, "include"));
            return fmt::format("'{}' now has {}", a->getName(), count(*a));
        }});

    ops.push_back({"select", "select active voxels by box, sphere or value range into a bool mask grid",
        {gridParam("the grid whose active voxels are candidates"), choice("shape", "how to select", {"box", "sphere", "range"}, "box"),
            when(typed("min", ParamType::Vector, "box: lower corner (world)", json::array({-1, -1, -1})), "shape=box"),
            when(typed("max", ParamType::Vector, "box: upper corner (world)", json::array({1, 1, 1})), "shape=box"),
            when(typed("centre", ParamType::Vector, "sphere: centre (world)", json::array({0, 0, 0})), "shape=sphere"),
            when(number("radius", "sphere: radius (world)", 1.0, 0.0), "shape=sphere"),
            when(number("low", "range: lowest value (every channel)", 0.0), "shape=range"),
            when(number("high", "range: highest value (every channel)", 1.0), "shape=range"), text("out", "the mask grid's name", "mask")},
        [](OpContext& ctx) {
            auto g = requireGrid(ctx.set, "select", ctx.args.text("grid"));
            const std::string shape = ctx.args.text("shape");
            openvdb::BoolGrid::Ptr mask;
            if (shape == "box") {
                mask = selectBox(*g, openvdb::BBoxd(ctx.args.color("min"), ctx.args.color("max")));
            } else if (shape == "sphere") {
                mask = selectSphere(*g, ctx.args.color("centre"), ctx.args.number("radius"));
            } else {
                mask = selectRange(*g, ctx.args.number("low"), ctx.args.number("high"));
            }
            mask->setName(ctx.args.text("out"));
            ctx.set.put(mask);
            return fmt::format("selected {} voxels of '{}' into '{}'", mask->activeVoxelCount(), g->getName(), mask->getName());
        }});

    ops.back().grids = [](const Args& a) { return GridUse{{a.text("grid")}, {a.text("out")}}; };
    ops.push_back({"edit",
        "on a selection: set a colour or value, shift hue, scale saturation and value, add an offset, add or remove voxels (a "
        "vec3s grid; a float grid: set, value, offset, add, remove)",
        {gridParam("a vec3s or float grid"), text("selection", "(optional) bool grid (vxf op select); default: every active voxel"),
            typed("set", ParamType::Color, "(optional) the new colour (a float grid: one number)"),
            number("hue_shift", "degrees (vec3s)", 0.0, -360.0, 360.0), number("saturation", "saturation scale (vec3s)", 1.0, 0.0),
            number("value", "value scale (a float grid: its values')", 1.0, 0.0),
            number("offset", "added after the rest (to each channel of a colour)", 0.0),
            flag("add", "activate selected voxels that are inactive"), flag("remove", "deactivate the selected voxels"), outParam()},
        [](OpContext& ctx) {
            const auto grid = target(ctx, "edit");
            auto g = openvdb::gridPtrCast<openvdb::Vec3SGrid>(grid);
            auto scalar = openvdb::gridPtrCast<openvdb::FloatGrid>(grid);
            if (!g && !scalar) {
                throw UsageError(
                    fmt::format("edit: grid '{}' is a {} grid; edit takes vec3s or float grids", ctx.args.text("grid"), grid->valueType()));
            }
            openvdb::BoolGrid::Ptr keep;
            const openvdb::BoolGrid* selection = optionalSelection(ctx, "edit", "selection", keep);
            EditOptions o;
            if (ctx.args.has("set")) o.set = ctx.args.color("set");
            o.hueShift = ctx.args.number("hue_shift");
            o.saturation = ctx.args.number("saturation");
            o.value = ctx.args.number("value");
            o.offset = ctx.args.number("offset");
            o.add = ctx.args.flag("add");
            o.remove = ctx.args.flag("remove");
            if (scalar) {
                ops::edit(*scalar, selection, o);
                return fmt::format("edited '{}' ({})", scalar->getName(), count(*scalar));
            }
            ops::edit(*g, selection, o);
            return fmt::format("edited '{}' ({})", g->getName(), count(*g));
        }});

    ops.push_back({"paint",
        "a brush stroke: paint a colour (a float grid: a number) onto the active voxels within a radius of its points, mixed "
        "toward it or added, by strength and a soft edge",
        {gridParam("a vec3s or float grid"), typed("points", ParamType::PointList, "the stroke: the brush's centres (world)"),
            number("radius", "the brush's radius (world)", 0.1, 1e-30),
            number("falloff", "the edge: (1 - (d/r)^2)^falloff; 0 hard", 1.0, 0.0, 64.0),
            number("strength", "at the brush's centre", 1.0, 0.0, 1.0), typed("value", ParamType::Color, "the colour or number", 1.0),
            choice("mode", "mix: toward the value; add: plus it", {"mix", "add"}, "mix"), outParam()},
        [](OpContext& ctx) {
            const auto grid = target(ctx, "paint");
            PaintOptions o;
            o.points = ctx.args.points("points");
            o.radius = ctx.args.number("radius");
            o.falloff = ctx.args.number("falloff");
            o.strength = ctx.args.number("strength");
            o.value = ctx.args.color("value");
            o.mode = ctx.args.text("mode") == "add" ? PaintMode::Add : PaintMode::Mix;
            std::uint64_t painted = 0;
            if (auto colour = openvdb::gridPtrCast<openvdb::Vec3SGrid>(grid)) {
                painted = ops::paint(*colour, o);
            } else if (auto number = openvdb::gridPtrCast<openvdb::FloatGrid>(grid)) {
                painted = ops::paint(*number, o);
            } else {
                throw UsageError(
                    fmt::format("paint: grid '{}' is a {} grid; paint takes vec3s or float grids", grid->getName(), grid->valueType()));
            }
            return fmt::format("painted {} voxels of '{}' ({} points)", painted, grid->getName(), o.points.size());
        }});

    return ops;
}

} // namespace vxf::ops
