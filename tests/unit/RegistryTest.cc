#include <vxf/pipeline/Operators.h>

#include <vxf/core/Error.h>
#include <vxf/io/GridChecksum.h>
#include <vxf/io/VoxelSetFile.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <map>
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
            } else if (p.type == vxf::ops::ParamType::PointList) {
                sample[p.name] = json::array({json::array({0, 0, 0})});
            }
        }
        CHECK_NOTHROW(vxf::ops::checkArgs(op, sample));
    }
    for (const char* expected : {"add", "sub", "mul", "div", "pow", "blend", "blur", "blur_special", "normalize", "denormalize", "gradient",
             "remove", "include", "select", "edit", "diff", "apply_diff", "split", "merge", "rename", "copy", "delete", "paint", "noise"}) {
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
    CHECK_THROWS_WITH(
        vxf::ops::checkArgs(gradient, {{"radius", 2.0}}), Catch::Contains("gradient: parameter 'radius' is unused with kind=directional"));
    CHECK_NOTHROW(vxf::ops::checkArgs(gradient, {{"kind", "radial"}, {"radius", 2.0}}));
    CHECK_THROWS_WITH(vxf::ops::checkArgs(vxf::findOperator("blend"), {{"grid", "a"}, {"with", "b"}, {"weight", 0.2}}),
        Catch::Contains("'weight' is unused with mode=add"));
    const auto args = vxf::ops::checkArgs(blur, {{"grid", "d"}});
    CHECK(args.integer("radius") == 1); // default filled in
    CHECK_FALSE(args.has("mask")); // optional, absent
    CHECK_THROWS_WITH(vxf::findOperator("blurr"), Catch::Contains("no operator named 'blurr'") && Catch::Contains("blur_special"));

    const auto& mul = vxf::findOperator("mul");
    const auto& value = mul.params[1];
    CHECK(vxf::ops::parseParamText(mul, value, "2") == json(2.0));
    CHECK(vxf::ops::parseParamText(mul, value, "1,0.5,2") == json::array({1.0, 0.5, 2.0}));
    CHECK_THROWS_WITH(vxf::ops::parseParamText(mul, value, "1,2"), Catch::Contains("mul: parameter 'value': cannot read '1,2'"));
    CHECK_THROWS_WITH(vxf::ops::parseParamText(mul, value, "two"), Catch::Contains("cannot read 'two'"));
    CHECK_THROWS_WITH(
        vxf::ops::checkArgs(mul, {{"grid", "d"}, {"value", json::array({1, 2})}}), Catch::Contains("parameter 'value' is [1,2]"));
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

TEST_CASE("rename and copy: grids between files, resampled when asked, backgrounds kept", "[ops][registry]")
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

TEST_CASE("every operator writes exactly the grids it declares, and reads only grids it declares", "[ops][registry]")
{
    // A set with a grid of each kind the operators take; each operator runs once on its own copy.
    const auto makeSet = [] {
        vxf::VoxelSet set;
        auto density = openvdb::FloatGrid::create(0.0f);
        density->setName("density");
        auto color = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
        color->setName("color");
        auto color2 = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
        color2->setName("color2");
        auto mask = openvdb::BoolGrid::create(false);
        mask->setName("mask_in");
        for (int i = 0; i < 6; ++i) {
            const openvdb::Coord c(i, 0, 0); // a row: blur_special fills along it
            density->tree().setValueOn(c, 0.2f * float(i + 1));
            if (i < 4) color->tree().setValueOn(c, openvdb::Vec3s(0.1f * float(i), 0.5f, 0.2f)); // blur_special fills the rest
            color2->tree().setValueOn(c, openvdb::Vec3s(0.3f, 0.1f * float(i), 0.4f));
            if (i % 2) mask->tree().setValueOn(c, true);
        }
        for (const auto& g : std::vector<openvdb::GridBase::Ptr>{density, color, color2, mask}) set.put(g);
        return set;
    };
    const auto fingerprint = [](const vxf::VoxelSet& set) {
        std::map<std::string, std::string> out;
        for (const auto& g : set.grids()) {
            const auto sum = vxf::gridChecksum(*g, false);
            out[g->getName()] = sum ? std::to_string(*sum) : std::to_string(g->activeVoxelCount()) + g->valueType();
        }
        return out;
    };
    const std::map<std::string, nlohmann::json> samples = {{"add", {{"grid", "density"}, {"value", 2}}},
        {"sub", {{"grid", "density"}, {"value", 2}, {"out", "less"}}}, {"mul", {{"grid", "color"}, {"value", 2}}},
        {"div", {{"grid", "density"}, {"value", 2}}}, {"pow", {{"grid", "density"}, {"value", 2}}},
        {"blend", {{"grid", "color"}, {"with", "color2"}, {"mode", "mix"}}}, {"blur", {{"grid", "density"}, {"mask", "mask_in"}}},
        {"blur_special", {{"grid", "color"}}}, {"normalize", {{"grid", "density"}, {"out", "norm"}}}, {"denormalize", {{"grid", "norm"}}},
        {"gradient", {{"out", "ramp"}}}, {"remove", {{"grid", "density"}, {"with", "mask_in"}}},
        {"include", {{"grid", "mask_in"}, {"with", "density"}}}, {"select", {{"grid", "density"}, {"shape", "range"}, {"low", 0.5}}},
        {"edit", {{"grid", "color"}, {"selection", "mask_in"}, {"hue_shift", 40}}}, {"diff", {{"grid", "color"}, {"with", "color2"}}},
        {"apply_diff", {{"grid", "color"}, {"with", "color2"}}}, {"split", {{"grid", "color"}}},
        {"merge", {{"x", "density"}, {"y", "density"}, {"z", "density"}, {"out", "merged"}}},
        {"rename", {{"grid", "color2"}, {"to", "other"}}}, {"copy", {{"grid", "density"}, {"to", "copied"}}},
        {"delete", {{"grid", "color2"}}}, {"noise", {{"grid", "color"}, {"selection", "mask_in"}}},
        {"paint", {{"grid", "density"}, {"points", json::array({json::array({0, 0, 0})})}, {"radius", 2.0}, {"out", "painted"}}}};
    for (const auto& op : vxf::ops::artistOperators()) {
        CAPTURE(op.name);
        const auto sample = samples.find(op.name);
        REQUIRE(sample != samples.end()); // a new operator needs a sample here
        vxf::VoxelSet set = makeSet();
        if (op.name == "denormalize") {
            const auto& normalize = vxf::findOperator("normalize");
            vxf::ops::OpContext first{set, vxf::ops::checkArgs(normalize, {{"grid", "density"}, {"out", "norm"}}), nullptr};
            normalize.run(first);
        }
        const auto args = vxf::ops::checkArgs(op, sample->second);
        const vxf::ops::GridUse use = vxf::ops::gridUse(op, args);
        for (const auto& name : use.reads) {
            CAPTURE(name);
            CHECK(set.find(name));
        }
        const auto before = fingerprint(set);
        vxf::ops::OpContext context{set, args, nullptr};
        op.run(context);
        const auto after = fingerprint(set);
        std::set<std::string> changed;
        for (const auto& [name, sum] : before) {
            if (!after.count(name) || after.at(name) != sum) changed.insert(name);
        }
        for (const auto& [name, sum] : after) {
            if (!before.count(name)) changed.insert(name);
        }
        CHECK(changed == use.writes);
    }
}
