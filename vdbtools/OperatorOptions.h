// vxf — an operator's parameters as a command's options, declared by the operator registry.
#pragma once

#include <vxf/ops/Registry.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <map>
#include <string>

namespace vxf::cli {

/// The options of `vxf op NAME` and of the stage commands (vxf voxelize, light, scatter,
/// render), generated from the operator's parameters, so that a parameter's name, type, range,
/// default and help are declared once, in the registry (a graph's nodes take the same ones).
/// Each parameter is `--name` (snake_case under `vxf op`; with '-' for '_' in a stage command,
/// @a dashed), its help the parameter's summary, type and default. @a spelling gives some
/// parameters another form: a positional name ("mesh") or "-o,--output"; an empty spelling
/// leaves the parameter out (the command sets it). Values are parsed and checked when args()
/// is called, errors naming the option as the user spelled it ("--cutoff is 0, out of range").
class OperatorOptions
{
public:
    OperatorOptions(CLI::App& app, const ops::Operator& op, bool dashed, std::map<std::string, std::string> spelling = {});

    /// The values given, parsed to JSON by type, not yet checked (what `--record` stores).
    nlohmann::json given() const;
    /// The checked arguments, defaults filled in, and @a extra values (parameters the command sets).
    ops::Args args(const nlohmann::json& extra = nlohmann::json::object()) const;
    /// Whether the user gave parameter @a name.
    bool has(const std::string& name) const { return mValues.count(name) != 0; }

private:
    std::string optionName(const ops::Param& param) const; ///< its name after `--`
    std::string label(const ops::Param& param) const; ///< how an error names it

    const ops::Operator* mOp;
    bool mDashed;
    std::map<std::string, std::string> mSpelling; ///< parameter → CLI11 option name
    std::map<std::string, std::string> mValues; ///< parameter → text as given
};

} // namespace vxf::cli
