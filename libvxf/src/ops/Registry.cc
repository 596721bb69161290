#include <vxf/ops/Registry.h>

#include "OperatorGroups.h"

#include <vxf/core/GridRoles.h>

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
    case ParamType::Integer: {
        if (p.choices.empty()) return "integer" + range();
        std::string s;
        for (const auto& c : p.choices) s += (s.empty() ? "" : "|") + c;
        return "one of " + s;
    }
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
    case ParamType::PointList: return "points (x,y,z;x,y,z;…)";
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

void checkValue(const Operator& op, const Param& p, const json& v, const ParamLabel& label)
{
    const auto fail = [&](const std::string& why) {
        throw UsageError(fmt::format("{} {} (expected {})", label(op, p), why, describeType(p)));
    };
    bool ok = false;
    switch (p.type) {
    case ParamType::Number: ok = v.is_number(); break;
    case ParamType::Integer:
        ok = v.is_number_integer() &&
            (p.choices.empty() || std::find(p.choices.begin(), p.choices.end(), std::to_string(v.get<long long>())) != p.choices.end());
        break;
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
    case ParamType::PointList:
        ok = v.is_array() && !v.empty() && std::all_of(v.begin(), v.end(), [](const json& c) { return c.is_array() && isColor(c); });
        break;
    }
    if (!ok) fail(fmt::format("is {}", v.dump()));
    if (!finiteNumbers(v)) fail("is not finite");
    if (v.is_number() && (v.get<double>() < p.min || v.get<double>() > p.max)) fail(fmt::format("is {}, out of range", v.dump()));
}

} // namespace

std::string paramLabel(const Operator& op, const Param& param) { return fmt::format("{}: parameter '{}'", op.name, param.name); }

Args checkArgs(const Operator& op, const json& values, const ParamLabel& label)
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
        checkValue(op, *p, it.value(), label);
        out[it.key()] = it.value();
    }
    for (const auto& p : op.params) {
        if (p.when.empty() || !values.contains(p.name)) continue;
        const auto eq = p.when.find('=');
        const std::string key = p.when.substr(0, eq), wanted = p.when.substr(eq + 1);
        const auto owner = std::find_if(op.params.begin(), op.params.end(), [&](const Param& q) { return q.name == key; });
        const std::string actual = values.contains(key) ? values[key].get<std::string>() : owner->defaultValue.get<std::string>();
        if (actual != wanted) {
            throw UsageError(fmt::format("{} is unused with {}={} (it applies to {})", label(op, p), key, actual, p.when));
        }
    }
    for (const auto& p : op.params) {
        if (out.contains(p.name)) continue;
        if (p.defaultValue.is_null()) {
            if (p.summary.rfind("(optional)", 0) == 0) continue;
            throw UsageError(fmt::format("{} is required ({})", label(op, p), describeType(p)));
        }
        out[p.name] = p.defaultValue;
    }
    return Args(op.name, out);
}

json parseParamText(const Operator& op, const Param& p, const std::string& text, const ParamLabel& label)
{
    const auto fail = [&]() -> json { throw UsageError(fmt::format("{}: cannot read '{}' as {}", label(op, p), text, describeType(p))); };
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
    case ParamType::PointList: {
        json list = json::array();
        for (const auto& c : split(text, ';')) {
            const json point = colour(c);
            if (!point.is_array()) return fail();
            list.push_back(point);
        }
        return list;
    }
    }
    return fail();
}

// ---------------------------------------------------------------------------------------------
// The operators (their declarations: ValueOperators.cc, ColourOperators.cc, SelectionOperators.cc,
// GridOperators.cc)

const std::vector<Operator>& artistOperators()
{
    static const std::vector<Operator> ops = [] {
        std::vector<Operator> all;
        for (auto group : {valueOperators, colourOperators, selectionOperators, gridOperators}) {
            for (Operator& op : group()) all.push_back(std::move(op));
        }
        return all;
    }();
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
    case ParamType::Integer: {
        s = {{"type", "integer"}};
        if (!p.choices.empty()) {
            json values = json::array();
            for (const auto& c : p.choices) values.push_back(std::stoi(c));
            s["enum"] = values;
        }
        break;
    }
    case ParamType::Boolean: s = {{"type", "boolean"}}; break;
    case ParamType::Text: s = {{"type", "string"}, {"minLength", 1}}; break;
    case ParamType::Choice: s = {{"enum", p.choices}}; break;
    case ParamType::Color: s = color; break;
    case ParamType::Vector: s = {{"type", "array"}, {"items", {{"type", "number"}}}, {"minItems", 3}, {"maxItems", 3}}; break;
    case ParamType::ColorList: s = {{"type", "array"}, {"items", color}, {"minItems", 2}}; break;
    case ParamType::NumberList: s = {{"type", "array"}, {"items", {{"type", "number"}}}}; break;
    case ParamType::PointList:
        s = {{"type", "array"}, {"items", {{"type", "array"}, {"items", {{"type", "number"}}}, {"minItems", 3}, {"maxItems", 3}}},
            {"minItems", 1}};
        break;
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
