// vxf — JSON documents (scenes, pipelines): parse with line:column errors, check against a schema.
#pragma once

#include <nlohmann/json.hpp>

#include <memory>
#include <string>

namespace vxf {

/// Parse @a text; a syntax error is a vxf::InputError naming @a path, line and column.
nlohmann::json parseJsonText(const std::string& text, const std::string& path);

/// A compiled JSON Schema (draft 7, valijson), checked once, reused.
class JsonSchema
{
public:
    /// @a name is how messages cite it, e.g. "schemas/scene.schema.json".
    JsonSchema(const nlohmann::json& schema, std::string name);
    ~JsonSchema();

    /// Throw vxf::InputError naming @a path, the most specific failing field (as a JSON
    /// pointer, e.g. /lights/1/cone_angle) and what was expected, when @a document fails.
    void check(const nlohmann::json& document, const std::string& path) const;

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
    std::string mName;
};

} // namespace vxf
