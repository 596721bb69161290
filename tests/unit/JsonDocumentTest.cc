// JSON files (vxf/io/JsonDocument.h): syntax errors name the line and column, schema errors the
// JSON pointer and the schema.
#include <vxf/io/JsonDocument.h>

#include <vxf/core/Error.h>

#include <catch2/catch.hpp>

TEST_CASE("invalid JSON is named by file, line and column", "[io][json]")
{
    CHECK(vxf::parseJsonText("{\"a\": [1, 2]}", "s.json")["a"][1] == 2);
    try {
        vxf::parseJsonText("{\n  \"a\": 1,\n  \"b\": ]\n}", "s.json");
        FAIL("invalid JSON parsed");
    } catch (const vxf::InputError& e) {
        CHECK(e.path() == "s.json");
        CHECK(e.line() == 3);
        CHECK(e.column() > 0);
        CHECK(std::string(e.what()).find("invalid JSON") != std::string::npos);
    }
}

TEST_CASE("a schema names the value that breaks it by its JSON pointer", "[io][json]")
{
    const nlohmann::json schema = nlohmann::json::parse(R"({
        "type": "object",
        "properties": {"lights": {"type": "array", "items": {"type": "object",
            "properties": {"intensity": {"type": "number", "minimum": 0}}}}}
    })");
    const vxf::JsonSchema check(schema, "scene.schema.json");
    CHECK_NOTHROW(check.check(nlohmann::json::parse(R"({"lights": [{"intensity": 2}]})"), "s.json"));
    CHECK_THROWS_WITH(check.check(nlohmann::json::parse(R"({"lights": [{"intensity": 2}, {"intensity": -1}]})"), "s.json"),
        Catch::Contains("/lights/1/intensity") && Catch::Contains("scene.schema.json") && Catch::Contains("s.json"));
}
