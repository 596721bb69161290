#include <vxf/ops/Registry.h>

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
#include <sstream>

namespace vxf::ops {

using nlohmann::json;
using namespace params;

// ---------------------------------------------------------------------------------------------
// Args

const nlohmann::json& Args::at(const std::string& name) const
{
    if (!has(name)) throw UsageError(fmt::format("{}: parameter '{}' is required", mOp, name));
    return mValues.at(name);
}
double Args::number(const std::string& name) const { return at(name).get<double>(); }
int Args::integer(const std::string& name) const { return at(name).get<int>(); }
bool Args::flag(const std::string& name) const { return has(name) && mValues.at(name).get<bool>(); }
std::string Args::text(const std::string& name) const { return at(name).get<std::string>(); }
openvdb::Vec3d Args::color(const std::string& name) const
{
    const nlohmann::json& j = at(name);
    if (j.is_number()) return openvdb::Vec3d(j.get<double>());
    return openvdb::Vec3d(j[0].get<double>(), j[1].get<double>(), j[2].get<double>());
}
std::vector<openvdb::Vec3d> Args::colors(const std::string& name) const
{
    std::vector<openvdb::Vec3d> out;
    for (const nlohmann::json& c : at(name)) {
        out.push_back(
            c.is_number() ? openvdb::Vec3d(c.get<double>()) : openvdb::Vec3d(c[0].get<double>(), c[1].get<double>(), c[2].get<double>()));
    }
    return out;
}
std::vector<double> Args::numbers(const std::string& name) const { return at(name).get<std::vector<double>>(); }

// ---------------------------------------------------------------------------------------------
// Checking and parsing

std::string describeType(const Param& p)
{
    const auto range = [&]() -> std::string {
        const bool lo = std::isfinite(p.min), hi = std::isfinite(p.max);
        if (lo && hi) return fmt::format(" in [{}, {}]", p.min, p.max);
        if (lo) return fmt::format(" >= {}", p.min);
        if (hi) return fmt::format(" <= {}", p.max);
        return "";
    };
    switch (p.type) {
    case ParamType::Number: return "number" + range();
    case ParamType::Integer: return "integer" + range();
    case ParamType::Boolean: return "flag";
    case ParamType::Text: return "name";
    case ParamType::Choice: {
        std::string s;
        for (const auto& c : p.choices) s += (s.empty() ? "" : "|") + c;
        return "one of " + s;
    }
    case ParamType::Color: return "colour (r,g,b or grey)";
    case ParamType::Vector: return "point (x,y,z)";
    case ParamType::ColorList: return "colours (r,g,b;r,g,b;…)";
    case ParamType::NumberList: return "numbers (a;b;…)";
    }
    return "";
}

namespace {

bool isColor(const json& j)
{
    if (j.is_number()) return true;
    if (!j.is_array() || j.size() != 3) return false;
    for (const auto& c : j) {
        if (!c.is_number()) return false;
    }
    return true;
}

bool finiteNumbers(const json& j)
{
    if (j.is_number()) return std::isfinite(j.get<double>());
    if (j.is_array()) {
        for (const auto& c : j) {
            if (!finiteNumbers(c)) return false;
        }
    }
    return true;
}

void checkValue(const Operator& op, const Param& p, const json& v)
{
    const auto fail = [&](const std::string& why) {
        throw UsageError(fmt::format("{}: parameter '{}' {} (expected {})", op.name, p.name, why, describeType(p)));
    };
    bool ok = false;
    switch (p.type) {
    case ParamType::Number: ok = v.is_number(); break;
    case ParamType::Integer: ok = v.is_number_integer(); break;
    case ParamType::Boolean: ok = v.is_boolean(); break;
    case ParamType::Text: ok = v.is_string() && !v.get<std::string>().empty(); break;
    case ParamType::Choice:
        ok = v.is_string() && std::find(p.choices.begin(), p.choices.end(), v.get<std::string>()) != p.choices.end();
        break;
    case ParamType::Color: ok = isColor(v); break;
    case ParamType::Vector: ok = v.is_array() && v.size() == 3 && isColor(v); break;
    case ParamType::ColorList:
        ok = v.is_array() && v.size() >= 2 && std::all_of(v.begin(), v.end(), [](const json& c) { return isColor(c); });
        break;
    case ParamType::NumberList: ok = v.is_array() && std::all_of(v.begin(), v.end(), [](const json& c) { return c.is_number(); }); break;
    }
    if (!ok) fail(fmt::format("is {}", v.dump()));
    if (!finiteNumbers(v)) fail("is not finite");
    if (v.is_number() && (v.get<double>() < p.min || v.get<double>() > p.max)) fail(fmt::format("is {}, out of range", v.dump()));
}

} // namespace

Args checkArgs(const Operator& op, const json& values)
{
    if (!values.is_object()) throw UsageError(fmt::format("{}: parameters must be a JSON object", op.name));
    json out = json::object();
    for (auto it = values.begin(); it != values.end(); ++it) {
        const auto p = std::find_if(op.params.begin(), op.params.end(), [&](const Param& q) { return q.name == it.key(); });
        if (p == op.params.end()) {
            std::string known;
            for (const auto& q : op.params) known += (known.empty() ? "" : ", ") + q.name;
            throw UsageError(fmt::format("{}: unknown parameter '{}' (it takes: {})", op.name, it.key(), known));
        }
        checkValue(op, *p, it.value());
        out[it.key()] = it.value();
    }
    for (const auto& p : op.params) {
        if (p.when.empty() || !values.contains(p.name)) continue;
        const auto eq = p.when.find('=');
        const std::string key = p.when.substr(0, eq), wanted = p.when.substr(eq + 1);
        const auto owner = std::find_if(op.params.begin(), op.params.end(), [&](const Param& q) { return q.name == key; });
        const std::string actual = values.contains(key) ? values[key].get<std::string>() : owner->defaultValue.get<std::string>();
        if (actual != wanted) {
            throw UsageError(
                fmt::format("{}: parameter '{}' is unused with {}={} (it applies to {})", op.name, p.name, key, actual, p.when));
        }
    }
    for (const auto& p : op.params) {
        if (out.contains(p.name)) continue;
        if (p.defaultValue.is_null()) {
            if (p.summary.rfind("(optional)", 0) == 0) continue;
            throw UsageError(fmt::format("{}: parameter '{}' is required ({})", op.name, p.name, describeType(p)));
        }
        out[p.name] = p.defaultValue;
    }
    return Args(op.name, out);
}

json parseParamText(const Operator& op, const Param& p, const std::string& text)
{
    const auto fail = [&]() -> json {
        throw UsageError(fmt::format("{}: parameter '{}': cannot read '{}' as {}", op.name, p.name, text, describeType(p)));
    };
    const auto number = [&](const std::string& s) {
        std::size_t used = 0;
        double v = 0.0;
        try {
            v = std::stod(s, &used);
        } catch (const std::exception&) {
            fail();
        }
        if (used != s.size()) fail();
        return v;
    };
    const auto split = [](const std::string& s, char sep) {
        std::vector<std::string> parts;
        std::stringstream in(s);
        std::string part;
        while (std::getline(in, part, sep)) parts.push_back(part);
        return parts;
    };
    const auto colour = [&](const std::string& s) -> json {
        const auto parts = split(s, ',');
        if (parts.size() == 1) return number(parts[0]);
        if (parts.size() != 3) return fail();
        return json::array({number(parts[0]), number(parts[1]), number(parts[2])});
    };
    switch (p.type) {
    case ParamType::Number: return number(text);
    case ParamType::Integer: {
        const double v = number(text);
        if (v != std::floor(v) || std::abs(v) > 2e9) fail();
        return json(int(v));
    }
    case ParamType::Boolean:
        if (text == "true" || text == "1" || text == "on") return true;
        if (text == "false" || text == "0" || text == "off") return false;
        return fail();
    case ParamType::Text:
    case ParamType::Choice: return text;
    case ParamType::Color: return colour(text);
    case ParamType::Vector: {
        const json v = colour(text);
        if (!v.is_array()) fail();
        return v;
    }
    case ParamType::ColorList: {
        json list = json::array();
        for (const auto& c : split(text, ';')) list.push_back(colour(c));
        return list;
    }
    case ParamType::NumberList: {
        json list = json::array();
        for (const auto& c : split(text, ';')) list.push_back(number(c));
        return list;
    }
    }
    return fail();
}

// ---------------------------------------------------------------------------------------------
// The operators

namespace {

Param gridParam(const char* summary = "the grid to work on") { return text("grid", summary); }
Param outParam() { return text("out", "(optional) write the result as this grid instead of replacing the input"); }
Param withParam(const char* summary) { return text("with", summary); }
Param withFileParam() { return text("with_file", "(optional) take 'with' from this .vdb instead of the same file"); }

openvdb::GridBase::Ptr requireGrid(const VoxelSet& set, const std::string& op, const std::string& name)
{
    if (auto g = set.find(name)) return g;
    std::string names;
    for (const auto& g : set.grids()) names += (names.empty() ? "" : ", ") + g->getName();
    throw UsageError(fmt::format("{}: no grid named '{}' (the voxel set has: {})", op, name, names.empty() ? "none" : names));
}

/// The grid to write: the input itself, or a copy named `out`.
openvdb::GridBase::Ptr target(OpContext& ctx, const std::string& op)
{
    auto grid = requireGrid(ctx.set, op, ctx.args.text("grid"));
    if (!ctx.args.has("out") || ctx.args.text("out") == grid->getName()) return grid;
    auto copy = grid->deepCopyGrid();
    copy->setName(ctx.args.text("out"));
    ctx.set.put(copy);
    return copy;
}

/// Grid 'with' (B): from with_file when given, else from the set.
openvdb::GridBase::Ptr withGrid(OpContext& ctx, const std::string& op)
{
    if (ctx.args.has("with_file")) {
        const VoxelSet other = readVoxelSet(ctx.args.text("with_file"));
        return requireGrid(other, op, ctx.args.text("with"));
    }
    return requireGrid(ctx.set, op, ctx.args.text("with"));
}

const openvdb::BoolGrid* optionalSelection(OpContext& ctx, const std::string& op, const char* param, openvdb::BoolGrid::Ptr& keep)
{
    if (!ctx.args.has(param)) return nullptr;
    auto g = requireGrid(ctx.set, op, ctx.args.text(param));
    keep = openvdb::gridPtrCast<openvdb::BoolGrid>(g);
    if (!keep)
        throw UsageError(fmt::format(
            "{}: '{}' grid '{}' holds {} values; a selection is a bool grid (vxf op select)", op, param, g->getName(), g->valueType()));
    return keep.get();
}

std::string count(const openvdb::GridBase& g) { return fmt::format("{} active voxels", g.activeVoxelCount()); }

std::vector<Operator> makeRegistry()
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
    ops.push_back({"edit", "on a selection: set RGB, shift hue, scale saturation and value, add or remove voxels",
        {gridParam("a vec3s grid"), text("selection", "(optional) bool grid (vxf op select); default: every active voxel"),
            typed("set", ParamType::Color, "(optional) the new colour"), number("hue_shift", "degrees", 0.0, -360.0, 360.0),
            number("saturation", "saturation scale", 1.0, 0.0), number("value", "value scale", 1.0, 0.0),
            flag("add", "activate selected voxels that are inactive"), flag("remove", "deactivate the selected voxels"), outParam()},
        [](OpContext& ctx) {
            auto g = openvdb::gridPtrCast<openvdb::Vec3SGrid>(target(ctx, "edit"));
            if (!g) throw UsageError(fmt::format("edit: grid '{}' is not a vec3s grid", ctx.args.text("grid")));
            openvdb::BoolGrid::Ptr keep;
            const openvdb::BoolGrid* selection = optionalSelection(ctx, "edit", "selection", keep);
            EditOptions o;
            if (ctx.args.has("set")) o.set = ctx.args.color("set");
            o.hueShift = ctx.args.number("hue_shift");
            o.saturation = ctx.args.number("saturation");
            o.value = ctx.args.number("value");
            o.add = ctx.args.flag("add");
            o.remove = ctx.args.flag("remove");
            ops::edit(*g, selection, o);
            return fmt::format("edited '{}' ({})", g->getName(), count(*g));
        }});

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

} // namespace

const std::vector<Operator>& artistOperators()
{
    static const std::vector<Operator> ops = makeRegistry();
    return ops;
}

GridUse gridUse(const Operator& op, const Args& args)
{
    if (op.grids) return op.grids(args);
    GridUse use;
    for (const char* name : {"grid", "mask", "selection", "region", "topology"}) {
        if (args.has(name)) use.reads.insert(args.text(name));
    }
    if (args.has("with") && !args.has("with_file")) use.reads.insert(args.text("with"));
    if (args.has("out")) {
        use.writes.insert(args.text("out"));
    } else if (args.has("grid")) {
        use.writes.insert(args.text("grid"));
    }
    return use;
}

const Operator& findOperatorIn(const std::vector<Operator>& operators, const std::string& name)
{
    for (const auto& op : operators) {
        if (op.name == name) return op;
    }
    std::string names;
    for (const auto& op : operators) names += (names.empty() ? "" : ", ") + op.name;
    throw UsageError(fmt::format("no operator named '{}' (there are: {})", name, names));
}

// ---------------------------------------------------------------------------------------------
// Generated documents

std::string operatorTableMarkdown(const std::vector<Operator>& operators)
{
    std::string out = "| operator | what it does | parameters |\n|---|---|---|\n";
    for (const auto& op : operators) {
        std::string params;
        for (const auto& p : op.params) {
            std::string def = p.defaultValue.is_null() ? (p.summary.rfind("(optional)", 0) == 0 ? "optional" : "required")
                                                       : "default " + p.defaultValue.dump();
            params += fmt::format(
                "{}`{}` ({}, {}{})", params.empty() ? "" : "<br>", p.name, describeType(p), def, p.when.empty() ? "" : ", with " + p.when);
        }
        const auto escape = [](std::string text) { // a bare | would split the table's cell
            for (std::size_t at = text.find('|'); at != std::string::npos; at = text.find('|', at + 2)) text.replace(at, 1, "\\|");
            return text;
        };
        out += fmt::format("| `{}` | {} | {} |\n", op.name, escape(op.summary), escape(params));
    }
    return out;
}

namespace {

json paramSchema(const Param& p)
{
    json color = {{"oneOf",
        json::array({{{"type", "number"}}, {{"type", "array"}, {"items", {{"type", "number"}}}, {"minItems", 3}, {"maxItems", 3}}})}};
    json s;
    switch (p.type) {
    case ParamType::Number: s = {{"type", "number"}}; break;
    case ParamType::Integer: s = {{"type", "integer"}}; break;
    case ParamType::Boolean: s = {{"type", "boolean"}}; break;
    case ParamType::Text: s = {{"type", "string"}, {"minLength", 1}}; break;
    case ParamType::Choice: s = {{"enum", p.choices}}; break;
    case ParamType::Color: s = color; break;
    case ParamType::Vector: s = {{"type", "array"}, {"items", {{"type", "number"}}}, {"minItems", 3}, {"maxItems", 3}}; break;
    case ParamType::ColorList: s = {{"type", "array"}, {"items", color}, {"minItems", 2}}; break;
    case ParamType::NumberList: s = {{"type", "array"}, {"items", {{"type", "number"}}}}; break;
    }
    if (std::isfinite(p.min)) s["minimum"] = p.min;
    if (std::isfinite(p.max)) s["maximum"] = p.max;
    s["description"] = p.summary;
    if (!p.defaultValue.is_null()) s["default"] = p.defaultValue;
    return s;
}

} // namespace

json pipelineSchema(const std::vector<Operator>& operators)
{
    json opNames = json::array();
    json cases = json::array();
    for (const auto& op : operators) {
        opNames.push_back(op.name);
        json props = json::object();
        json required = json::array();
        for (const auto& p : op.params) {
            props[p.name] = paramSchema(p);
            if (p.defaultValue.is_null() && p.summary.rfind("(optional)", 0) != 0) required.push_back(p.name);
        }
        json params = {{"type", "object"}, {"additionalProperties", false}, {"properties", props}};
        if (!required.empty()) params["required"] = required;
        cases.push_back({{"if", {{"properties", {{"op", {{"const", op.name}}}}}, {"required", {"op"}}}},
            {"then", {{"properties", {{"params", params}}}}}});
    }
    return {{"$schema", "http://json-schema.org/draft-07/schema#"}, {"$id", "https://vxf.invalid/schemas/pipeline.schema.json"},
        {"title", "vxf pipeline (node graph)"},
        {"description",
            "Generated from the operator registry by `vxf op --schema`; do not edit (a test fails when it drifts). "
            "Named nodes: each reads a .vdb file, or applies an operator to the voxel set of its input node; "
            "outputs name the nodes to write."},
        {"type", "object"}, {"additionalProperties", false}, {"required", {"nodes", "outputs"}},
        {"properties",
            {{"nodes",
                 {{"type", "object"}, {"minProperties", 1},
                     {"additionalProperties",
                         {{"type", "object"}, {"additionalProperties", false},
                             {"properties",
                                 {{"file", {{"type", "string"}, {"minLength", 1}, {"description", "a source node: this .vdb"}}},
                                     {"op", {{"enum", opNames}}},
                                     {"input",
                                         {{"type", "string"}, {"minLength", 1},
                                             {"description",
                                                 "the node whose voxel set it edits (none for a source operator such as voxelize)"}}},
                                     {"with",
                                         {{"type", "string"}, {"minLength", 1},
                                             {"description",
                                                 "a node whose voxel set provides the operator's second input (its 'with' grid), instead "
                                                 "of with_file"}}},
                                     {"params", {{"type", "object"}}}}},
                             {"oneOf",
                                 json::array({{{"required", {"file"}},
                                                  {"not",
                                                      {{"anyOf",
                                                          json::array({{{"required", {"op"}}}, {{"required", {"input"}}},
                                                              {{"required", {"with"}}}})}}}},
                                     {{"required", {"op"}}, {"not", {{"required", {"file"}}}}}})},
                             {"allOf", cases}}}}},
                {"outputs",
                    {{"type", "object"}, {"description", "node name → .vdb path to write"},
                        {"additionalProperties", {{"type", "string"}, {"minLength", 1}}}}}}}};
}

} // namespace vxf::ops
