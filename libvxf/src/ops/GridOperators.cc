// vxf — the operators on whole grids: diff, apply_diff, split, merge, rename, copy.
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
#include <vxf/ops/Select.h>

#include <fmt/format.h>

#include <cmath>

namespace vxf::ops {

using nlohmann::json;
using namespace params;
using namespace detail;

std::vector<Operator> gridOperators()
{
    std::vector<Operator> ops;
    ops.push_back({"diff", "the voxels where grid B differs from grid A, as B - A (the thesis's difference export)",
        {gridParam("grid A (the original)"), withParam("grid B (the edited one)"), withFileParam(),
            number("tolerance", "differences up to this are equal", 0.0, 0.0),
            text("out", "(optional) the difference grid's name (default GRID_diff)")},
        [](OpContext& ctx) {
            auto a = requireGrid(ctx.set, "diff", ctx.args.text("grid"));
            auto d = difference(*a, *withGrid(ctx, "diff"), ctx.args.number("tolerance"));
            if (ctx.args.has("out")) d->setName(ctx.args.text("out"));
            ctx.set.put(d);
            return fmt::format("'{}': {} differ", d->getName(), count(*d));
        }});

    ops.back().grids = [](const Args& a) {
        GridUse use{{a.text("grid")}, {a.has("out") ? a.text("out") : a.text("grid") + "_diff"}};
        if (!a.has("with_file")) use.reads.insert(a.text("with"));
        return use;
    };
    ops.push_back({"apply_diff", "replay a difference grid onto a grid, optionally blending its edge (difference + smooth)",
        {gridParam(), withParam("the difference grid (vxf op diff)"), withFileParam(),
            integer("smooth", "blend this many voxels around the edit with blur_special (0: none)", 0, 0, 64), outParam()},
        [](OpContext& ctx) {
            auto a = target(ctx, "apply_diff");
            auto d = withGrid(ctx, "apply_diff");
            applyDifferenceSmoothed(*a, *d, ctx.args.integer("smooth"), ctx.interrupter);
            return fmt::format("applied '{}' to '{}'", d->getName(), a->getName());
        }});

    ops.push_back({"split", "split a vec3s grid into float grids NAME.x, NAME.y, NAME.z (Houdini's Cd.x/y/z)", {gridParam("a vec3s grid")},
        [](OpContext& ctx) {
            auto g = openvdb::gridPtrCast<openvdb::Vec3SGrid>(requireGrid(ctx.set, "split", ctx.args.text("grid")));
            if (!g) throw UsageError(fmt::format("split: grid '{}' is not a vec3s grid", ctx.args.text("grid")));
            for (auto& c : splitChannels(*g)) ctx.set.put(c);
            return fmt::format("split '{}' into {}.x, .y, .z", g->getName(), g->getName());
        }});

    ops.back().grids = [](const Args& a) {
        const std::string g = a.text("grid");
        return GridUse{{g}, {g + ".x", g + ".y", g + ".z"}};
    };
    ops.push_back({"merge", "merge three float grids into one vec3s grid",
        {text("x", "the first channel's grid"), text("y", "the second channel's grid"), text("z", "the third channel's grid"),
            text("out", "the vec3s grid's name")},
        [](OpContext& ctx) {
            openvdb::FloatGrid::Ptr c[3];
            for (int i = 0; i < 3; ++i) {
                const std::string name = ctx.args.text(std::string(1, "xyz"[i]));
                c[i] = openvdb::gridPtrCast<openvdb::FloatGrid>(requireGrid(ctx.set, "merge", name));
                if (!c[i]) throw UsageError(fmt::format("merge: grid '{}' is not a float grid", name));
            }
            auto g = mergeChannels(*c[0], *c[1], *c[2], ctx.args.text("out"));
            ctx.set.put(g);
            return fmt::format("merged into '{}' ({})", g->getName(), count(*g));
        }});

    ops.back().grids = [](const Args& a) { return GridUse{{a.text("x"), a.text("y"), a.text("z")}, {a.text("out")}}; };
    ops.push_back({"rename", "rename a grid", {gridParam(), text("to", "the new name")}, [](OpContext& ctx) {
                       auto g = requireGrid(ctx.set, "rename", ctx.args.text("grid"));
                       const std::string to = ctx.args.text("to");
                       if (ctx.set.find(to)) throw UsageError(fmt::format("rename: a grid named '{}' exists already", to));
                       ctx.set.remove(g->getName());
                       g->setName(to);
                       ctx.set.put(g);
                       return fmt::format("renamed '{}' to '{}'", ctx.args.text("grid"), to);
                   }});

    ops.back().grids = [](const Args& a) { return GridUse{{a.text("grid")}, {a.text("grid"), a.text("to")}}; };
    ops.push_back(
        {"delete", "delete a grid from the set (a helper mask, a grid not to ship)", {gridParam("the grid deleted")}, [](OpContext& ctx) {
             requireGrid(ctx.set, "delete", ctx.args.text("grid"));
             ctx.set.remove(ctx.args.text("grid"));
             return fmt::format("deleted '{}'", ctx.args.text("grid"));
         }});
    ops.back().grids = [](const Args& a) { return GridUse{{}, {a.text("grid")}}; };
    ops.push_back({"copy", "copy a grid from another .vdb (or within the file) under a name",
        {gridParam("the grid to copy"), text("from_file", "(optional) the .vdb it comes from (default: this file)"),
            text("to", "(optional) its name here (default: the same)"),
            flag("resample", "resample it onto this file's transform when it differs")},
        [](OpContext& ctx) {
            openvdb::GridBase::Ptr g;
            if (ctx.args.has("from_file")) {
                const VoxelSet other = readVoxelSet(ctx.args.text("from_file"));
                g = requireGrid(other, "copy", ctx.args.text("grid"))->deepCopyGrid();
            } else {
                g = requireGrid(ctx.set, "copy", ctx.args.text("grid"))->deepCopyGrid();
            }
            if (ctx.args.flag("resample") && !ctx.set.empty() && g->transform() != ctx.set.transform()) {
                g = resampleLike(*g, *ctx.set.grids().front());
            }
            g->setName(ctx.args.has("to") ? ctx.args.text("to") : ctx.args.text("grid"));
            ctx.set.put(g);
            return fmt::format("copied '{}' as '{}'", ctx.args.text("grid"), g->getName());
        }});

    ops.back().grids = [](const Args& a) {
        GridUse use{{}, {a.has("to") ? a.text("to") : a.text("grid")}};
        if (!a.has("from_file")) use.reads.insert(a.text("grid"));
        return use;
    };
    return ops;
}

} // namespace vxf::ops
