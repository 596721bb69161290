#include <vxf/io/JsonDocument.h>

#include <vxf/core/Error.h>

#include <fmt/format.h>
#include <valijson/adapters/nlohmann_json_adapter.hpp>
#include <valijson/schema.hpp>
#include <valijson/schema_parser.hpp>
#include <valijson/validator.hpp>

namespace vxf {

using nlohmann::json;

namespace {

/// The 1-based line and column of byte @a offset (0-based) of @a text.
std::pair<std::size_t, std::size_t> lineAndColumn(const std::string& text, std::size_t offset)
{
    std::size_t line = 1, column = 1;
    for (std::size_t i = 0; i < offset && i < text.size(); ++i) {
        if (text[i] == '\n') {
            ++line;
            column = 1;
        } else {
            ++column;
        }
    }
    return {line, column};
}

} // namespace

json parseJsonText(const std::string& text, const std::string& path)
{
    try {
        return json::parse(text);
    } catch (const json::parse_error& e) {
        // e.byte: the 1-based offset just past the error.
        const auto [line, column] = lineAndColumn(text, e.byte > 0 ? e.byte - 1 : 0);
        std::string what = e.what();
        const auto colon = what.find(": ", what.find("parse error"));
        if (colon != std::string::npos) what = what.substr(colon + 2);
        throw InputError(path, line, column, "invalid JSON: " + what);
    } catch (const json::out_of_range& e) {
        // A number beyond a double ("number overflow parsing '1e999'", found by fuzzing): placed at
        // the number the message quotes.
        std::string what = e.what();
        const auto bracket = what.find("] ");
        if (bracket != std::string::npos) what = what.substr(bracket + 2);
        const auto quote = what.find('\''), end = what.rfind('\'');
        const std::size_t at =
            quote != std::string::npos && end > quote ? text.find(what.substr(quote + 1, end - quote - 1)) : std::string::npos;
        const auto [line, column] = lineAndColumn(text, at == std::string::npos ? 0 : at);
        throw InputError(path, at == std::string::npos ? 0 : line, at == std::string::npos ? 0 : column, "invalid JSON: " + what);
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
