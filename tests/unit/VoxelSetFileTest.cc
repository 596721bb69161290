#include <vxf/io/VoxelSetFile.h>

#include <vxf/core/GridRoles.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

using vxf::test::TempDir;

namespace {

vxf::VoxelSet sampleSet()
{
    auto xform = openvdb::math::Transform::createLinearTransform(0.1);
    xform->postTranslate(openvdb::Vec3d(1.0, 2.0, 3.0));
    vxf::VoxelSet set(xform);
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->setTransform(xform);
    density->setGridClass(openvdb::GRID_FOG_VOLUME);
    density->tree().setValueOn(openvdb::Coord(1, 2, 3), 0.3f);
    density->tree().setValueOn(openvdb::Coord(-40, 2, 3), -2.5f); // artists use negatives
    density->tree().addTile(1, openvdb::Coord(128, 0, 0), 1.0f, true);
    set.put(density);
    auto color = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    color->setName("color");
    color->setTransform(xform);
    color->tree().setValueOn(openvdb::Coord(1, 2, 3), openvdb::Vec3f(0.1f, 1.7f, -0.25f));
    set.put(color);
    auto mask = openvdb::BoolGrid::create(false);
    mask->setName("mask");
    mask->setTransform(xform);
    mask->tree().setValueOn(openvdb::Coord(5, 5, 5), true);
    set.put(mask);
    set.setProvenance("voxelize", R"({"command":"voxelize","dim":64})");
    return set;
}

nlohmann::json metadataAsJson(const openvdb::MetaMap& meta)
{
    nlohmann::json j = nlohmann::json::object();
    for (auto it = meta.beginMeta(); it != meta.endMeta(); ++it) {
        j[it->first] = it->first == vxf::kParamsMetaKey ? nlohmann::json::parse(it->second->str()) : nlohmann::json(it->second->str());
    }
    return j;
}

} // namespace

TEST_CASE("voxel sets round-trip through .vdb files exactly", "[io][vdb]")
{
    TempDir dir;
    const vxf::VoxelSet set = sampleSet();
    const std::string path = dir.path("set.vdb");
    vxf::writeVoxelSet(path, set);
    const vxf::VoxelSet back = vxf::readVoxelSet(path);

    REQUIRE(back.grids().size() == 3);
    for (const auto& grid : set.grids()) {
        INFO(grid->getName());
        auto read = back.find(grid->getName());
        REQUIRE(read);
        std::string why;
        CHECK(vxf::test::identicalGrids(*grid, *read, &why));
        INFO(why);
        CHECK(&read->transform() == &back.transform());
    }
    CHECK(back.stage() == "voxelize");
    CHECK(back.paramsJson() == R"({"command":"voxelize","dim":64})");
    CHECK(back.metadata().metaValue<std::string>(vxf::kVersionMetaKey) == vxf::versionString());
    CHECK(back.find("density")->metaValue<std::string>(vxf::kUnitsMetaKey) == "fraction");
    CHECK(back.find("color")->metaValue<std::string>(vxf::kUnitsMetaKey) == "linear RGB");
    // The caller's grids were not touched by writing.
    CHECK_FALSE(set.find("density")->getMetadata<openvdb::StringMetadata>(vxf::kUnitsMetaKey));

    CHECK(vxf::test::schemaErrors(metadataAsJson(back.metadata()), "schemas/vxf-metadata.schema.json") == "");
}

TEST_CASE("a read can leave grids on disk and take them later, as they were", "[io][vdb]")
{
    TempDir dir;
    const vxf::VoxelSet set = sampleSet();
    const std::string path = dir.path("set.vdb");
    vxf::writeVoxelSet(path, set);
    vxf::VoxelSetReadOptions options;
    options.wanted = [](const std::string& name) { return name != "color"; };
    vxf::VoxelSet partial = vxf::readVoxelSet(path, options);
    CHECK(partial.grids().size() == 2);
    CHECK_FALSE(partial.find("color"));
    REQUIRE(partial.find("mask")); // the grid after the one left on disk is read as it is
    CHECK(vxf::test::identicalGrids(*set.find("mask"), *partial.find("mask")));
    vxf::readGridsInto(partial, path, {"color", "no such grid"});
    REQUIRE(partial.grids().size() == 3);
    std::string why;
    CHECK(vxf::test::identicalGrids(*set.find("color"), *partial.find("color"), &why));
    INFO(why);
    CHECK(&partial.find("color")->transform() == &partial.transform());
}

TEST_CASE("readGrids reads the grids named, voxelGridNames lists a file's grids, neither reads the others' data", "[io][vdb]")
{
    TempDir dir;
    const vxf::VoxelSet set = sampleSet();
    const std::string path = dir.path("set.vdb");
    vxf::writeVoxelSet(path, set);
    const vxf::VoxelSet one = vxf::readGrids(path, {"mask", "no such grid"});
    REQUIRE(one.grids().size() == 1);
    CHECK(vxf::test::identicalGrids(*set.find("mask"), *one.find("mask")));
    CHECK(one.stage() == set.stage()); // the file's metadata with it
    std::vector<std::string> names;
    for (const auto& grid : set.grids()) names.push_back(grid->getName());
    CHECK(vxf::voxelGridNames(path) == names);
    // Their data not read: a grid damaged on disk (the file's last bytes, the last grid's data)
    // stops neither unless it is asked for.
    std::string bytes = vxf::test::slurp(path);
    REQUIRE(bytes.size() > 64);
    for (std::size_t i = bytes.size() - 32; i < bytes.size() - 8; ++i) bytes[i] = char(~bytes[i]);
    vxf::test::spit(path, bytes);
    const std::string last = names.back();
    CHECK_THROWS_WITH(vxf::readVoxelSet(path), Catch::Contains("'" + last + "'"));
    CHECK(vxf::voxelGridNames(path) == names);
    CHECK(vxf::readGrids(path, {names.front()}).grids().size() == 1);
    CHECK_THROWS_WITH(vxf::readGrids(path, {last}), Catch::Contains("'" + last + "'"));
}

TEST_CASE("the metadata schema rejects what it should", "[io][vdb][schema]")
{
    const std::string schema = "schemas/vxf-metadata.schema.json";
    CHECK(vxf::test::schemaErrors(
              {{"vxf:version", "0.1.0"}, {"vxf:stage", "voxelize"}, {"vxf:params", {{"command", "voxelize"}}}}, schema) == "");
    CHECK_THAT(
        vxf::test::schemaErrors({{"vxf:version", "one"}, {"vxf:stage", "voxelize"}, {"vxf:params", nlohmann::json::object()}}, schema),
        Catch::StartsWith("document: /vxf:version: "));
    CHECK_THAT(vxf::test::schemaErrors({{"vxf:version", "0.1.0"}, {"vxf:stage", "bake"}, {"vxf:params", nlohmann::json::object()}}, schema),
        Catch::StartsWith("document: /vxf:stage: "));
    CHECK_THAT(vxf::test::schemaErrors({{"vxf:version", "0.1.0"}}, schema), Catch::StartsWith("document: "));
}

TEST_CASE("grids vxf does not know pass through untouched", "[io][vdb]")
{
    TempDir dir;
    vxf::VoxelSet set = sampleSet();
    auto ids = openvdb::Int32Grid::create(-1);
    ids->setName("piece_id");
    ids->setTransform(openvdb::math::Transform::createLinearTransform(0.37)); // its own transform
    ids->tree().setValueOn(openvdb::Coord(9, 9, 9), 42);
    ids->insertMeta("houdini_attr", openvdb::StringMetadata("keep me"));
    set.putAsIs(ids);
    set.metadata().insertMeta("creator", openvdb::StringMetadata("Houdini 20"));
    const std::string first = dir.path("a.vdb"), second = dir.path("b.vdb");
    vxf::writeVoxelSet(first, set);
    vxf::writeVoxelSet(second, vxf::readVoxelSet(first));
    const vxf::VoxelSet back = vxf::readVoxelSet(second);
    auto readIds = back.find("piece_id");
    REQUIRE(readIds);
    CHECK(vxf::test::identicalGrids(*ids, *readIds));
    CHECK(readIds->voxelSize()[0] == Approx(0.37));
    CHECK(readIds->metaValue<std::string>("houdini_attr") == "keep me");
    CHECK(back.metadata().metaValue<std::string>("creator") == "Houdini 20");
    CHECK(back.transform().voxelSize()[0] == Approx(0.1)); // the roles' transform, not piece_id's
}

TEST_CASE("half-float storage (the --half flag)", "[io][vdb]")
{
    TempDir dir;
    vxf::VoxelSetWriteOptions options;
    options.half = true;
    vxf::writeVoxelSet(dir.path("half.vdb"), sampleSet(), options);
    vxf::writeVoxelSet(dir.path("full.vdb"), sampleSet());
    const auto half = vxf::readVoxelSet(dir.path("half.vdb"));
    const float value = half.get<openvdb::Vec3SGrid>("color")->tree().getValue(openvdb::Coord(1, 2, 3))[1];
    CHECK(value != 1.7f);
    CHECK(value == Approx(1.7f).epsilon(1e-3));
    CHECK(std::filesystem::file_size(dir.path("half.vdb")) < std::filesystem::file_size(dir.path("full.vdb")));
}

TEST_CASE("unreadable .vdb files are reported with their path", "[io][vdb]")
{
    TempDir dir;
    CHECK_THROWS_WITH(vxf::readVoxelSet(dir.path("missing.vdb")), Catch::EndsWith("missing.vdb: no such file"));
    vxf::test::spit(dir.path("text.vdb"), "this is not a vdb\n");
    CHECK_THROWS_WITH(vxf::readVoxelSet(dir.path("text.vdb")), Catch::Contains("text.vdb: not a readable OpenVDB file"));
    // A truncated file (the first half of a real one).
    vxf::writeVoxelSet(dir.path("full.vdb"), sampleSet());
    const std::string bytes = vxf::test::slurp(dir.path("full.vdb"));
    vxf::test::spit(dir.path("cut.vdb"), bytes.substr(0, bytes.size() / 2));
    CHECK_THROWS_WITH(vxf::readVoxelSet(dir.path("cut.vdb")), Catch::Contains("cut.vdb"));
}
