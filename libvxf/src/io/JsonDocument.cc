#include <vxf/io/JsonDocument.h>

#include <vxf/core/Error.h>

#include <fmt/format.h>
#include <valijson/adapters/nlohmann_json_adapter.hpp>
#include <valijson/schema.hpp>
#include <valijson/schema_parser.hpp>
#include <valijson/validator.hpp>

namespace vxf {

using nlohmann::json;

json parseJsonText(const std::string& text, const std::string& path)
{
    try {
        return json::parse(text);
    } catch (const json::parse_error& e) {
        // Locate e.byte (1-based offset just past the error) as line:column.
        std::size_t line = 1, column = 1;
        for (std::size_t i = 0; i + 1 < e.byte && i < text.size(); ++i) {
            if (text[i] == '\n') {
                ++line;
                column = 1;
            } else {
                ++column;
            }
        }
        std::string what = e.what();
        const auto colon = what.find(": ", what.find("parse error"));
        if (colon != std::string::npos) what = what.substr(colon + 2);
        throw InputError(path, line, column, "invalid JSON: " + what);
    }
}

namespace {

/// valijson's context ["<root>", "[lights]", "[0]"] as a JSON pointer "/lights/0".
std::string pointer(const std::vector<std::string>& context)
{
    std::string result;
    for (const auto& part : context) {
        if (part == "<root>") continue;
        std::string key = part;
        if (key.size() >= 2 && key.front() == '[' && key.back() == ']') key = key.substr(1, key.size() - 2);
        if (key.size() >= 2 && key.front() == '"' && key.back() == '"') key = key.substr(1, key.size() - 2);
        result += "/" + key;
    }
    return result.empty() ? "/" : result;
}

} // namespace

struct JsonSchema::Impl
{
    valijson::Schema schema;
};

JsonSchema::JsonSchema(const json& schema, std::string name)
    : mImpl(std::make_unique<Impl>())
    , mName(std::move(name))
{
    valijson::SchemaParser parser;
    valijson::adapters::NlohmannJsonAdapter adapter(schema);
    parser.populateSchema(adapter, mImpl->schema);
}

JsonSchema::~JsonSchema() = default;

void JsonSchema::check(const json& document, const std::string& path) const
{
    valijson::Validator validator;
    valijson::ValidationResults results;
    valijson::adapters::NlohmannJsonAdapter target(document);
    if (validator.validate(mImpl->schema, target, &results)) return;
    // Report the most specific violation (the deepest field).
    valijson::ValidationResults::Error error, best;
    std::size_t count = 0;
    while (results.popError(error)) {
        if (count++ == 0 || error.context.size() > best.context.size()) best = error;
    }
    throw InputError(path, 0, 0, fmt::format("{}: {} (checked against {})", pointer(best.context), best.description, mName));
}

} // namespace vxf
