#include <vxf/pipeline/Operators.h>

#include <vxf/core/GridRoles.h>
#include <vxf/core/ProceduralMesh.h>
#include <vxf/io/ImageFile.h>
#include <vxf/io/MeshFile.h>
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

/// What the medium is made of, which every stage after voxelize reads.
const std::set<std::string>& mediumGrids() { return Medium::gridsRead(); }

Operator voxelizeOperator()
{
    Operator op{"voxelize", "a mesh (file or builtin:NAME) to `surface` and `density` (a source node: no input)",
        {text("mesh", fmt::format("mesh file (.obj .ply .off .stl) or a built-in mesh: {}", fmt::join(builtinMeshNames(), ", "))),
            integer("dim", "voxels along the mesh's longest side (ignored with voxel_size)", defaults::kDim, 1, 1 << 20),
            number("voxel_size", "(optional) voxel size in world units (instead of dim)", nullptr, kMinVoxelSize),
            number("band", "narrow band half width in voxels, each side of the surface", defaults::kBand, 1.0, 1000.0)},
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
            number("step", "(optional) march step in voxels (default: the scene's scatter.step, 1 unless set, as vxf run lights it)",
                nullptr, 0.01, 64.0),
            number("cutoff", "stop marching below this transmittance", defaults::kLightCutoff, 0.0, 0.5),
            number("band",
                "(optional) adaptive band, world units: the grids' 8^3 leaves deeper inside than this written as tiles of their "
                "means, as the scatter stage's band takes its source (0: every voxel; default: the scene's scatter.band, as vxf "
                "run lights it)",
                nullptr, 0.0),
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
        {integer("passes", "at most this many passes (0: none, single scattering alone)", defaults::kPasses, 0, 10000),
            integer("directions", "directions per voxel", defaults::kDirections, 1, 65536),
            number("step", "march step in voxels", defaults::kStep, 0.01, 64.0),
            number("cutoff",
                "a march stops where the transmittance falls below this and adds the light beyond it as the source held over an "
                "unbounded medium (1e-2 saves a third of the time for about 0.2% error on thick media)",
                defaults::kScatterCutoff, 1e-12, 0.5),
            number("tolerance",
                "stop when the rest of the series, estimated as phi_K r/(1-r), is known to within this fraction of the sum, and add "
                "it; accelerated, when the sum's estimated error is below it (0: never)",
                defaults::kTolerance, 0.0, 1.0),
            number("band",
                "adaptive narrow band, world units: full resolution within this distance of the surface, the tree's 8^3 and 128^3 "
                "tiles deeper, each 8^3 block one cell of the accelerated sweeps (0: full resolution everywhere)",
                0.0, 0.0),
            flag("extrapolate", "after the last pass add the geometric tail phi_K r/(1-r), r = phi_K/phi_(K-1) per voxel"),
            flag("keep_passes", "keep each pass as scatter_pass_K"),
            integer("from_pass", "(optional) continue from scatter_pass_K (as edited) instead of scatter_source", nullptr, 1, 10000),
            integer("fine_passes",
                "run the passes after the first N on a coarser lattice (high orders are smooth; their sum returns by a fine gather "
                "and correcting coarse cycles) (0: all passes at full resolution)",
                0, 0, 10000),
            integerOf("coarse_factor", "how much coarser that lattice is", defaults::kCoarseFactor, {2, 4, 8}),
            choice("kernel",
                "(optional) how a pass carries light: gather (a ray march per voxel and direction, the thesis's) or sweep (discrete "
                "ordinates: one upwind sweep over the tree per direction). Default: sweep for a forward-scattering phase (g > 0), "
                "whose anisotropy only the accelerated sweeps carry, gather otherwise",
                {"gather", "sweep"}, nullptr),
            flag("no_accelerate",
                "plain source iteration, one scattering order per pass, instead of solving the whole sum with acceleration (each "
                "sweep corrected by diffusion, each gather by accelerated sweeps of its change); keep_passes, from_pass and "
                "fine_passes need the orders and imply this"),
            flag("fixed_directions", "the same direction set at every voxel (banding instead of noise)")},
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
        {text("scene", "scene file (camera, lights, objects, render settings)"), sceneFrame(), text("image", "the .exr to write"),
            text("png", "(optional) an sRGB PNG preview to write"), number("exposure", "the PNG's exposure in stops", 0.0, -64.0, 64.0),
            integer("width", "(optional) override the scene's width", nullptr, 1, 32768),
            integer("height", "(optional) override the scene's height", nullptr, 1, 32768),
            integer("samples", "(optional) override the samples per pixel", nullptr, 1, 65536),
            integer("max_samples",
                "(optional) adaptive sampling: pixels whose first samples disagree (silhouettes, object edges, noise above "
                "noise_level) get more, up to this many in all (overrides the scene's max_samples)",
                nullptr, 0, 65536),
            number("noise_level",
                "(optional) adaptive sampling's threshold: the relative standard error of a pixel's mean luminance (overrides the "
                "scene's noise_level)",
                nullptr, 1e-6, 1.0),
            choice("mode", "(optional) view or gather (overrides the scene's)", {"view", "gather"}, nullptr),
            flag("level_set", "hit the voxel set's `surface` level set instead of the scene's meshes"),
            flag("no_surface", "leave out the surface term"),
            flag("direct_from_lights",
                "march single scattering to the lights at every step instead of reading the `direct` grid (exact in dense media at "
                "any voxel size, and the only way an anisotropic phase shows in single scattering: the scene's default when its "
                "medium's phase g is not 0; edits of `direct` do not show)")},
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

VoxelizeOptions voxelizeOptions(const Args& args)
{
    VoxelizeOptions o;
    o.voxelSize = args.has("voxel_size") ? args.number("voxel_size") : 0.0;
    o.dim = o.voxelSize > 0.0 ? 0 : args.integer("dim");
    o.bandWidth = float(args.number("band"));
    return o;
}

DirectLightOptions lightOptions(const Args& args, const SceneSettings& settings)
{
    DirectLightOptions o;
    o.march.step = args.has("step") ? args.number("step") : settings.step;
    o.march.cutoff = args.number("cutoff");
    o.sweep = !args.flag("march");
    o.band = args.has("band") ? args.number("band") : settings.scatterBand;
    return o;
}

ScatterOptions scatterOptions(const Args& args, const Material& material)
{
    ScatterOptions o;
    o.passes = args.integer("passes");
    o.pass.directions = args.integer("directions");
    o.pass.step = args.number("step");
    o.pass.cutoff = args.number("cutoff");
    o.tolerance = args.number("tolerance");
    o.band = args.number("band");
    o.extrapolateTail = args.flag("extrapolate");
    o.keepPasses = args.flag("keep_passes");
    o.fromPass = args.has("from_pass") ? args.integer("from_pass") : 0;
    o.finePasses = args.integer("fine_passes");
    o.coarseFactor = args.integer("coarse_factor");
    const std::string kernel = args.has("kernel") ? args.text("kernel") : defaultScatterKernel(material.phaseG);
    o.pass.kernel = scatterKernelNamed(kernel);
    o.accelerate = !args.flag("no_accelerate");
    o.pass.rotatePerVoxel = !args.flag("fixed_directions");
    return o;
}

RenderOptions renderOptions(const Args& args, const SceneSettings& settings)
{
    RenderOptions o = renderOptionsFrom(settings);
    if (args.has("width")) o.width = args.integer("width");
    if (args.has("height")) o.height = args.integer("height");
    if (args.has("samples")) o.samples = args.integer("samples");
    if (args.has("max_samples")) o.maxSamples = args.integer("max_samples");
    if (args.has("noise_level")) o.noiseLevel = args.number("noise_level");
    if (args.has("mode")) o.gather = args.text("mode") == "gather";
    if (args.flag("no_surface")) o.surface = false;
    if (args.flag("direct_from_lights")) o.directFromLights = true;
    return o;
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
