// vxf — the operator registry: every artist operator declared once.
#pragma once

#include <vxf/core/Interrupter.h>
#include <vxf/core/VoxelSet.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <functional>
#include <limits>
#include <set>
#include <string>
#include <vector>

namespace vxf::ops {

enum class ParamType {
    Number, ///< a real number
    Integer, ///< a whole number
    Boolean, ///< a flag
    Text, ///< a grid name or file path
    Choice, ///< one of Param::choices
    Color, ///< linear RGB: one number (grey) or three
    Vector, ///< three numbers (a world-space point)
    ColorList, ///< two or more colours (a ramp)
    NumberList, ///< numbers (ramp positions)
    PointList ///< one or more world-space points (a brush stroke)
};

/// One typed parameter: its JSON/CLI name (snake_case), type, one-line summary, default
/// (null: required), inclusive range for numbers, and the choices of a Choice.
struct Param
{
    std::string name;
    ParamType type = ParamType::Number;
    std::string summary;
    nlohmann::json defaultValue; ///< null: required
    double min = -std::numeric_limits<double>::infinity(), max = std::numeric_limits<double>::infinity();
    std::vector<std::string> choices; ///< a Choice's names; an Integer's allowed values, when only some are
    /// "PARAM=VALUE" when the parameter means something only then (e.g. "kind=radial");
    /// giving it otherwise is an error ("unused parameter"). Empty: always used.
    std::string when;
};

/// Parameter values checked against an operator's declaration, defaults filled in.
class Args
{
public:
    Args(std::string op, nlohmann::json values)
        : mOp(std::move(op))
        , mValues(std::move(values))
    {
    }
    bool has(const std::string& name) const { return mValues.contains(name) && !mValues[name].is_null(); }
    double number(const std::string& name) const;
    int integer(const std::string& name) const;
    bool flag(const std::string& name) const;
    std::string text(const std::string& name) const;
    openvdb::Vec3d color(const std::string& name) const; ///< Color or Vector
    std::vector<openvdb::Vec3d> colors(const std::string& name) const;
    std::vector<double> numbers(const std::string& name) const;
    std::vector<openvdb::Vec3d> points(const std::string& name) const { return colors(name); }
    const nlohmann::json& json() const { return mValues; }

private:
    const nlohmann::json& at(const std::string& name) const;
    std::string mOp;
    nlohmann::json mValues;
};

/// Where an operator runs: the voxel set it edits in place, its checked arguments.
struct OpContext
{
    VoxelSet& set;
    const Args& args;
    Interrupter* interrupter = nullptr;
};

/// One operator: name (snake_case, as on the command line and in graphs), one-line summary,
/// parameters, and run, which edits the set and returns a one-line report.
/// The grids of the voxel set one call of an operator reads and writes (a removed or renamed
/// grid is written).
struct GridUse
{
    std::set<std::string> reads, writes;
};

struct Operator
{
    std::string name, summary;
    std::vector<Param> params;
    std::function<std::string(OpContext&)> run;
    bool source = false; ///< builds its voxel set from nothing (voxelize): no input node
    /// The grids a call reads and writes, from its checked arguments; empty: the common case
    /// (gridUse). Declared with the operator, so that what an edit invalidates (the view re-runs
    /// the scatter stage after an edit of what it reads) is known without a table kept by hand.
    std::function<GridUse(const Args&)> grids = nullptr;
};

/// What a call of @a op with @a args reads and writes: op.grids when declared, else the
/// common case: it reads `grid` and the grids named by `with`, `mask`, `selection`, `region`
/// and `topology` when given (`with_file`'s grid is another file's), and writes `out` when
/// given, else `grid` (edited in place).
GridUse gridUse(const Operator& op, const Args& args);

/// The artist operators, in the order help lists them. The pipeline stages a graph runs
/// (voxelize, light, scatter, render) are registered above them: vxf::operators()
/// (vxf/pipeline/Operators.h) holds both.
const std::vector<Operator>& artistOperators();

/// The operator of @a operators named @a name; vxf::UsageError listing the names otherwise.
const Operator& findOperatorIn(const std::vector<Operator>& operators, const std::string& name);

/// How an error message names a parameter: "OP: parameter 'NAME'" (paramLabel) in a graph or a
/// checked JSON; a command line names its option ("--cutoff"), the command being named before.
using ParamLabel = std::function<std::string(const Operator&, const Param&)>;
std::string paramLabel(const Operator& op, const Param& param);

/// Check @a values (a JSON object) against @a op: unknown parameters, parameters unused in the
/// chosen mode (Param::when), wrong types, values out of range or not among the choices, and
/// missing required ones are vxf::UsageError naming the operator and the parameter (@a label).
/// Defaults fill what is not given.
Args checkArgs(const Operator& op, const nlohmann::json& values, const ParamLabel& label = paramLabel);

/// Parse command-line text for @a param into JSON of its type (numbers, "r,g,b", "a,b,c;d,e,f",
/// true/false); vxf::UsageError naming the parameter (@a label) when it does not parse.
nlohmann::json parseParamText(const Operator& op, const Param& param, const std::string& text, const ParamLabel& label = paramLabel);

/// Human-readable type of a parameter ("number in [0, 1]", "one of box|distance", …).
std::string describeType(const Param& param);

/// The operator table (markdown) of @a operators.
std::string operatorTableMarkdown(const std::vector<Operator>& operators);

/// schemas/pipeline.schema.json, generated from the registry: a graph of named nodes, each an
/// operator with its checked parameters (or a file), and the outputs wanted.
nlohmann::json pipelineSchema(const std::vector<Operator>& operators);

/// Declaring parameters: Param{name, type, summary, default, range} spelled per type.
namespace params {

using json = nlohmann::json;

inline Param number(std::string name, std::string summary, json def, double lo = -INFINITY, double hi = INFINITY)
{
    return {std::move(name), ParamType::Number, std::move(summary), std::move(def), lo, hi, {}, {}};
}
inline Param integer(std::string name, std::string summary, json def, double lo, double hi)
{
    return {std::move(name), ParamType::Integer, std::move(summary), std::move(def), lo, hi, {}, {}};
}
/// An integer that must be one of @a values (e.g. a coarsening factor of 2, 4 or 8).
inline Param integerOf(std::string name, std::string summary, json def, const std::vector<int>& values)
{
    Param p{std::move(name), ParamType::Integer, std::move(summary), std::move(def), -INFINITY, INFINITY, {}, {}};
    for (int v : values) p.choices.push_back(std::to_string(v));
    return p;
}
inline Param flag(std::string name, std::string summary)
{
    return {std::move(name), ParamType::Boolean, std::move(summary), false, -INFINITY, INFINITY, {}, {}};
}
inline Param text(std::string name, std::string summary, json def = nullptr)
{
    return {std::move(name), ParamType::Text, std::move(summary), std::move(def), -INFINITY, INFINITY, {}, {}};
}
inline Param choice(std::string name, std::string summary, std::vector<std::string> choices, json def)
{
    return {std::move(name), ParamType::Choice, std::move(summary), std::move(def), -INFINITY, INFINITY, std::move(choices), {}};
}
inline Param typed(std::string name, ParamType type, std::string summary, json def = nullptr)
{
    return {std::move(name), type, std::move(summary), std::move(def), -INFINITY, INFINITY, {}, {}};
}

inline Param when(Param p, std::string condition)
{
    p.when = std::move(condition);
    return p;
}

} // namespace params

} // namespace vxf::ops
