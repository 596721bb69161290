// vxf — the operator registry: every artist operator declared once.
#pragma once

#include <vxf/core/Interrupter.h>
#include <vxf/core/VoxelSet.h>

#include <nlohmann/json.hpp>

#include <functional>
#include <string>
#include <vector>

namespace vxf::ops {

enum class ParamType
{
    Number,    ///< a real number
    Integer,   ///< a whole number
    Boolean,   ///< a flag
    Text,      ///< a grid name or file path
    Choice,    ///< one of Param::choices
    Color,     ///< linear RGB: one number (grey) or three
    Vector,    ///< three numbers (a world-space point)
    ColorList, ///< two or more colours (a ramp)
    NumberList ///< numbers (ramp positions)
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
    std::vector<std::string> choices;
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
    openvdb::Vec3d color(const std::string& name) const;  ///< Color or Vector
    std::vector<openvdb::Vec3d> colors(const std::string& name) const;
    std::vector<double> numbers(const std::string& name) const;
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
struct Operator
{
    std::string name, summary;
    std::vector<Param> params;
    std::function<std::string(OpContext&)> run;
    bool source = false; ///< builds its voxel set from nothing (voxelize): no input node
};

/// Every operator, in the order help lists them: the artist operators, then the pipeline
/// stages a graph can run (voxelize, light, scatter).
const std::vector<Operator>& registry();

/// The operator named @a name; vxf::UsageError listing the names otherwise.
const Operator& findOperator(const std::string& name);

/// Check @a values (a JSON object) against @a op: unknown parameters, parameters unused in the
/// chosen mode (Param::when), wrong types, values out of range or not among the choices, and
/// missing required ones are vxf::UsageError naming the operator and the parameter. Defaults
/// fill what is not given.
Args checkArgs(const Operator& op, const nlohmann::json& values);

/// Parse command-line text for @a param into JSON of its type (numbers, "r,g,b", "a,b,c;d,e,f",
/// true/false); vxf::UsageError naming the operator and parameter when it does not parse.
nlohmann::json parseParamText(const Operator& op, const Param& param, const std::string& text);

/// Human-readable type of a parameter ("number in [0, 1]", "one of box|distance", …).
std::string describeType(const Param& param);

/// The README's operator table (markdown), generated from the registry.
std::string operatorTableMarkdown();

/// schemas/pipeline.schema.json, generated from the registry: a graph of named nodes, each an
/// operator with its checked parameters (or a file), and the outputs wanted.
nlohmann::json pipelineSchema();

} // namespace vxf::ops
