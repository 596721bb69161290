// The pipeline's stage operators (vxf/pipeline/Operators.h): a stage's parameters and defaults
// are declared once. The operators' defaults give the stage options' defaults and a scene's,
// and the stage commands' options are those parameters.
#include <vxf/pipeline/Operators.h>

#include <vxf/core/StageDefaults.h>

#include <catch2/catch.hpp>

using nlohmann::json;

namespace {
vxf::ops::Args defaultsOf(const char* stage, json values = json::object()) { return vxf::ops::checkArgs(vxf::findOperator(stage), values); }
} // namespace

TEST_CASE("a stage operator's defaults are its options' and a scene's defaults", "[pipeline][operators]")
{
    const vxf::SceneSettings scene;

    const vxf::ScatterOptions plain;
    const vxf::ScatterOptions scatter = vxf::scatterOptions(defaultsOf("scatter"), vxf::Material{});
    CHECK(scatter.passes == plain.passes);
    CHECK(scatter.passes == scene.passes);
    CHECK(scatter.pass.directions == plain.pass.directions);
    CHECK(scatter.pass.directions == scene.directions);
    CHECK(scatter.pass.step == plain.pass.step);
    CHECK(scatter.pass.cutoff == plain.pass.cutoff);
    CHECK(scatter.pass.cutoff == scene.cutoff);
    CHECK(scatter.tolerance == plain.tolerance);
    CHECK(scatter.tolerance == scene.tolerance);
    CHECK(scatter.coarseFactor == plain.coarseFactor);
    CHECK(scatter.coarseFactor == scene.coarseFactor);
    CHECK(scatter.band == plain.band);
    CHECK(scatter.finePasses == plain.finePasses);
    CHECK(scatter.accelerate == plain.accelerate);
    CHECK(scatter.pass.rotatePerVoxel == plain.pass.rotatePerVoxel);
    CHECK(scatter.fromPass == plain.fromPass);

    const vxf::RenderOptions render = vxf::renderOptions(defaultsOf("render", {{"scene", "s.json"}, {"image", "i.exr"}}), scene);
    const vxf::RenderOptions plainRender;
    CHECK(render.width == plainRender.width);
    CHECK(render.height == plainRender.height);
    CHECK(render.samples == plainRender.samples);
    CHECK(render.noiseLevel == plainRender.noiseLevel);
    CHECK(render.gatherDirections == plainRender.gatherDirections);
    CHECK(render.step == plainRender.step);

    const vxf::VoxelizeOptions voxelize = vxf::voxelizeOptions(defaultsOf("voxelize", {{"mesh", "builtin:sphere"}}));
    CHECK(voxelize.dim == scene.dim);
    CHECK(double(voxelize.bandWidth) == scene.band);
    CHECK(double(vxf::VoxelizeOptions{}.bandWidth) == vxf::defaults::kBand);

    const vxf::DirectLightOptions light = vxf::lightOptions(defaultsOf("light", {{"scene", "s.json"}}), scene);
    CHECK(light.march.step == scene.step); // the scene's step unless given, as vxf run lights it
    CHECK(light.march.cutoff == vxf::defaults::kLightCutoff);
    CHECK(light.sweep);
}

TEST_CASE("the scatter stage picks its kernel by the phase unless named", "[pipeline][operators]")
{
    vxf::Material forward;
    forward.phaseG = 0.6;
    CHECK(vxf::scatterOptions(defaultsOf("scatter"), vxf::Material{}).pass.kernel == vxf::ScatterKernel::Gather);
    CHECK(vxf::scatterOptions(defaultsOf("scatter"), forward).pass.kernel == vxf::ScatterKernel::Sweep);
    CHECK(vxf::scatterOptions(defaultsOf("scatter", {{"kernel", "gather"}}), forward).pass.kernel == vxf::ScatterKernel::Gather);
    // Given parameters reach the options.
    const auto o = vxf::scatterOptions(
        defaultsOf("scatter", {{"passes", 3}, {"from_pass", 2}, {"fixed_directions", true}, {"accelerate", false}}), forward);
    CHECK(o.passes == 3);
    CHECK(o.fromPass == 2);
    CHECK_FALSE(o.pass.rotatePerVoxel);
    CHECK_FALSE(o.accelerate);
}

TEST_CASE("an integer of a few allowed values is checked against them", "[pipeline][operators]")
{
    CHECK_THROWS_WITH(defaultsOf("scatter", {{"coarse_factor", 3}}), "scatter: parameter 'coarse_factor' is 3 (expected one of 2|4|8)");
    CHECK(vxf::scatterOptions(defaultsOf("scatter", {{"coarse_factor", 8}}), vxf::Material{}).coarseFactor == 8);
    const json schema = vxf::pipelineSchema();
    CHECK(schema.dump().find(R"("enum":[2,4,8])") != std::string::npos);
}
