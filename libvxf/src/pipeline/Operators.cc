#include <vxf/pipeline/Operators.h>

#include <vxf/core/GridRoles.h>
#include <vxf/core/ProceduralMesh.h>
#include <vxf/io/ImageFile.h>
#include <vxf/io/MeshFile.h>
#include <vxf/pipeline/Knobs.h>
#include <vxf/pipeline/LightScene.h>
#include <vxf/pipeline/SceneFile.h>
#include <vxf/pipeline/SceneGeometry.h>
#include <vxf/render/Render.h>
#include <vxf/scatter/Scatter.h>
#include <vxf/pipeline/SceneMedium.h>
#include <vxf/voxelize/Voxelize.h>

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace vxf {

using nlohmann::json;
using namespace ops;
using namespace ops::params;

namespace {

std::string count(const openvdb::GridBase& g) { return fmt::format("{} active voxels", g.activeVoxelCount()); }

/// @a first, then the knobs of the scene's @a block as parameters (declared once: Knobs.h) —
/// as optional overrides of the scene's values when @a overrides (a stage that reads a scene) —
/// then @a after.
std::vector<Param> withKnobs(std::vector<Param> first, const std::string& block, bool overrides, std::vector<Param> after = {})
{
    for (const Knob& k : knobs()) {
        if (k.block == block) first.push_back(overrides ? sceneOverride(k) : k.param);
    }
    first.insert(first.end(), after.begin(), after.end());
    return first;
}

/// @a settings with the knobs of @a block that @a args give.
SceneSettings overridden(SceneSettings settings, const Args& args, const std::string& block)
{
    for (const Knob& k : knobs()) {
        if (k.block == block && args.has(k.param.name)) k.set(settings, args.json()[k.param.name]);
    }
    return settings;
}

/// What the medium is made of, which every stage after voxelize reads.
const std::set<std::string>& mediumGrids() { return Medium::gridsRead(); }

Operator voxelizeOperator()
{
    Operator op{"voxelize", "a mesh (file or builtin:NAME) to `surface` and `density` (a source node: no input)",
        withKnobs(
            {text("mesh", fmt::format("mesh file (.obj .ply .off .stl) or a built-in mesh: {}", fmt::join(builtinMeshNames(), ", ")))},
            "voxelize", false),
        [](OpContext& ctx) {
            const std::string mesh = ctx.args.text("mesh");
            SceneObject object;
            object.name = "mesh";
            object.mesh = mesh;
            object.objectToWorld = openvdb::Mat4d::identity();
            ctx.set = voxelize(objectMesh(object), voxelizeOptions(ctx.args), ctx.interrupter);
            return fmt::format("voxelized {} ({})", mesh, count(*ctx.set.find(grids::kDensity)));
        }};
    op.source = true;
    op.grids = [](const Args&) { return GridUse{{}, {grids::kSurface, grids::kDensity}}; };
    return op;
}

/// The `frame` parameter of the stages that read a scene: an animated scene is read at it.
Param sceneFrame()
{
    return integer("frame",
        "(optional) the frame to read an animated scene at (keyframes, frame tokens; vxf run --frames renders them all)", nullptr, -999999,
        9999999);
}

Operator lightOperator()
{
    Operator op{"light", "the light stage: `direct` and `scatter_source` from a scene's lights, material and occluders",
        {text("scene", "scene file (schemas/scene.schema.json): material and lights"), sceneFrame(),
            sceneOverride(findKnob("scatter", "step")),
            number("cutoff", "stop marching below this transmittance", defaults::kLightCutoff, 0.0, 0.5),
            sceneOverride(findKnob("scatter", "band")),
            flag("march",
                "every light by a march per voxel and sample (the reference; slow). By default directional and environment lights "
                "take their transmittance from one optical-depth sweep over the medium per direction (the surface's rim is marched "
                "only along directions that graze it); point and spot lights from one sweep around the light, the voxels within "
                "3 of the surface marched; area lights are marched either way")},
        [](OpContext& ctx) {
            const Scene scene = stageScene(ctx.args);
            const auto report = lightScene(ctx.set, scene, lightOptions(ctx.args, scene.settings), ctx.interrupter);
            return fmt::format("lit by {} lights", report.lights.size());
        }};
    op.grids = [](const Args&) { return GridUse{mediumGrids(), {grids::kDirect, grids::kScatterSource, grids::kSourceAnisotropy}}; };
    return op;
}

Operator scatterOperator()
{
    Operator op{"scatter",
        "the scatter stage: passes of source iteration into `scatter` (their sum) and `illumination` (direct + scatter); reads "
        "`scatter_source` (or a kept pass), so edited grids are honoured; the material from the file",
        withKnobs({}, "scatter", false,
            {flag("keep_passes", "keep each pass as scatter_pass_K"),
                integer("from_pass", "(optional) continue from scatter_pass_K (as edited) instead of scatter_source", nullptr, 1, 10000),
                flag("fixed_directions", "the same direction set at every voxel (banding instead of noise)")}),
        [](OpContext& ctx) {
            const Material material = recordedMaterial(ctx.set);
            const ScatterOptions options = scatterOptions(ctx.args, material);
            const auto report = scatter(ctx.set, scatterMedium(ctx.set, material, options), options, ctx.interrupter);
            return fmt::format("{} passes ({})", report.passes.size(), report.stopReason);
        }};
    op.grids = [](const Args& a) {
        GridUse use{mediumGrids(), {grids::kScatter, grids::kIllumination, grids::kScatterAnisotropy}};
        use.reads.insert({grids::kDirect, grids::kScatterSource, grids::kSourceAnisotropy});
        if (a.has("from_pass")) use.reads.insert(fmt::format("scatter_pass_{}", a.integer("from_pass")));
        if (a.flag("keep_passes")) {
            for (int k = 1; k <= a.integer("passes"); ++k) use.writes.insert(fmt::format("scatter_pass_{}", k));
        }
        return use;
    };
    return op;
}

Operator renderOperator()
{
    Operator op{"render",
        "the renderer: writes an OpenEXR image (and a PNG preview) of the voxel set with a scene's camera; the set passes on unchanged",
        withKnobs(
            {text("scene", "scene file (camera, lights, objects, render settings)"), sceneFrame(), text("image", "the .exr to write"),
                text("png", "(optional) an sRGB PNG preview to write"), number("exposure", "the PNG's exposure in stops", 0.0, -64.0, 64.0),
                flag("level_set", "hit the voxel set's `surface` level set instead of the scene's meshes")},
            "render", true),
        [](OpContext& ctx) {
            const Scene scene = stageScene(ctx.args);
            const RenderOptions o = renderOptions(ctx.args, scene.settings);
            const Medium medium(ctx.set, recordedMaterial(ctx.set));
            const RenderedImage image = renderScene(ctx.set, medium, scene, o, ctx.args.flag("level_set"), ctx.interrupter);
            writeExr(ctx.args.text("image"), image);
            if (ctx.args.has("png")) writePng(ctx.args.text("png"), image, ctx.args.number("exposure"));
            return fmt::format("rendered {}x{} to {}", o.width, o.height, ctx.args.text("image"));
        }};
    op.grids = [](const Args&) { return GridUse{renderGrids(RenderOptions{}), {}}; };
    return op;
}

} // namespace

Scene stageScene(const Args& args)
{
    return loadScene(args.text("scene"), args.has("frame") ? std::optional<int>(args.integer("frame")) : std::nullopt);
}

VoxelizeOptions voxelizeOptions(const Args& args) { return sceneVoxelizeOptions(overridden(SceneSettings{}, args, "voxelize")); }

DirectLightOptions lightOptions(const Args& args, const SceneSettings& settings)
{
    // The scatter block's step and band (the light's own `cutoff` is not scatter.cutoff).
    SceneSettings s = settings;
    for (const char* name : {"step", "band"}) {
        if (args.has(name)) findKnob("scatter", name).set(s, args.json()[name]);
    }
    DirectLightOptions o = lightOptionsFrom(s);
    o.march.cutoff = args.number("cutoff");
    o.sweep = !args.flag("march");
    return o;
}

ScatterOptions scatterOptions(const Args& args, const Material& material)
{
    SceneSettings s;
    s.kernel = defaultScatterKernel(material.phaseG); // unless `kernel` is given
    ScatterOptions o = scatterOptionsFrom(overridden(s, args, "scatter"));
    o.keepPasses = args.flag("keep_passes");
    o.fromPass = args.has("from_pass") ? args.integer("from_pass") : 0;
    o.pass.rotatePerVoxel = !args.flag("fixed_directions");
    return o;
}

RenderOptions renderOptions(const Args& args, const SceneSettings& settings)
{
    return renderOptionsFrom(overridden(settings, args, "render"));
}

RenderedImage renderScene(
    const VoxelSet& set, const Medium& medium, const Scene& scene, const RenderOptions& options, bool levelSet, Interrupter* interrupter)
{
    SceneRayScenes meshes;
    if (levelSet) {
        meshes.occluders = sceneGeometry(scene, SceneObject::Role::Occluder);
    } else {
        meshes = sceneRayScenes(scene);
    }
    return render(set, medium, scene, options, {&meshes.visible, &meshes.occluders, &meshes.media}, interrupter);
}

namespace {

/// The pipeline's stages as operators, so a graph can run the whole method.
std::vector<Operator> stageOperators() { return {voxelizeOperator(), lightOperator(), scatterOperator(), renderOperator()}; }

} // namespace

const std::vector<Operator>& operators()
{
    static const std::vector<Operator> all = [] {
        std::vector<Operator> ops = artistOperators();
        for (Operator& stage : stageOperators()) ops.push_back(std::move(stage));
        return ops;
    }();
    return all;
}

const Operator& findOperator(const std::string& name) { return findOperatorIn(operators(), name); }

std::string operatorTableMarkdown() { return ops::operatorTableMarkdown(operators()); }

json pipelineSchema() { return ops::pipelineSchema(operators()); }

} // namespace vxf
