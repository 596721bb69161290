// The stages' defaults (vxf/core/StageDefaults.h): each is what the stage's options struct and a
// scene's settings start from, and every operator's default lies in its parameter's own range.
#include <vxf/core/StageDefaults.h>

#include <vxf/core/Scene.h>
#include <vxf/pipeline/Operators.h>
#include <vxf/render/Render.h>
#include <vxf/scatter/Scatter.h>
#include <vxf/voxelize/Voxelize.h>

#include <catch2/catch.hpp>

#include <algorithm>

TEST_CASE("the stages' options and a scene's settings start from the declared defaults", "[core][defaults]")
{
    const vxf::ScatterOptions scatter;
    CHECK(scatter.passes == vxf::defaults::kPasses);
    CHECK(scatter.pass.directions == vxf::defaults::kDirections);
    CHECK(scatter.pass.cutoff == vxf::defaults::kScatterCutoff);
    CHECK(scatter.tolerance == vxf::defaults::kTolerance);
    CHECK(scatter.coarseFactor == vxf::defaults::kCoarseFactor);
    CHECK(vxf::SweepSolveOptions().directions == vxf::defaults::kDirections);
    const vxf::RenderOptions render;
    CHECK(render.width == vxf::defaults::kWidth);
    CHECK(render.height == vxf::defaults::kHeight);
    CHECK(render.samples == vxf::defaults::kSamples);
    CHECK(render.cutoff == vxf::defaults::kRenderCutoff);
    CHECK(double(vxf::VoxelizeOptions().bandWidth) == vxf::defaults::kBand);
    const vxf::SceneSettings scene;
    CHECK(scene.dim == vxf::defaults::kDim);
    CHECK(scene.cutoff == vxf::defaults::kScatterCutoff);
    CHECK(scene.noiseLevel == vxf::defaults::kNoiseLevel);
    CHECK(scene.gatherDirections == vxf::defaults::kGatherDirections);
}

TEST_CASE("every operator's defaults pass its own checks", "[core][defaults]")
{
    int checked = 0;
    for (const vxf::ops::Operator& op : vxf::operators()) {
        INFO(op.name);
        // Each default given as a value (a mode's parameters only in their mode), required names as "x".
        nlohmann::json values = nlohmann::json::object();
        bool checkable = true;
        for (const vxf::ops::Param& p : op.params) {
            const bool optional = p.summary.rfind("(optional)", 0) == 0;
            if (p.defaultValue.is_null()) {
                if (optional) continue;
                if (p.type != vxf::ops::ParamType::Text) checkable = false;
                values[p.name] = "x";
                continue;
            }
            if (!p.when.empty()) {
                const auto eq = p.when.find('=');
                const auto owner = std::find_if(
                    op.params.begin(), op.params.end(), [&](const vxf::ops::Param& q) { return q.name == p.when.substr(0, eq); });
                if (owner == op.params.end() || owner->defaultValue != p.when.substr(eq + 1)) continue;
            }
            values[p.name] = p.defaultValue;
        }
        if (!checkable) continue;
        CHECK_NOTHROW(vxf::ops::checkArgs(op, values));
        ++checked;
    }
    CHECK(checked >= 20); // of them all: the others need a number or colour that has no default
}
