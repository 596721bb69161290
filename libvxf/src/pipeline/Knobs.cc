// vxf — the knob table (vxf/pipeline/Knobs.h): each setting of a scene's voxelize, scatter and
// render blocks declared once, and what is made from it.
#include <vxf/pipeline/Knobs.h>

#include <vxf/core/Error.h>
#include <vxf/core/StageDefaults.h>
#include <vxf/pipeline/SceneFile.h>
#include <vxf/voxelize/Voxelize.h>

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>

namespace vxf {

using nlohmann::json;
using namespace ops::params;

namespace {

/// A knob held as @a member of SceneSettings, written in the scene as it is held.
template <typename T>
Knob held(const char* block, ops::Param param, std::vector<Stage> readBy, T SceneSettings::*member, bool quality = false)
{
    return Knob{block, std::move(param), std::move(readBy), quality, [member](const SceneSettings& s) { return json(s.*member); },
        [member](SceneSettings& s, const json& v) { s.*member = v.get<T>(); }};
}

/// A colour knob: one number (grey) or three in the scene, a Vec3d held.
Knob colour(const char* block, ops::Param param, std::vector<Stage> readBy, openvdb::Vec3d SceneSettings::*member)
{
    return Knob{block, std::move(param), std::move(readBy), false,
        [member](const SceneSettings& s) {
            const openvdb::Vec3d& c = s.*member;
            return json::array({c[0], c[1], c[2]});
        },
        [member](SceneSettings& s, const json& v) {
            s.*member = v.is_number() ? openvdb::Vec3d(v.get<double>())
                                      : openvdb::Vec3d(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
        }};
}

/// A choice of two names held as a flag: @a member is true for the second (render mode "gather").
Knob namedFlag(const char* block, ops::Param param, std::vector<Stage> readBy, bool SceneSettings::*member, bool quality = false)
{
    const std::string off = param.choices.at(0), on = param.choices.at(1);
    return Knob{block, std::move(param), std::move(readBy), quality,
        [member, off, on](const SceneSettings& s) { return json(s.*member ? on : off); },
        [member, on](SceneSettings& s, const json& v) { s.*member = v.get<std::string>() == on; }};
}

using S = SceneSettings;

std::vector<Knob> voxelizeKnobs()
{
    const std::vector<Stage> voxelize{Stage::Voxelize};
    return {
        held("voxelize",
            integer("dim",
                "voxels along the mesh's longest side (ignored with voxel_size); a volume object keeps its own voxels unless "
                "dim or voxel_size is given, then they are coarsened by halvings (2x, 4x, ...) to the power of two nearest the "
                "size asked, never refined",
                defaults::kDim, 1, 1 << 20),
            voxelize, &S::dim),
        Knob{"voxelize", number("voxel_size", "(optional) voxel size in world units (instead of dim)", nullptr, kMinVoxelSize), voxelize,
            false, [](const S& s) { return s.voxelSize > 0.0 ? json(s.voxelSize) : json(); },
            [](S& s, const json& v) { s.voxelSize = v.get<double>(); }},
        held("voxelize", number("band", "narrow band half width in voxels, each side of the surface", defaults::kBand, 1.0, 1000.0),
            voxelize, &S::band),
    };
}

std::vector<Knob> scatterKnobs()
{
    const std::vector<Stage> scatter{Stage::Scatter};
    return {
        held("scatter",
            integer("passes",
                "at most this many passes (accelerated: sweeps or corrected gathers); 0: none, the scatter grid zero, single "
                "scattering alone (its image is the direct layer)",
                defaults::kPasses, 0, 10000),
            scatter, &S::passes, true),
        held("scatter", integer("directions", "directions per voxel (and per sweep)", defaults::kDirections, 1, 65536), scatter,
            &S::directions, true),
        held("scatter",
            number("step", "march step in voxels: the scatter's gathers, the light stage's marches and the camera's", defaults::kStep, 0.01,
                64.0),
            {Stage::Light, Stage::Scatter, Stage::Render}, &S::step, true),
        held("scatter",
            number("cutoff",
                "a scatter march stops where the transmittance falls below this and adds the light beyond it as the source "
                "held over an unbounded medium (1e-2 saves a third of the time for about 0.2% error on thick media)",
                defaults::kScatterCutoff, 1e-12, 0.5),
            scatter, &S::cutoff, true),
        held("scatter",
            number("tolerance",
                "stop when the rest of the series, estimated as phi_K r/(1-r), is known to within this fraction of the sum, "
                "and add it; accelerated, when the sum's estimated error is below it (0: never)",
                defaults::kTolerance, 0.0, 1.0),
            scatter, &S::tolerance, true),
        held("scatter",
            flag("extrapolate",
                "after the last pass add the geometric tail phi_K r/(1-r), r = phi_K/phi_(K-1) per voxel (fast convergence "
                "for albedo near 1)"),
            scatter, &S::extrapolate, true),
        held("scatter",
            number("band",
                "adaptive narrow band, world units: full resolution within this distance of the surface, the tree's 8^3 and "
                "128^3 tiles deeper (the light stage writes them as tiles of their means), each 8^3 block one cell of the "
                "accelerated sweeps (0: full resolution everywhere)",
                0.0, 0.0),
            {Stage::Light, Stage::Scatter}, &S::scatterBand),
        held("scatter",
            integer("fine_passes",
                "run the passes after the first N on a lattice coarse_factor times coarser (high scattering orders are "
                "smooth); their sum returns by a fine gather and correcting coarse cycles (0: all passes at full resolution)",
                0, 0, 10000),
            scatter, &S::finePasses, true),
        held("scatter",
            integerOf(
                "coarse_factor", "how much coarser the lattice of the passes after fine_passes is", defaults::kCoarseFactor, {2, 4, 8}),
            scatter, &S::coarseFactor, true),
        held("scatter",
            choice("kernel",
                "(optional) how a pass carries light: gather (a ray march per voxel and direction, the thesis's) or sweep "
                "(discrete ordinates: one upwind sweep over the tree per direction). Default: sweep for a forward-scattering "
                "phase (g > 0), whose anisotropy only the accelerated sweeps carry, gather otherwise",
                {"gather", "sweep"}, nullptr),
            scatter, &S::kernel, true),
        held("scatter",
            typed("accelerate", ops::ParamType::Boolean,
                "solve the whole sum with acceleration (each sweep corrected by diffusion, each gather by accelerated sweeps "
                "of its change) instead of plain source iteration, one scattering order per pass; kept passes, from_pass and "
                "fine_passes need the orders and turn it off",
                true),
            scatter, &S::accelerate, true),
    };
}

std::vector<Knob> renderKnobs()
{
    const std::vector<Stage> render{Stage::Render};
    return {
        held("render", integer("width", "image width in pixels", defaults::kWidth, 1, 32768), render, &S::width),
        held("render", integer("height", "image height in pixels", defaults::kHeight, 1, 32768), render, &S::height),
        held("render", integer("samples", "camera rays per pixel", defaults::kSamples, 1, 65536), render, &S::samples, true),
        held("render",
            integer("max_samples",
                "adaptive sampling: a pixel whose first samples disagree (silhouettes, object edges, or a relative standard "
                "error of its mean luminance above noise_level) gets more, up to this many in all (at most samples: off)",
                0, 0, 65536),
            render, &S::maxSamples),
        held("render",
            number("noise_level",
                "adaptive sampling's threshold: the relative standard error of a pixel's mean luminance above which it gets "
                "more samples",
                defaults::kNoiseLevel, 1e-6, 1.0),
            render, &S::noiseLevel, true),
        namedFlag("render",
            choice("mode",
                "view (physical: the camera ray marches on through the medium) or gather (the thesis's final gather: "
                "cosine-weighted marches into the volume)",
                {"view", "gather"}, "view"),
            render, &S::gather),
        held("render", integer("gather_directions", "gather mode: directions per hit", defaults::kGatherDirections, 1, 65536), render,
            &S::gatherDirections),
        held("render", typed("surface", ops::ParamType::Boolean, "add the surface term (Lambert and specular from the lights)", true),
            render, &S::surface),
        namedFlag("render",
            choice("direct",
                "(optional) single scattering: grid interpolates the light stage's direct grid (edits of it show); lights "
                "marches to the lights at every step of a camera ray (exact in dense media at any voxel size, and the only "
                "way an anisotropic phase shows in single scattering). Default: lights when the medium's phase g is not 0, "
                "grid otherwise",
                {"grid", "lights"}, nullptr),
            render, &S::directFromLights, true),
        colour("render",
            typed("background", ops::ParamType::Color,
                "radiance the camera sees where its rays leave the scene: an environment light lights the medium but is not "
                "seen unless this says so",
                0.0),
            render, &S::background),
    };
}

std::vector<Knob> declare()
{
    std::vector<Knob> all = voxelizeKnobs();
    for (auto block : {scatterKnobs, renderKnobs}) {
        for (Knob& k : block()) all.push_back(std::move(k));
    }
    return all;
}

/// Every field of SceneSettings is a knob above, or named here as not one: this binding stops
/// compiling when a field is added, so a new setting cannot be read without being declared.
[[maybe_unused]] void everySettingDeclared(const SceneSettings& s)
{
    [[maybe_unused]] const auto& [dim, voxelSize, band, passes, directions, step, tolerance, cutoff, extrapolate, scatterBand, finePasses,
        coarseFactor, kernel, accelerate, width, height, samples, gatherDirections, maxSamples, noiseLevel, gather, surface,
        directFromLights, background,
        outputs, // not a knob: the scene's `outputs`
        quality // not a knob: the scene's `quality`, which sets knobs
    ] = s;
}

/// A parameter's help as a sentence: "(optional) " dropped, the first letter capital, a full stop.
std::string sentence(const ops::Param& p)
{
    std::string text = p.summary.rfind("(optional) ", 0) == 0 ? p.summary.substr(11) : p.summary;
    if (!text.empty()) text[0] = char(std::toupper(static_cast<unsigned char>(text[0])));
    if (!text.empty() && text.back() != '.') text += '.';
    return text;
}

json propertySchema(const ops::Param& p)
{
    json s = {{"description", sentence(p)}};
    const auto range = [&](const char* type) {
        s["type"] = type;
        if (std::isfinite(p.min)) s["minimum"] = p.min;
        if (std::isfinite(p.max)) s["maximum"] = p.max;
    };
    switch (p.type) {
    case ops::ParamType::Integer:
        if (p.choices.empty()) {
            range("integer");
        } else {
            s["enum"] = json::array();
            for (const std::string& c : p.choices) s["enum"].push_back(std::stoi(c));
        }
        break;
    case ops::ParamType::Number: range("number"); break;
    case ops::ParamType::Boolean: s["type"] = "boolean"; break;
    case ops::ParamType::Choice: s["enum"] = p.choices; break;
    case ops::ParamType::Color: s["$ref"] = "#/definitions/rgb"; break;
    default: s["type"] = "string"; break;
    }
    if (!p.defaultValue.is_null()) s["default"] = p.defaultValue;
    return s;
}

} // namespace

bool Knob::reads(Stage stage) const { return std::find(readBy.begin(), readBy.end(), stage) != readBy.end(); }

const std::vector<Knob>& knobs()
{
    static const std::vector<Knob> all = declare();
    return all;
}

const Knob& findKnob(const std::string& block, const std::string& name)
{
    for (const Knob& k : knobs()) {
        if (k.block == block && k.param.name == name) return k;
    }
    throw Error(fmt::format("no knob /{}/{} is declared (pipeline/Knobs.cc)", block, name));
}

bool givesKnob(const json& document, const Knob& knob)
{
    return document.contains(knob.block) && document[knob.block].contains(knob.param.name);
}

void readKnobs(const json& document, SceneSettings& settings)
{
    for (const Knob& k : knobs()) {
        if (givesKnob(document, k)) k.set(settings, document[k.block][k.param.name]);
    }
}

json knobSchema(const std::string& block)
{
    json properties = json::object();
    for (const Knob& k : knobs()) {
        if (k.block == block) properties[k.param.name] = propertySchema(k.param);
    }
    return properties;
}

const json& sceneSchemaDocument()
{
    static const json schema = [] {
        json s = json::parse(sceneSchemaText());
        for (const char* block : {"voxelize", "scatter", "render"}) s["properties"][block]["properties"] = knobSchema(block);
        return s;
    }();
    return schema;
}

json stageSettingsKey(const SceneSettings& settings, Stage stage)
{
    json key = json::object();
    for (const Knob& k : knobs()) {
        if (k.reads(stage)) key[k.path()] = k.get(settings);
    }
    return key;
}

ops::Param sceneOverride(const Knob& knob)
{
    ops::Param p = knob.param;
    const std::string help = p.summary.rfind("(optional) ", 0) == 0 ? p.summary.substr(11) : p.summary;
    p.summary = fmt::format("(optional) {} (default: the scene's {})", help, knob.path());
    p.defaultValue = nullptr;
    return p;
}

} // namespace vxf
