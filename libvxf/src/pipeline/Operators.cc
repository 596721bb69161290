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
#include <vxf/voxelize/Voxelize.h>

#include <fmt/format.h>

namespace vxf {

using nlohmann::json;
using namespace ops;
using namespace ops::params;

namespace {

std::string count(const openvdb::GridBase& g) { return fmt::format("{} active voxels", g.activeVoxelCount()); }

/// The pipeline's stages as operators, so a graph can run the whole method.
std::vector<Operator> stageOperators()
{
    std::vector<Operator> ops;
    // Pipeline stages, so a graph can run the whole method.
    Operator voxelizeStage{"voxelize", "a mesh (file or builtin:NAME) to `surface` and `density` (a source node: no input)",
        {text("mesh", "mesh file (.obj .ply .off .stl) or builtin:candle|sphere|box"),
            integer("dim", "voxels along the mesh's longest side (ignored with voxel_size)", 128, 1, 1 << 20),
            number("voxel_size", "(optional) voxel size in world units", nullptr, 1e-30),
            number("band", "narrow band half width, voxels", 3.0, 1.0, 1000.0)},
        [](OpContext& ctx) {
            const std::string mesh = ctx.args.text("mesh");
            SceneObject object;
            object.name = "mesh";
            object.mesh = mesh;
            object.objectToWorld = openvdb::Mat4d::identity();
            VoxelizeOptions o;
            o.voxelSize = ctx.args.has("voxel_size") ? ctx.args.number("voxel_size") : 0.0;
            o.dim = o.voxelSize > 0.0 ? 0 : ctx.args.integer("dim");
            o.bandWidth = float(ctx.args.number("band"));
            ctx.set = voxelize(objectMesh(object), o, ctx.interrupter);
            return fmt::format("voxelized {} ({})", mesh, count(*ctx.set.find(grids::kDensity)));
        }};
    voxelizeStage.source = true;
    voxelizeStage.grids = [](const Args&) { return GridUse{{}, {grids::kSurface, grids::kDensity}}; };
    ops.push_back(voxelizeStage);
    // What the medium is made of, which every later stage reads.
    const std::set<std::string> mediumGrids = {grids::kSurface, grids::kDensity, grids::kSigmaA, grids::kSigmaS};

    ops.push_back({"light", "the light stage: `direct` and `scatter_source` from a scene's lights, material and occluders",
        {text("scene", "scene file (schemas/scene.schema.json)"),
            number("step", "march step, voxels (0: the scene's scatter.step, 1 unless set there, as vxf run lights it)", 0.0, 0.0, 64.0),
            number("cutoff", "stop marching below this transmittance", 1e-4, 0.0, 0.5),
            flag("march",
                "every light by a march per voxel and sample (the reference; slow) instead of one optical-depth sweep "
                "per direction for directional and environment lights")},
        [](OpContext& ctx) {
            const double step = ctx.args.number("step");
            if (step > 0.0 && step < 0.01) {
                throw UsageError(fmt::format("light: parameter 'step' {} is below 0.01 voxels (0 takes the scene's)", step));
            }
            const Scene scene = loadScene(ctx.args.text("scene"));
            DirectLightOptions o;
            o.march.step = step > 0.0 ? step : scene.settings.step;
            o.march.cutoff = ctx.args.number("cutoff");
            o.sweep = !ctx.args.flag("march");
            const auto report = lightScene(ctx.set, scene, o, ctx.interrupter);
            return fmt::format("lit by {} lights", report.lights.size());
        }});
    ops.back().grids = [mediumGrids](const Args&) {
        return GridUse{mediumGrids, {grids::kDirect, grids::kScatterSource, grids::kSourceAnisotropy}};
    };

    ops.push_back({"scatter", "the scatter stage: passes of source iteration into `scatter` and `illumination` (material from the file)",
        {integer("passes", "at most this many", 16, 0, 10000), integer("directions", "per voxel", 64, 1, 65536),
            number("step", "march step, voxels", 1.0, 0.01, 64.0),
            number("cutoff", "a march stops below this transmittance and adds the light beyond", 1e-3, 1e-12, 0.5),
            number("tolerance", "stop when the rest of the series is known to within this fraction of the sum, and add it", 1e-3, 0.0, 1.0),
            number("band", "adaptive band, world units (0: full resolution)", 0.0, 0.0), flag("extrapolate", "add the geometric tail"),
            flag("keep_passes", "keep scatter_pass_K"),
            integer("fine_passes", "passes at full resolution before the rest run on a coarser lattice (0: all)", 0, 0, 10000),
            integer("coarse_factor", "how much coarser (2, 4 or 8)", 4, 2, 8),
            choice("kernel", "gather (a march per voxel and direction) or sweep (one upwind sweep over the tree per direction)",
                {"gather", "sweep"}, "gather"),
            flag("no_accelerate",
                "plain source iteration (one scattering order per pass) instead of accelerated sweeps (a diffusion correction) or gathers "
                "(corrected by accelerated sweeps)")},
        [](OpContext& ctx) {
            ScatterOptions o;
            o.pass.kernel = scatterKernelNamed(ctx.args.text("kernel"));
            o.accelerate = !ctx.args.flag("no_accelerate");
            o.finePasses = ctx.args.integer("fine_passes");
            o.coarseFactor = ctx.args.integer("coarse_factor");
            o.passes = ctx.args.integer("passes");
            o.pass.directions = ctx.args.integer("directions");
            o.pass.step = ctx.args.number("step");
            o.pass.cutoff = ctx.args.number("cutoff");
            o.tolerance = ctx.args.number("tolerance");
            o.band = ctx.args.number("band");
            o.extrapolateTail = ctx.args.flag("extrapolate");
            o.keepPasses = ctx.args.flag("keep_passes");
            const Medium medium(ctx.set, recordedMaterial(ctx.set));
            const auto report = scatter(ctx.set, medium, o, ctx.interrupter);
            return fmt::format("{} passes ({})", report.passes.size(), report.stopReason);
        }});
    ops.back().grids = [mediumGrids](const Args& a) {
        GridUse use{mediumGrids, {grids::kScatter, grids::kIllumination, grids::kScatterAnisotropy}};
        use.reads.insert({grids::kDirect, grids::kScatterSource, grids::kSourceAnisotropy});
        if (a.flag("keep_passes")) {
            for (int k = 1; k <= a.integer("passes"); ++k) use.writes.insert(fmt::format("scatter_pass_{}", k));
        }
        return use;
    };

    ops.push_back({"render",
        "the renderer: writes an OpenEXR image (and a PNG preview) of the voxel set with a scene's camera; the set passes on unchanged",
        {text("scene", "scene file (camera, lights, objects, render settings)"), text("image", "the .exr to write"),
            text("png", "(optional) an sRGB PNG preview to write"),
            integer("width", "(optional) override the scene's width", nullptr, 1, 32768),
            integer("height", "(optional) override the scene's height", nullptr, 1, 32768),
            integer("samples", "(optional) override the samples per pixel", nullptr, 1, 65536),
            integer("max_samples",
                "(optional) override the scene's max_samples: adaptive, up to this many rays in a pixel whose first ones disagree", nullptr,
                0, 65536),
            number("noise_level", "(optional) override the scene's noise_level: the relative standard error a pixel may keep", nullptr,
                1e-6, 1.0)},
        [](OpContext& ctx) {
            const Scene scene = loadScene(ctx.args.text("scene"));
            RenderOptions o = renderOptionsFrom(scene.settings);
            if (ctx.args.has("width")) o.width = ctx.args.integer("width");
            if (ctx.args.has("height")) o.height = ctx.args.integer("height");
            if (ctx.args.has("samples")) o.samples = ctx.args.integer("samples");
            if (ctx.args.has("max_samples")) o.maxSamples = ctx.args.integer("max_samples");
            if (ctx.args.has("noise_level")) o.noiseLevel = ctx.args.number("noise_level");
            const Medium medium(ctx.set, recordedMaterial(ctx.set));
            const SceneRayScenes meshes = sceneRayScenes(scene);
            const RenderedImage image =
                vxf::render(ctx.set, medium, scene, o, {&meshes.visible, &meshes.occluders, &meshes.media}, ctx.interrupter);
            writeExr(ctx.args.text("image"), image);
            if (ctx.args.has("png")) writePng(ctx.args.text("png"), image);
            return fmt::format("rendered {}x{} to {}", o.width, o.height, ctx.args.text("image"));
        }});
    ops.back().grids = [mediumGrids](const Args&) {
        GridUse use{mediumGrids, {}};
        use.reads.insert({grids::kDirect, grids::kScatter, grids::kScatterAnisotropy});
        return use;
    };
    return ops;
}

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
