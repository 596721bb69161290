#include "OperatorOptions.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>

namespace vxf::cli {

namespace {

/// What --help shows after an option's name for a parameter of @a type.
const char* typeName(ops::ParamType type)
{
    switch (type) {
    case ops::ParamType::Number: return "NUMBER";
    case ops::ParamType::Integer: return "INT";
    case ops::ParamType::Boolean: return "";
    case ops::ParamType::Text: return "TEXT";
    case ops::ParamType::Choice: return "CHOICE";
    case ops::ParamType::Color: return "R,G,B";
    case ops::ParamType::Vector: return "X,Y,Z";
    case ops::ParamType::ColorList: return "COLOURS";
    case ops::ParamType::NumberList: return "NUMBERS";
    case ops::ParamType::PointList: return "X,Y,Z;…";
    }
    return "";
}

} // namespace

OperatorOptions::OperatorOptions(CLI::App& app, const ops::Operator& op, bool dashed, std::map<std::string, std::string> spelling)
    : mOp(&op)
    , mDashed(dashed)
    , mSpelling(std::move(spelling))
{
    for (const ops::Param& p : op.params) {
        const auto spelt = mSpelling.find(p.name);
        if (spelt != mSpelling.end() && spelt->second.empty()) continue;
        const bool optional = p.summary.rfind("(optional)", 0) == 0;
        const bool required = p.defaultValue.is_null() && !optional;
        const std::string def = required ? " [required]" : p.defaultValue.is_null() ? "" : " [default " + p.defaultValue.dump() + "]";
        std::string summary = optional ? p.summary.substr(11) : p.summary;
        if (!summary.empty()) summary[0] = char(std::toupper(static_cast<unsigned char>(summary[0])));
        const std::string help = p.type == ops::ParamType::Boolean ? summary : fmt::format("{} ({}){}", summary, ops::describeType(p), def);
        const std::string name = spelt != mSpelling.end() ? spelt->second : "--" + optionName(p);
        if (p.type == ops::ParamType::Boolean) {
            // A flag that is on by default, or the scene's unless given, can be turned off: --no-NAME.
            const bool negatable = p.defaultValue != false && spelt == mSpelling.end();
            const std::string off = "--no-" + optionName(p);
            app.add_flag_function(
                negatable ? name + ",!" + off : name,
                [this, key = p.name](std::int64_t count) { mValues[key] = count > 0 ? "true" : "false"; },
                !negatable                   ? summary
                    : p.defaultValue == true ? fmt::format("{} (on by default; {} turns it off)", summary, off)
                                             : fmt::format("{}; {} turns it off", summary, off));
            continue;
        }
        // Required ones are not CLI11-required: args() names what is missing with its type.
        app.add_option_function<std::string>(
               name, [this, key = p.name](const std::string& v) { mValues[key] = v; }, help)
            ->type_name(typeName(p.type));
    }
}

std::string OperatorOptions::optionName(const ops::Param& param) const
{
    std::string name = param.name;
    if (mDashed) std::replace(name.begin(), name.end(), '_', '-');
    return name;
}

std::string OperatorOptions::label(const ops::Param& param) const
{
    // `vxf op NAME`'s messages name the operator too (the command is `op`).
    const std::string op = mDashed ? "" : mOp->name + ": ";
    const auto spelt = mSpelling.find(param.name);
    if (spelt == mSpelling.end()) return op + "--" + optionName(param);
    if (spelt->second.empty()) return fmt::format("{}'{}'", op, param.name); // set by the command
    const auto comma = spelt->second.rfind(',');
    return op + (comma == std::string::npos ? spelt->second : spelt->second.substr(comma + 1));
}

nlohmann::json OperatorOptions::given() const
{
    nlohmann::json values = nlohmann::json::object();
    for (const auto& value : mValues) {
        const std::string& name = value.first; // (clang 14 captures no structured binding)
        const std::string& text = value.second;
        const auto p = std::find_if(mOp->params.begin(), mOp->params.end(), [&](const ops::Param& q) { return q.name == name; });
        values[name] = ops::parseParamText(*mOp, *p, text, [this](const ops::Operator&, const ops::Param& q) { return label(q); });
    }
    return values;
}

ops::Args OperatorOptions::args(const nlohmann::json& extra) const
{
    nlohmann::json values = given();
    values.update(extra);
    return ops::checkArgs(*mOp, values, [this](const ops::Operator&, const ops::Param& q) { return label(q); });
}

} // namespace vxf::cli
