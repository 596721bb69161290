// vxf — the operators on a grid's values: arithmetic, blend, blur, fill, normalize.
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

std::vector<Operator> valueOperators()
{
    std::vector<Operator> ops;
    // Arithmetic with a number.
    const std::pair<const char*, ArithmeticOp> arithmetic[] = {{"add", ArithmeticOp::Add}, {"sub", ArithmeticOp::Sub},
        {"mul", ArithmeticOp::Mul}, {"div", ArithmeticOp::Div}, {"pow", ArithmeticOp::Pow}};
    const char* arithmeticSummary[] = {"v + value on the active values", "v - value on the active values", "v * value on the active values",
        "v / value on the active values (x / 0 = 0)", "v ^ value on the active values (negative v: -|v|^value; 0 ^ negative = 0)"};
    for (std::size_t i = 0; i < 5; ++i) {
        const ArithmeticOp kind = arithmetic[i].second;
        ops.push_back({arithmetic[i].first, arithmeticSummary[i],
            {gridParam(), typed("value", ParamType::Color, "the number (or r,g,b per channel)"), outParam()},
            [kind, name = std::string(arithmetic[i].first)](OpContext& ctx) {
                auto g = target(ctx, name);
                ops::arithmetic(*g, kind, ctx.args.color("value"));
                return fmt::format("{} on '{}' ({})", name, g->getName(), count(*g));
            }});
    }

    ops.push_back({"blend", "blend grid B into grid A: add, subtract, multiply, darker, lighter or mix; active where either is",
        {gridParam("grid A (the result replaces it unless out is given)"), withParam("grid B"), withFileParam(),
            choice("mode", "how to combine", {"add", "subtract", "multiply", "darker", "lighter", "mix"}, "add"),
            when(number("weight", "mix: A (1 - w) + B w", 0.5, 0.0, 1.0), "mode=mix"),
            flag("clamp_negatives", "clamp A and B to >= 0 first"), flag("normalize_b", "divide B by its largest |value| first"),
            flag("resample", "resample B onto A's transform when they differ (trilinear)"), outParam()},
        [](OpContext& ctx) {
            auto a = target(ctx, "blend");
            auto b = withGrid(ctx, "blend");
            if (ctx.args.flag("resample") && a->transform() != b->transform()) b = resampleLike(*b, *a);
            BlendOptions o;
            const std::string mode = ctx.args.text("mode");
            o.mode = mode == "subtract" ? BlendMode::Subtract
                : mode == "multiply"    ? BlendMode::Multiply
                : mode == "darker"      ? BlendMode::Darker
                : mode == "lighter"     ? BlendMode::Lighter
                : mode == "mix"         ? BlendMode::Mix
                                        : BlendMode::Add;
            o.weight = ctx.args.number("weight");
            o.clampNegatives = ctx.args.flag("clamp_negatives");
            o.normalizeB = ctx.args.flag("normalize_b");
            ops::blend(*a, *b, o);
            return fmt::format("blended '{}' into '{}' ({}; {})", b->getName(), a->getName(), mode, count(*a));
        }});

    ops.push_back({"blur", "box or distance-weighted blur of the active voxels (OpenVDB's Filter), optionally within a selection",
        {gridParam(), choice("kind", "box: mean; distance: Gaussian-weighted", {"box", "distance"}, "box"),
            integer("radius", "voxels", 1, 1, 64), integer("iterations", "passes", 1, 1, 1000),
            text("mask", "(optional) bool selection grid: blur only there"), outParam()},
        [](OpContext& ctx) {
            auto g = target(ctx, "blur");
            openvdb::BoolGrid::Ptr keep;
            const openvdb::BoolGrid* selection = optionalSelection(ctx, "blur", "mask", keep);
            openvdb::FloatGrid::Ptr weights = selection ? weightsFromSelection(*selection) : nullptr;
            BlurOptions o;
            o.kind = ctx.args.text("kind") == "distance" ? BlurKind::Distance : BlurKind::Box;
            o.radius = ctx.args.integer("radius");
            o.iterations = ctx.args.integer("iterations");
            o.mask = weights.get();
            ops::blur(*g, o, ctx.interrupter);
            return fmt::format("blurred '{}' (radius {}, {} iterations)", g->getName(), o.radius, o.iterations);
        }});

    ops.push_back({"blur_special", "fill unset voxels (or a selection) from their neighbours; the artist's voxels stay bit-identical",
        {gridParam(), text("region", "where values are wanted (its active voxels)", "density"),
            text("selection", "(optional) bool grid: also recompute these set voxels"),
            integer("smoothing", "smoothing passes over the filled voxels", 4, 0, 1000), outParam()},
        [](OpContext& ctx) {
            auto g = target(ctx, "blur_special");
            auto region = requireGrid(ctx.set, "blur_special", ctx.args.text("region"));
            openvdb::BoolGrid::Ptr keep;
            FillOptions o;
            o.region = region.get();
            o.selection = optionalSelection(ctx, "blur_special", "selection", keep);
            o.smoothing = ctx.args.integer("smoothing");
            const auto filled = ops::fill(*g, o, ctx.interrupter);
            return fmt::format("filled {} voxels of '{}'", filled, g->getName());
        }});

    ops.push_back({"normalize",
        "scale the active values into [0, 1] by a power of two (bit-exact round trip), recording offset and scale in the grid's metadata",
        {gridParam(), flag("clamp_negatives", "clamp negative values to 0 first"),
            flag("max_to_one", "put the largest value on 1 exactly (the round trip is then exact to 1 ulp, not bit for bit)"), outParam()},
        [](OpContext& ctx) {
            auto g = target(ctx, "normalize");
            NormalizeOptions o;
            o.clampNegatives = ctx.args.flag("clamp_negatives");
            o.exact = !ctx.args.flag("max_to_one");
            ops::normalize(*g, o);
            return fmt::format("normalized '{}' (offset {}, scale {})", g->getName(), g->metaValue<double>(kNormalizeOffsetKey),
                g->metaValue<double>(kNormalizeScaleKey));
        }});

    ops.push_back(
        {"denormalize", "restore the values normalize scaled, from the grid's metadata", {gridParam(), outParam()}, [](OpContext& ctx) {
             auto g = target(ctx, "denormalize");
             ops::denormalize(*g);
             return fmt::format("denormalized '{}'", g->getName());
         }});

    return ops;
}

} // namespace vxf::ops
