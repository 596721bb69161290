// vxf — the `quality` setting: the accuracy bench's table read for a scene (QualityPreset.h).
#include "QualityPreset.h"

#include <vxf/core/Error.h>
#include <vxf/pipeline/Knobs.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vxf {

const std::vector<std::string>& qualityLevels()
{
    static const std::vector<std::string> levels{"draft", "final", "reference"};
    return levels;
}

double qualityLevelError(const std::string& level)
{
    if (level == "draft") return 0.10;
    if (level == "final") return 0.05;
    if (level == "reference") return 0.02;
    throw UsageError(fmt::format("unknown quality level '{}': draft (10% error), final (5%) or reference (2%)", level));
}

std::string QualityChoice::summary() const
{
    const std::string asking = asked.level.empty() ? fmt::format("an error of {:.3g}%", 100.0 * asked.error)
                                                   : fmt::format("'{}' ({:.3g}% error)", asked.level, 100.0 * asked.error);
    std::string text = fmt::format("quality: {} asked; {}. ", asking, why);
    text += reached
        ? fmt::format("Its fastest setting to that error reached {:.2f}% in {:.1f} s on the bench: {}", 100.0 * error, seconds, setting)
        : fmt::format(
              "No setting the bench measured reaches it; its most accurate, {:.2f}% in {:.1f} s: {}", 100.0 * error, seconds, setting);
    if (!kept.empty()) {
        text += ". The scene's own";
        for (std::size_t i = 0; i < kept.size(); ++i) text += (i == 0 ? " " : ", ") + kept[i];
        text += " kept";
    }
    return text + ".";
}

namespace detail {

namespace {

using nlohmann::json;

/// How far a bench scene's medium is from @a medium: a volume object against a mesh's interior
/// counts most, then the albedo as the number of scatterings it allows (decades of 1 − albedo),
/// then whether the phase is anisotropic, then the optical size (half a point a decade; the
/// voxel size follows it, see applyQuality).
double mediumDistance(const QualityMedium& medium, const json& bench)
{
    const auto decades = [](double albedo) { return std::log10(std::max(1.0 - std::min(albedo, 1.0), 1e-4)); };
    const double size = bench.at("optical_size").get<double>();
    return 2.0 * double(medium.volume != bench.at("volume").get<bool>()) +
        std::abs(decades(medium.albedo) - decades(bench.at("albedo").get<double>())) +
        double((medium.phaseG != 0.0) != (bench.at("g").get<double>() != 0.0)) +
        (medium.opticalSize > 0.0 ? 0.5 * std::abs(std::log10(medium.opticalSize / size)) : 0.0);
}

/// The largest dim `quality` scales a bench setting's to.
constexpr int kMaxQualityDim = 1024;

std::string describe(bool volume, double albedo, double g, double opticalSize)
{
    return fmt::format("{} of albedo {:.3g}{}{}", volume ? "a volume object" : "a mesh medium", albedo,
        g != 0.0 ? fmt::format(", g {:.2g}", g) : std::string(", isotropic"),
        opticalSize > 0.0 ? fmt::format(", {:.3g} mean free paths across", opticalSize) : std::string());
}

/// Whether the scene gives the knob /@a block/@a key itself (findKnob: a name not declared is a bug).
bool sets(const json& document, const char* block, const char* key) { return givesKnob(document, findKnob(block, key)); }

} // namespace

QualityChoice applyQuality(const QualityRequest& request, const QualityMedium& medium, const json& document, SceneSettings& s)
{
    const json& scenes = qualityTable().at("scenes");
    QualityChoice choice;
    choice.asked = request;
    double nearest = std::numeric_limits<double>::max();
    for (const auto& [name, bench] : scenes.items()) {
        const double d = mediumDistance(medium, bench);
        if (d < nearest) {
            nearest = d;
            choice.benchScene = name;
        }
    }
    const json& bench = scenes.at(choice.benchScene);
    const bool keepPhaseDefaults = medium.phaseG != 0.0 && bench.at("g").get<double>() == 0.0;
    choice.why = fmt::format("the scene ({}) is closest to the accuracy bench's '{}' ({}, {}x{} pixels){}",
        describe(medium.volume, medium.albedo, medium.phaseG, medium.opticalSize), choice.benchScene,
        describe(bench.at("volume").get<bool>(), bench.at("albedo").get<double>(), bench.at("g").get<double>(),
            bench.at("optical_size").get<double>()),
        qualityTable().at("image")[0].get<int>(), qualityTable().at("image")[1].get<int>(),
        keepPhaseDefaults ? "; its kernel and single scattering stay the anisotropic phase's" : "");

    // The frontier is in order of time: the first that reaches the error is the fastest; none
    // does, the last (the most accurate).
    const json& rows = bench.at("settings");
    const auto reaching =
        std::find_if(rows.begin(), rows.end(), [&](const json& r) { return r.at("error").get<double>() <= request.error; });
    choice.reached = reaching != rows.end();
    const json& row = choice.reached ? *reaching : rows.back();
    choice.setting = row.at("setting").get<std::string>();
    choice.error = row.at("error").get<double>();
    choice.seconds = row.at("seconds").get<double>();

    const json& knobs = row.at("knobs");
    // A mesh's voxels (dim), or a volume's own coarsened to about volume_dim along the bench
    // volume's longest side (0: its own voxels; never refined: SceneMedium.h).
    const char* dimKnob = medium.volume ? "volume_dim" : "dim";
    if (knobs.contains(dimKnob) && knobs[dimKnob].get<int>() > 0) {
        if (sets(document, "voxelize", "dim") || sets(document, "voxelize", "voxel_size")) {
            choice.kept.push_back(sets(document, "voxelize", "dim") ? "/voxelize/dim" : "/voxelize/voxel_size");
        } else {
            // The bench's voxels per mean free path kept in a medium optically larger than its
            // scene's (the error follows the voxel's size in mean free paths); never fewer voxels
            // than the bench's (the silhouette's error follows those).
            const int dim = knobs[dimKnob].get<int>();
            const double scale = medium.opticalSize / bench.at("optical_size").get<double>();
            s.dim = scale > 1.0 ? int(std::min(std::ceil(dim * scale), double(kMaxQualityDim))) : dim;
            s.voxelSize = 0.0;
            if (s.dim != dim)
                choice.setting += fmt::format(
                    " (dim {} here, for the bench's {} voxels per mean free path)", s.dim, dim / bench.at("optical_size").get<double>());
        }
    }
    // The bench's knobs that are the scene's own by name (Knob::quality), where the scene does not
    // set them itself. A knob whose default the medium chooses (the kernel, single scattering)
    // keeps the anisotropic phase's when the bench scene's phase is isotropic.
    for (const Knob& k : vxf::knobs()) {
        if (!k.quality || !knobs.contains(k.param.name)) continue;
        if (givesKnob(document, k)) {
            choice.kept.push_back(k.path());
        } else if (!(keepPhaseDefaults && k.param.defaultValue.is_null())) {
            k.set(s, knobs[k.param.name]);
        }
    }
    if (knobs.contains("max_samples")) {
        // The bench leaves adaptive sampling off unless it asks for more rays than `samples`.
        if (sets(document, "render", "max_samples")) {
            choice.kept.push_back("/render/max_samples");
        } else {
            const int maxSamples = knobs["max_samples"].get<int>();
            s.maxSamples = maxSamples > s.samples ? maxSamples : 0;
        }
    }
    // A band in voxels of the bench's lattice (0 in every setting it has taken so far) is not
    // carried: the scene's voxel size is not known before its mesh is read, and a band only
    // saves time.
    if (knobs.contains("env_samples")) choice.environmentSamples = knobs["env_samples"].get<int>();
    return choice;
}

} // namespace detail

} // namespace vxf
