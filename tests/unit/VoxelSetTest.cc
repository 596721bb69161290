#include <vxf/core/VoxelSet.h>

#include <catch2/catch.hpp>

namespace {
openvdb::FloatGrid::Ptr namedGrid(const std::string& name, double voxelSize = 0.5)
{
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName(name);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(voxelSize));
    return grid;
}
} // namespace

TEST_CASE("a voxel set holds named grids sharing one transform", "[core][voxelset]")
{
    vxf::VoxelSet set;
    set.put(namedGrid("density"));
    CHECK(set.transform().voxelSize()[0] == 0.5); // the first grid defines it
    set.put(namedGrid("surface"));
    REQUIRE(set.grids().size() == 2);
    CHECK(set.grids()[0]->getName() == "density");
    CHECK(&set.grids()[1]->transform() == &set.transform()); // shared, not copied

    SECTION("replacing keeps the position")
    {
        auto replacement = namedGrid("density");
        replacement->tree().setValueOn(openvdb::Coord(0), 1.0f);
        set.put(replacement);
        REQUIRE(set.grids().size() == 2);
        CHECK(set.get<openvdb::FloatGrid>("density")->activeVoxelCount() == 1);
        CHECK(set.grids()[0]->getName() == "density");
    }
    SECTION("a different transform is refused with the grid's name")
    {
        CHECK_THROWS_WITH(set.put(namedGrid("direct", 0.25)), Catch::Contains("grid 'direct' does not share"));
    }
    SECTION("lookups name the missing or mistyped grid")
    {
        CHECK(set.find("nothing") == nullptr);
        CHECK_THROWS_WITH(set.get<openvdb::FloatGrid>("nothing"), "no grid named 'nothing' in the voxel set");
        CHECK_THROWS_WITH(set.get<openvdb::Vec3SGrid>("density"), "grid 'density' holds float values, expected vec3s");
    }
    SECTION("removal")
    {
        CHECK(set.remove("surface"));
        CHECK_FALSE(set.remove("surface"));
        CHECK(set.grids().size() == 1);
    }
}

TEST_CASE("an explicit transform wins over the grids'", "[core][voxelset]")
{
    vxf::VoxelSet set(openvdb::math::Transform::createLinearTransform(0.25));
    CHECK_THROWS_WITH(set.put(namedGrid("density", 0.5)), Catch::Contains("does not share"));
    set.put(namedGrid("density", 0.25));
    CHECK(&set.find("density")->transform() == &set.transform());
}

TEST_CASE("provenance is recorded in file metadata", "[core][voxelset]")
{
    vxf::VoxelSet set;
    CHECK(set.stage().empty());
    set.setProvenance("voxelize", R"({"dim":64})");
    CHECK(set.stage() == "voxelize");
    CHECK(set.paramsJson() == R"({"dim":64})");
    CHECK(set.metadata().metaValue<std::string>(vxf::kVersionMetaKey) == vxf::versionString());
}
