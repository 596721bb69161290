// The knob table (vxf/pipeline/Knobs.h): each setting declared once, and everything made from it
// agrees with it — the scene reader, the schema, the stage operators, the quality table's knobs
// and the cached stages' keys, which must change whenever what a stage reads does.
#include <vxf/pipeline/Knobs.h>

#include "pipeline/QualityPreset.h"

#include "TestSupport.h"

#include <vxf/pipeline/LightScene.h>
#include <vxf/pipeline/Operators.h>
#include <vxf/pipeline/SceneFile.h>
#include <vxf/pipeline/SceneMedium.h>
#include <vxf/render/Render.h>
#include <vxf/scatter/Scatter.h>

#include <catch2/catch.hpp>

#include <cmath>
#include <set>

using nlohmann::json;
using vxf::Knob;
using vxf::Stage;

namespace {

/// A valid value of @a knob other than its value in @a settings.
json otherValue(const Knob& knob, const vxf::SceneSettings& settings)
{
    const vxf::ops::Param& p = knob.param;
    const json now = knob.get(settings);
    switch (p.type) {
    case vxf::ops::ParamType::Boolean: return !now.get<bool>();
    case vxf::ops::ParamType::Color: return json::array({0.25, 0.5, 0.75});
    case vxf::ops::ParamType::Choice:
        for (const std::string& c : p.choices) {
            if (json(c) != now) return c;
        }
        break;
    case vxf::ops::ParamType::Integer:
        for (const std::string& c : p.choices) {
            if (json(std::stoi(c)) != now) return std::stoi(c);
        }
        return now.is_number() && now.get<double>() + 1 <= p.max ? now.get<int>() + 1 : int(p.min);
    case vxf::ops::ParamType::Number: {
        const double base = now.is_number() ? now.get<double>() : std::max(p.min, 0.0);
        const double up = base > 0.0 ? base * 1.5 : base + 0.5;
        return up <= p.max ? up : (base + std::max(p.min, 0.0)) / 2.0;
    }
    default: break;
    }
    FAIL("no other value for " << knob.path());
    return nullptr;
}

// What each stage's options are, field by field. The structured bindings stop compiling when a
// field is added to an options struct: the new field must be listed here, and so checked below.
json optionsJson(const vxf::VoxelizeOptions& o)
{
    const auto& [voxelSize, dim, bandWidth, lattice] = o;
    return {voxelSize, dim, bandWidth, lattice != nullptr};
}

json optionsJson(const vxf::DirectLightOptions& o)
{
    const auto& [march, coarseTiles, band, sweep, similarity, occluders, boundary] = o;
    const auto& [step, cutoff] = march;
    // similarity: keyed by RunPipeline's phase_scaling where the phase makes it matter (g ≠ 0).
    (void)similarity;
    return {step, cutoff, coarseTiles, band, sweep, occluders != nullptr, boundary != nullptr};
}

json optionsJson(const vxf::ScatterOptions& o)
{
    const auto& [passes, tolerance, keepPasses, fromPass, extrapolateTail, finePasses, coarseFactor, coarseCorrection, band, accelerate,
        warmStart, pass] = o;
    const auto& [kernel, directions, rotationSeed, step, cutoff, rotatePerVoxel, source] = pass;
    return {passes, tolerance, keepPasses, fromPass, extrapolateTail, finePasses, coarseFactor, coarseCorrection, band, accelerate,
        warmStart != nullptr, int(kernel), directions, rotationSeed, step, cutoff, rotatePerVoxel, int(source)};
}

json optionsJson(const vxf::RenderOptions& o)
{
    const auto& [width, height, samples, maxSamples, noiseLevel, gather, gatherDirections, surface, directFromLights, background, step,
        cutoff] = o;
    return {width, height, samples, maxSamples, noiseLevel, gather, gatherDirections, surface, directFromLights,
        {background[0], background[1], background[2]}, step, cutoff};
}

json stageOptions(const vxf::SceneSettings& s, Stage stage)
{
    switch (stage) {
    case Stage::Voxelize: return optionsJson(vxf::sceneVoxelizeOptions(s));
    case Stage::Light: return optionsJson(vxf::lightOptionsFrom(s));
    case Stage::Scatter: return optionsJson(vxf::scatterOptionsFrom(s));
    case Stage::Render: return optionsJson(vxf::renderOptionsFrom(s));
    }
    return nullptr;
}

const char* stageName(Stage stage)
{
    static const char* names[] = {"voxelize", "light", "scatter", "render"};
    return names[int(stage)];
}

/// A scene of a sphere, a light and a camera, with @a blocks.
std::string sceneWith(const json& blocks)
{
    json scene = {{"objects", {{{"mesh", "builtin:sphere"}, {"material", {{"albedo", 0.8}, {"mean_free_path", 0.2}}}}}},
        {"lights", {{{"type", "point"}, {"position", {0, 0, 3}}}}}, {"camera", {{"position", {0, -4, 0}}, {"look_at", {0, 0, 0}}}}};
    scene.update(blocks);
    return scene.dump();
}

} // namespace

TEST_CASE("every knob's default is a scene's default", "[pipeline][knobs]")
{
    const vxf::SceneSettings defaults;
    for (const Knob& k : vxf::knobs()) {
        INFO(k.path());
        if (k.param.defaultValue.is_null()) continue; // the medium chooses, or off until given
        vxf::SceneSettings s;
        k.set(s, k.param.defaultValue);
        CHECK(k.get(s) == k.get(defaults));
    }
    // Knobs of one block have one name each.
    std::set<std::string> paths;
    for (const Knob& k : vxf::knobs()) CHECK(paths.insert(k.path()).second);
}

TEST_CASE("every knob a scene gives reaches its settings", "[pipeline][knobs]")
{
    for (const Knob& k : vxf::knobs()) {
        const json value = otherValue(k, vxf::SceneSettings{});
        INFO(k.path() << " = " << value.dump());
        const vxf::Scene scene = vxf::parseScene(sceneWith({{k.block, {{k.param.name, value}}}}), "/scenes/k.json");
        CHECK(k.get(scene.settings) == value);
    }
    // Out of a knob's range: the schema, made from the knob, names it.
    CHECK_THROWS_WITH(
        vxf::parseScene(sceneWith({{"scatter", {{"coarse_factor", 3}}}}), "/scenes/k.json"), Catch::Contains("/scatter/coarse_factor"));
    CHECK_THROWS_WITH(vxf::parseScene(sceneWith({{"render", {{"samples", 0}}}}), "/scenes/k.json"), Catch::Contains("/render/samples"));
    CHECK_THROWS_WITH(vxf::parseScene(sceneWith({{"scatter", {{"no_such_knob", 1}}}}), "/scenes/k.json"), Catch::Contains("no_such_knob"));
}

TEST_CASE("a cached stage's key changes whenever what the stage reads changes, and only then", "[pipeline][knobs][cache]")
{
    // For each knob and stage: a changed knob that changes the stage's options must change its
    // key (else a stale entry is reused), and a knob the stage is declared to read must change
    // them (else the entry is recomputed for nothing). Both for the scatter kernels' defaults.
    for (const char* kernel : {"gather", "sweep"}) {
        vxf::SceneSettings base;
        base.kernel = kernel;
        for (const Knob& k : vxf::knobs()) {
            vxf::SceneSettings changed = base;
            k.set(changed, otherValue(k, base));
            for (Stage stage : {Stage::Voxelize, Stage::Light, Stage::Scatter, Stage::Render}) {
                INFO(k.path() << " in the " << stageName(stage) << " stage, kernel " << kernel);
                const bool optionsChange = stageOptions(base, stage) != stageOptions(changed, stage);
                const bool keyChanges = vxf::stageSettingsKey(base, stage) != vxf::stageSettingsKey(changed, stage);
                CHECK(optionsChange == keyChanges);
                CHECK(keyChanges == k.reads(stage));
            }
        }
    }
}

TEST_CASE("the committed scene schema's settings are what the knobs make", "[pipeline][knobs][schema][drift]")
{
    INFO("run scripts/generate to refresh schemas/scene.schema.json");
    CHECK(vxf::sceneSchemaDocument() == json::parse(vxf::test::slurp(vxf::test::source("schemas/scene.schema.json"))));
    const json scatter = vxf::knobSchema("scatter");
    CHECK(scatter["coarse_factor"]["enum"] == json::array({2, 4, 8}));
    CHECK(scatter["passes"]["minimum"] == 0);
    CHECK(scatter["passes"]["default"] == vxf::defaults::kPasses);
    CHECK_FALSE(scatter["kernel"].contains("default"));
}

TEST_CASE("the stage operators take the knobs: as they are, or as overrides of the scene's", "[pipeline][knobs][operators]")
{
    const auto param = [](const char* op, const std::string& name) -> const vxf::ops::Param* {
        for (const auto& p : vxf::findOperator(op).params) {
            if (p.name == name) return &p;
        }
        return nullptr;
    };
    for (const Knob& k : vxf::knobs()) {
        INFO(k.path());
        if (k.block == "voxelize" || k.block == "scatter") {
            const vxf::ops::Param* p = param(k.block.c_str(), k.param.name);
            REQUIRE(p);
            CHECK(p->defaultValue == k.param.defaultValue);
            CHECK(p->summary == k.param.summary);
        } else {
            const vxf::ops::Param* p = param("render", k.param.name);
            REQUIRE(p);
            CHECK(p->defaultValue.is_null());
            CHECK(p->summary.find("(default: the scene's " + k.path() + ")") != std::string::npos);
        }
    }
    // The light stage takes the scatter block's step and band, as vxf run lights.
    for (const char* name : {"step", "band"})
        CHECK(param("light", name)->summary.find("/scatter/" + std::string(name)) != std::string::npos);
    // An override given wins over the scene's; one not given keeps it.
    vxf::SceneSettings scene;
    scene.surface = false;
    scene.width = 33;
    const auto args = vxf::ops::checkArgs(vxf::findOperator("render"), {{"scene", "s.json"}, {"image", "i.exr"}, {"direct", "lights"}});
    const vxf::RenderOptions o = vxf::renderOptions(args, scene);
    CHECK(o.directFromLights);
    CHECK_FALSE(o.surface);
    CHECK(o.width == 33);
}

TEST_CASE("the quality table's knobs are declared knobs", "[pipeline][knobs][quality]")
{
    // Those the bench names in its own terms, each applied by Quality.cc's own rule.
    const std::set<std::string> own{"dim", "volume_dim", "band", "env_samples", "max_samples"};
    for (const auto& [name, scene] : vxf::detail::qualityTable().at("scenes").items()) {
        for (const json& row : scene.at("settings")) {
            for (const auto& [knob, value] : row.at("knobs").items()) {
                INFO(name << ": " << knob);
                if (own.count(knob)) continue;
                bool declared = false;
                for (const Knob& k : vxf::knobs()) declared = declared || (k.quality && k.param.name == knob);
                CHECK(declared);
            }
        }
    }
}
