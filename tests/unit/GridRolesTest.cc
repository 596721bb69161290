#include <vxf/core/GridRoles.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

TEST_CASE("grid roles are found by name", "[core][roles]")
{
    REQUIRE(vxf::findGridRole("surface") != nullptr);
    CHECK(vxf::findGridRole("surface")->gridClass == openvdb::GRID_LEVEL_SET);
    CHECK(vxf::findGridRole("density")->gridClass == openvdb::GRID_FOG_VOLUME);
    CHECK(vxf::findGridRole("scatter_pass_3")->name == "scatter_pass_K");
    CHECK(vxf::findGridRole("scatter_pass_12")->name == "scatter_pass_K");
    CHECK(vxf::findGridRole("scatter_pass_") == nullptr);
    CHECK(vxf::findGridRole("scatter_pass_x") == nullptr);
    CHECK(vxf::findGridRole("temperature") == nullptr);
}

TEST_CASE("every role is specified in schemas/voxelset.md", "[core][roles][schema]")
{
    const std::string spec = vxf::test::slurp(vxf::test::source("schemas/voxelset.md"));
    REQUIRE(!spec.empty());
    for (const auto& role : vxf::gridRoles()) {
        INFO(role.name);
        CHECK(spec.find("| `" + role.name + "` |") != std::string::npos);
        CHECK(spec.find(role.units) != std::string::npos);
    }
}
