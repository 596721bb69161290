#include <vxf/pipeline/Operators.h>

#include <vxf/core/Error.h>
#include <vxf/io/VoxelSetFile.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <regex>
#include <set>

using nlohmann::json;

TEST_CASE("the registry: every operator named, summarized and typed once", "[ops][registry]")
{
    std::set<std::string> names;
    const std::regex snake("[a-z][a-z0-9_]*");
    for (const auto& op : vxf::operators()) {
        INFO(op.name);
        CHECK(names.insert(op.name).second);
        CHECK(std::regex_match(op.name, snake));
        CHECK(!op.summary.empty());
        CHECK(op.run);
        std::set<std::string> params;
        json sample = json::object(); // every default, and a value of its type for each required parameter
        for (const auto& p : op.params) {
            INFO(p.name);
            CHECK(params.insert(p.name).second);
            CHECK(std::regex_match(p.name, snake));
            CHECK(!p.summary.empty());
            if (!p.when.empty()) {
                // conditioned: its default applies only in its mode
            } else if (!p.defaultValue.is_null()) {
                sample[p.name] = p.defaultValue;
            } else if (p.type == vxf::ops::ParamType::Color) {
                sample[p.name] = 1.0;
            } else if (p.type == vxf::ops::ParamType::Text) {
                sample[p.name] = "density";
            }
        }
        CHECK_NOTHROW(vxf::ops::checkArgs(op, sample));
    }
    for (const char* expected : {"add", "sub", "mul", "div", "pow", "blend", "blur", "blur_special", "normalize", "denormalize",
             "gradient", "remove", "include", "select", "edit", "diff", "apply_diff", "split", "merge", "rename", "copy"}) {
        INFO(expected);
        CHECK(names.count(expected));
    }
}

TEST_CASE("bad parameters are errors naming the operator and the parameter", "[ops][registry]")
{
    const auto& blur = vxf::findOperator("blur");
    CHECK_THROWS_WITH(vxf::ops::checkArgs(blur, {{"grid", "d"}, {"radious", 2}}),
        Catch::Contains("blur: unknown parameter 'radious'") && Catch::Contains("radius"));
    CHECK_THROWS_WITH(vxf::ops::checkArgs(blur, {{"grid", "d"}, {"radius", 0}}),
        Catch::Contains("blur: parameter 'radius' is 0, out of range") && Catch::Contains("[1, 64]"));
    CHECK_THROWS_WITH(vxf::ops::checkArgs(blur, {{"grid", "d"}, {"radius", 1.5}}), Catch::Contains("parameter 'radius' is 1.5"));
    CHECK_THROWS_WITH(vxf::ops::checkArgs(blur, {{"grid", "d"}, {"kind", "gauss"}}), Catch::Contains("one of box|distance"));
    CHECK_THROWS_WITH(vxf::ops::checkArgs(blur, json::object()), Catch::Contains("blur: parameter 'grid' is required"));
    const auto& gradient = vxf::findOperator("gradient");
    CHECK_THROWS_WITH(vxf::ops::checkArgs(gradient, {{"radius", 2.0}}),
        Catch::Contains("gradient: parameter 'radius' is unused with kind=directional"));
    CHECK_NOTHROW(vxf::ops::checkArgs(gradient, {{"kind", "radial"}, {"radius", 2.0}}));
    CHECK_THROWS_WITH(vxf::ops::checkArgs(vxf::findOperator("blend"), {{"grid", "a"}, {"with", "b"}, {"weight", 0.2}}),
        Catch::Contains("'weight' is unused with mode=add"));
    const auto args = vxf::ops::checkArgs(blur, {{"grid", "d"}});
    CHECK(args.integer("radius") == 1); // default filled in
    CHECK_FALSE(args.has("mask"));       // optional, absent
    CHECK_THROWS_WITH(vxf::findOperator("blurr"), Catch::Contains("no operator named 'blurr'") && Catch::Contains("blur_special"));

    const auto& mul = vxf::findOperator("mul");
    const auto& value = mul.params[1];
    CHECK(vxf::ops::parseParamText(mul, value, "2") == json(2.0));
    CHECK(vxf::ops::parseParamText(mul, value, "1,0.5,2") == json::array({1.0, 0.5, 2.0}));
    CHECK_THROWS_WITH(vxf::ops::parseParamText(mul, value, "1,2"), Catch::Contains("mul: parameter 'value': cannot read '1,2'"));
    CHECK_THROWS_WITH(vxf::ops::parseParamText(mul, value, "two"), Catch::Contains("cannot read 'two'"));
    CHECK_THROWS_WITH(vxf::ops::checkArgs(mul, {{"grid", "d"}, {"value", json::array({1, 2})}}), Catch::Contains("parameter 'value' is [1,2]"));
}

TEST_CASE("an operator runs on a voxel set and leaves the other grids untouched", "[ops][registry]")
{
    vxf::VoxelSet set;
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->tree().setValueOn(openvdb::Coord(0), 0.5f);
    auto other = openvdb::FloatGrid::create(0.0f);
    other->setName("other");
    other->tree().setValueOn(openvdb::Coord(0), 7.0f);
    set.put(density);
    set.put(other);
    const auto& mul = vxf::findOperator("mul");
    const auto args = vxf::ops::checkArgs(mul, {{"grid", "density"}, {"value", 4}, {"out", "bright"}});
    vxf::ops::OpContext context{set, args, nullptr};
    CHECK(mul.run(context).find("mul on 'bright'") != std::string::npos);
    CHECK(set.get<openvdb::FloatGrid>("bright")->tree().getValue(openvdb::Coord(0)) == 2.0f);
    CHECK(set.get<openvdb::FloatGrid>("density")->tree().getValue(openvdb::Coord(0)) == 0.5f);
    CHECK(set.get<openvdb::FloatGrid>("other")->tree().getValue(openvdb::Coord(0)) == 7.0f);
    const auto missing = vxf::ops::checkArgs(mul, {{"grid", "nothing"}, {"value", 4}});
    vxf::ops::OpContext bad{set, missing, nullptr};
    CHECK_THROWS_WITH(mul.run(bad), Catch::Contains("mul: no grid named 'nothing'") && Catch::Contains("density"));
}

TEST_CASE("rename and copy: grids between files, resampled when asked; backgrounds kept", "[ops][registry]")
{
    vxf::test::TempDir dir;
    vxf::VoxelSet other(openvdb::math::Transform::createLinearTransform(0.5));
    auto warm = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    warm->setName("warm");
    warm->setTransform(other.transformPtr());
    warm->tree().fill(openvdb::CoordBBox(openvdb::Coord(-4), openvdb::Coord(4)), openvdb::Vec3f(1, 0.5f, 0.25f), true);
    other.put(warm);
    vxf::writeVoxelSet(dir.path("other.vdb"), other);

    vxf::VoxelSet set(openvdb::math::Transform::createLinearTransform(0.25));
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->setTransform(set.transformPtr());
    density->tree().setValueOn(openvdb::Coord(1), 1.0f);
    set.put(density);
    const auto run = [&](const char* name, const json& params) {
        const auto& op = vxf::findOperator(name);
        const auto args = vxf::ops::checkArgs(op, params);
        vxf::ops::OpContext context{set, args, nullptr};
        return op.run(context);
    };
    CHECK_THROWS_WITH(run("copy", {{"grid", "warm"}, {"from_file", dir.path("other.vdb")}}), Catch::Contains("resample"));
    run("copy", {{"grid", "warm"}, {"from_file", dir.path("other.vdb")}, {"to", "tint"}, {"resample", true}});
    auto tint = set.get<openvdb::Vec3SGrid>("tint");
    CHECK(tint->transform() == set.transform());
    CHECK(tint->tree().getValue(openvdb::Coord(0)) == openvdb::Vec3f(1, 0.5f, 0.25f)); // world 0 lies inside the box
    CHECK(tint->background() == openvdb::Vec3f(0.0f));
    run("rename", {{"grid", "tint"}, {"to", "Cd"}});
    CHECK(set.find("Cd"));
    CHECK_FALSE(set.find("tint"));
    CHECK_THROWS_WITH(run("rename", {{"grid", "Cd"}, {"to", "density"}}), Catch::Contains("exists already"));
    run("mul", {{"grid", "density"}, {"value", 3}});
    CHECK(set.get<openvdb::FloatGrid>("density")->background() == 0.0f);
}
