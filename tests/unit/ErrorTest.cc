#include <vxf/core/Error.h>

#include <catch2/catch.hpp>

TEST_CASE("InputError names file, line and column", "[core][error]")
{
    const vxf::InputError e("scene.vxf", 12, 7, "expected a number for grid 'color' r, found 'x'");
    CHECK(std::string(e.what()) == "scene.vxf:12:7: expected a number for grid 'color' r, found 'x'");
    CHECK(e.line() == 12);
    CHECK(e.column() == 7);
    CHECK(std::string(vxf::InputError("a.vxf", 3, 0, "bad").what()) == "a.vxf:3: bad");
    CHECK(std::string(vxf::InputError("a.vxf", 0, 0, "bad").what()) == "a.vxf: bad");
}

TEST_CASE("error hierarchy lets front ends tell usage from runtime errors", "[core][error]")
{
    CHECK_THROWS_AS(throw vxf::UsageError("x"), vxf::Error);
    CHECK_THROWS_AS(throw vxf::InputError("f", 1, 1, "x"), vxf::Error);
    CHECK_THROWS_AS(throw vxf::Interrupted(), vxf::Error);
}
