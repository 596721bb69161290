// `vxf render S.json --volume V.vdb -o IMAGE.exr [--png PREVIEW.png] [--level-set] [--no-surface] [--direct-from-lights]`
#include "CliSupport.h"
#include "Commands.h"

#include <vxf/io/ImageFile.h>
#include <vxf/transport/Medium.h>
#include <vxf/pipeline/SceneGeometry.h>
#include <vxf/pipeline/SceneMedium.h>
#include <vxf/render/Render.h>

#include <fmt/format.h>

#include <iostream>

namespace vxf::cli {

namespace {

class RenderCommand : public Command
{
public:
    explicit RenderCommand(CLI::App& parent)
    {
        mApp = parent.add_subcommand("render",
            "Render a lit voxel set with the scene's camera: rays hit the scene's meshes (Embree; or the `surface` level "
            "set) and gather the volume (view mode: along the camera ray; gather mode: the thesis's final gather), plus "
            "the surface term (Lambert + specular) of objects with a reflecting surface. OpenEXR layers: R G B A, "
            "surface, direct, scatter, depth, normal, samples (camera rays per pixel); optional sRGB PNG preview.");
        mApp->add_option("scene", mScene, "Scene file (camera, render settings)")->required();
        mApp->add_option("--volume", mVolume, "Voxel set from vxf scatter (or vxf light)")->required();
        mApp->add_option("-o,--output", mOutput, "Output .exr")->required()->check(OutputFile);
        mApp->add_option("--png", mPng, "Also write an sRGB PNG preview")->check(OutputFile);
        mApp->add_option("--exposure", mExposure, "PNG exposure in stops (default 0)");
        mApp->add_option("--width", mWidth, "Override the scene's width")->check(CLI::Range(1, 32768));
        mApp->add_option("--height", mHeight, "Override the scene's height")->check(CLI::Range(1, 32768));
        mApp->add_option("--samples", mSamples, "Override the samples per pixel")->check(CLI::Range(1, 65536));
        mApp->add_option("--max-samples", mMaxSamples,
                "Adaptive sampling: pixels whose first samples disagree (silhouettes, object edges, noise above "
                "--noise-level) get more, up to this many in all (overrides the scene's max_samples)")
            ->check(CLI::Range(1, 65536));
        mApp->add_option("--noise-level", mNoiseLevel,
                "Adaptive sampling's threshold: relative standard error of a pixel's mean luminance (default 0.02)")
            ->check(CLI::Range(1e-6, 1.0));
        mApp->add_option("--mode", mMode, "view or gather (overrides the scene)")->check(CLI::IsMember({"view", "gather"}));
        mApp->add_flag("--level-set", mLevelSet, "Hit the volume's `surface` level set instead of the scene's meshes");
        mApp->add_flag(
            "--no-surface", [this](std::int64_t) { mNoSurface = true; }, "Leave out the surface term");
        mApp->add_flag(
            "--direct-from-lights", [this](std::int64_t) { mDirectFromLights = true; },
            "March single scattering to the lights at every step instead of reading the `direct` grid (exact in dense "
            "media at any voxel size, and the only way an anisotropic phase shows in single scattering: the scene's "
            "default when its medium's phase g is not 0; edits of `direct` do not show)");
        mApp->add_flag("--half", mHalf, "16-bit half EXR channels");
    }

    void run() override
    {
        TerminalProgress progress;
        const auto start = std::chrono::steady_clock::now();
        const Scene scene = loadScene(mScene);
        const VoxelSet set = readVoxelSet(mVolume);
        Material material;
        if (set.metadata().getMetadata<openvdb::StringMetadata>(kMaterialMetaKey)) {
            material = recordedMaterial(set);
        } else {
            material = sceneMaterial(scene);
        }
        const Medium medium(set, material);
        RenderOptions options = renderOptionsFrom(scene.settings);
        if (mWidth) options.width = mWidth;
        if (mHeight) options.height = mHeight;
        if (mSamples) options.samples = mSamples;
        if (mMaxSamples) options.maxSamples = mMaxSamples;
        if (mNoiseLevel > 0.0) options.noiseLevel = mNoiseLevel;
        if (!mMode.empty()) options.gather = mMode == "gather";
        if (mNoSurface) options.surface = false;
        if (mDirectFromLights) options.directFromLights = true;
        SceneRayScenes meshes;
        if (mLevelSet) {
            meshes.occluders = sceneGeometry(scene, SceneObject::Role::Occluder);
        } else {
            meshes = sceneRayScenes(scene);
        }
        const RenderedImage image = render(set, medium, scene, options, {&meshes.visible, &meshes.occluders, &meshes.media}, &progress);
        writeExr(mOutput, image, mHalf);
        if (!mPng.empty()) writePng(mPng, image, mExposure);
        const std::string adaptive = image.refinedPixels == 0 ? std::string() : ", " + refinedSummary(image, options);
        std::cout << fmt::format("rendered {} ({}x{}, {} samples per pixel{}, {} mode) -> {}{} in {:.3f} s\n", mVolume, options.width,
            options.height, options.samples, adaptive, options.gather ? "gather" : "view", mOutput, mPng.empty() ? "" : " + " + mPng,
            secondsSince(start));
    }

private:
    std::string mScene, mVolume, mOutput, mPng, mMode;
    double mExposure = 0.0, mNoiseLevel = 0.0;
    int mWidth = 0, mHeight = 0, mSamples = 0, mMaxSamples = 0;
    bool mHalf = false, mLevelSet = false, mNoSurface = false, mDirectFromLights = false;
};

} // namespace

std::unique_ptr<Command> makeRenderCommand(CLI::App& parent) { return std::make_unique<RenderCommand>(parent); }

} // namespace vxf::cli
