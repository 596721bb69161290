// `vxf run S.json [--out DIR] [--frames RANGE]`: the whole pipeline, doing only what the scene
// needs, for a still or for the frames of a shot.
#include "CliSupport.h"
#include "Commands.h"

#include <vxf/core/Frames.h>
#include <vxf/pipeline/Knobs.h>
#include <vxf/pipeline/RunPipeline.h>
#include <vxf/pipeline/SceneFile.h>
#include <vxf/pipeline/SceneGeometry.h>

#include <fmt/format.h>

#include <filesystem>
#include <iostream>
#include <optional>
#include <set>

namespace vxf::cli {

namespace {

class RunCommand : public Command
{
public:
    explicit RunCommand(CLI::App& parent)
    {
        mApp = parent.add_subcommand("run",
            "Run voxelize -> light -> scatter -> render for a scene, simulating only what it calls for: stage outputs "
            "are cached by a hash of their inputs (OUT/cache), so changing only the camera re-renders only. An animated "
            "scene (keyframes, frame tokens $F4 or #### in its paths: schemas/scene.schema.json) renders frame by frame "
            "with --frames into OUT/NAME.0001.exr ...; each frame re-runs only the stages whose inputs changed.");
        mApp->add_option("scene", mScene, "Scene file");
        mApp->add_flag("--schema", mSchema,
            "Print schemas/scene.schema.json (its voxelize, scatter and render blocks generated from the stages' knobs) and exit");
        mApp->add_option("--out", mOut, "Output folder (default: out)");
        mApp->add_option("--frames", mFrames,
            "Frames to render: N, A-B, A-B:STEP or a comma-separated list of those (1-240, 1-240:2, 1,5,10-20). Every "
            "frame's scene and input files are checked before the first is rendered. A still scene renders the same "
            "image at every frame (NAME.0001.exr ...)");
        mApp->add_flag("--prune-cache", mPrune,
            "With --frames: after each frame, remove the cache entries the frame before used and this one did not (a shot's "
            "cache then holds one frame's stages, not every frame's; a rerun recomputes them)");
        mApp->add_flag(
            "--dry-run", mDryRun, "Check the scene (at every frame) and its input files and print each frame's image, rendering nothing");
        mApp->add_option("--error", mError,
                "The error wanted (relative RMSE against a path tracer, 0.001-1): the scene is read with the fastest setting "
                "bench/accuracy measured to reach it on the closest of its scenes, under the knobs the scene sets itself "
                "(printed: what was chosen and why). Overrides the scene's quality")
            ->check(CLI::Range(0.001, 1.0));
        mApp->add_option("--quality", mLevel, "A level naming an error, as --error: draft (10%), final (5%), reference (2%)")
            ->check(CLI::IsMember(qualityLevels()))
            ->excludes("--error");
        mApp->add_flag("--warm-start", mWarmStart,
            "With --frames: each frame's scatter solve starts from the frame before's where the medium lies on the same "
            "voxels (fewer sweeps; results then depend on the frame order, within the scene's tolerance)");
    }

    void run() override
    {
        if (mSchema) {
            std::cout << sceneSchemaDocument().dump(2) << "\n";
            return;
        }
        if (mScene.empty()) throw UsageError("name a scene file (vxf run SCENE)");
        if (mFrames.empty()) {
            if (mWarmStart || mPrune) throw UsageError(fmt::format("{} needs --frames", mWarmStart ? "--warm-start" : "--prune-cache"));
            const Scene scene = loadScene(mScene, std::nullopt, qualityAsked());
            refuseImagesOverInputs(scene);
            sayQuality(scene);
            if (mDryRun) {
                requireSceneInputs(scene);
                std::cout << fmt::format("still: {}\n", sceneImagePath(scene, mOut));
            } else {
                runOne(scene, {});
            }
            return;
        }
        const std::vector<int> frames = parseFrameRange(mFrames);
        // Every frame's scene and inputs before any work: a missing smoke.0037.vdb stops the
        // run now, not after 36 frames.
        std::vector<Scene> scenes;
        for (int frame : frames) {
            scenes.push_back(loadScene(mScene, frame, qualityAsked()));
            requireSceneInputs(scenes.back());
            refuseImagesOverInputs(scenes.back());
        }
        sayQuality(scenes.front());
        if (mDryRun) {
            for (const Scene& scene : scenes) std::cout << fmt::format("frame {}: {}\n", *scene.frame, sceneImagePath(scene, mOut));
            return;
        }
        PipelineOptions options;
        std::set<std::string> previous; // the cache entries the frame before used
        std::size_t done = 0;
        for (const Scene& scene : scenes) {
            std::cout << fmt::format("frame {}\n", *scene.frame);
            PipelineReport report;
            try {
                report = runOne(scene, options);
            } catch (const Interrupted&) {
                // The frames before are whole files; "no output written" is the interrupted frame's.
                if (done > 0)
                    warn(fmt::format("{} of {} frames written before frame {} was interrupted", done, scenes.size(), *scene.frame));
                throw;
            }
            ++done;
            if (mWarmStart && !report.volume.empty()) options.warmStart = report.volume;
            if (mPrune) previous = pruned(previous, report);
        }
    }

private:
    /// --error or --quality, when given.
    std::optional<QualityRequest> qualityAsked() const
    {
        if (mError > 0.0) return QualityRequest{mError, ""};
        if (!mLevel.empty()) return qualityRequestForLevel(mLevel);
        return std::nullopt;
    }

    /// The image and preview vxf run writes for @a scene must not be files the scene reads.
    void refuseImagesOverInputs(const Scene& scene) const
    {
        const std::string image = sceneImagePath(scene, mOut);
        refuseOverwrites(
            sceneFiles(scene), {{"the image", image}, {"the preview", std::filesystem::path(image).replace_extension(".png").string()}});
    }

    static void sayQuality(const Scene& scene)
    {
        if (scene.settings.quality) std::cout << scene.settings.quality->summary() << "\n";
    }

    /// Remove the entries of @a previous that @a report's frame did not use; the entries it used.
    static std::set<std::string> pruned(const std::set<std::string>& previous, const PipelineReport& report)
    {
        std::set<std::string> used;
        for (const StageRecord& stage : report.stages) {
            if (stage.action != "skipped" && stage.stage != "render" && !stage.file.empty()) used.insert(stage.file);
        }
        std::uintmax_t bytes = 0;
        int removed = 0;
        for (const std::string& file : previous) {
            if (used.count(file)) continue;
            std::error_code error;
            const std::uintmax_t size = std::filesystem::file_size(file, error);
            if (std::filesystem::remove(file, error)) {
                bytes += error ? 0 : size;
                ++removed;
            }
            const std::filesystem::path entry(file);
            std::filesystem::remove(entry.parent_path() / ("." + entry.filename().string() + ".lock"), error);
        }
        if (removed > 0)
            std::cout << fmt::format("  pruned {} cache entries of the frame before ({:.1f} MB)\n", removed, double(bytes) / 1e6);
        return used;
    }

    PipelineReport runOne(const Scene& scene, const PipelineOptions& options)
    {
        TerminalProgress progress;
        const auto start = std::chrono::steady_clock::now();
        PipelineReport report = runPipeline(scene, mOut, &progress, options);
        // What repairing the meshes did, once per file, as `vxf voxelize` says it.
        for (const auto& object : scene.objects) {
            if (object.isVolume() || !mToldMeshes.insert(object.mesh).second) continue;
            for (const auto& warning : objectMeshWarnings(object)) warn(fmt::format("{}: {}", object.mesh, warning));
        }
        for (const auto& warning : report.warnings) warn(warning);
        for (const auto& stage : report.stages) {
            std::cout << fmt::format("  {:<9} {:<7} {:>7.2f} s  {}\n", stage.stage, stage.action, stage.seconds, stage.why);
        }
        if (!report.image.empty()) std::cout << fmt::format("wrote {} and {}", report.image, report.preview);
        std::cout << fmt::format(" in {:.2f} s\n", secondsSince(start)) << std::flush;
        return report;
    }

    std::string mScene, mOut = "out", mFrames, mLevel;
    double mError = 0.0;
    bool mWarmStart = false, mDryRun = false, mPrune = false, mSchema = false;
    std::set<std::string> mToldMeshes;
};

} // namespace

std::unique_ptr<Command> makeRunCommand(CLI::App& parent) { return std::make_unique<RunCommand>(parent); }

} // namespace vxf::cli
