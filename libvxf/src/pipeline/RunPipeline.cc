#include <vxf/pipeline/RunPipeline.h>

#include "SceneJson.h"

#include <vxf/core/Frames.h>
#include <vxf/core/GridRoles.h>
#include <vxf/io/AtomicFile.h>
#include <vxf/io/ContentHash.h>
#include <vxf/io/ImageFile.h>
#include <vxf/io/VoxelSetFile.h>
#include <vxf/pipeline/Knobs.h>
#include <vxf/pipeline/LightScene.h>
#include <vxf/pipeline/SceneGeometry.h>
#include <vxf/pipeline/SceneMedium.h>
#include <vxf/render/Render.h>
#include <vxf/scatter/Scatter.h>
#include <vxf/voxelize/Voxelize.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <optional>
#include <thread>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

namespace vxf {

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

std::string hashOf(const json& inputs) { return hashHex(inputs.dump()); }

using detail::matrixJson;
using detail::vecJson;

json lightJson(const Light& l)
{
    return {{"type", int(l.type)}, {"name", l.name}, {"color", vecJson(l.color)}, {"intensity", l.intensity}, {"falloff", int(l.falloff)},
        {"position", vecJson(l.position)}, {"direction", vecJson(l.direction)}, {"cone", {l.coneAngleDegrees, l.coneSoftnessDegrees}},
        {"shape", int(l.shape)}, {"size", {l.width, l.height, l.radius}}, {"samples", l.samples}, {"file", l.file}, {"grid", l.grid},
        {"grid_to_world", matrixJson(l.gridToWorld)}, {"placement", int(l.placement)}, {"blackbody", l.blackbodyKelvin}};
}

} // namespace

namespace {

/// A cache entry that cannot be read (a machine killed while the file system had not written
/// it all; a byte damaged on disk: the grids' checksums) is removed, and the run starts over,
/// recomputing that stage and reusing the others.
struct UnreadableCacheEntry
{
    std::string warning;
};

VoxelSet readCacheEntry(const fs::path& path, const VoxelSetReadOptions& options = {})
{
    try {
        return readVoxelSet(path.string(), options);
    } catch (const Error& e) {
        std::error_code ignored;
        fs::remove(path, ignored);
        throw UnreadableCacheEntry{
            fmt::format("cache entry {} could not be read ({}): removed, and its stage recomputed", path.string(), e.what())};
    }
}

/// An exclusive lock on a cache entry's computation (flock on a hidden `.ENTRY.lock` beside
/// it, released when the process ends, however it ends): two runs sharing a cache compute each
/// entry once, the second waiting for the first's file. Waits in steps of 100 ms so that an
/// interrupt stops the wait. A cache folder that takes no lock file is computed as before.
class CacheLock
{
public:
    CacheLock(const fs::path& entry, Interrupter* interrupter)
    {
        const fs::path path = entry.parent_path() / ("." + entry.filename().string() + ".lock");
        mFd = ::open(path.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0644);
        if (mFd < 0) return;
        while (::flock(mFd, LOCK_EX | LOCK_NB) != 0) {
            if (errno != EWOULDBLOCK && errno != EINTR) break;
            if (interrupter && interrupter->wasInterrupted(-1)) {
                ::close(mFd);
                throw Interrupted();
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
        }
    }
    ~CacheLock()
    {
        if (mFd >= 0) ::close(mFd);
    }
    CacheLock(const CacheLock&) = delete;
    CacheLock& operator=(const CacheLock&) = delete;

private:
    int mFd = -1;
};

/// Claim OUT/STEM.exr for the scene at @a scenePath: a hidden `.STEM.scene` beside it names the
/// scene that renders there, and another scene of the same file stem is refused before any work
/// (two scenes named s.json in one --out both printed "wrote out/s.exr", and one image was lost).
/// Returns the claim's file when this call made it (a run that then fails removes it: a failed
/// run claims nothing), else "".
fs::path claimImageName(const fs::path& out, const std::string& stem, const std::string& scenePath)
{
    const fs::path claim = out / ("." + stem + ".scene");
    const std::string mine = fs::weakly_canonical(fs::absolute(scenePath)).string();
    std::ifstream in(claim);
    std::string theirs;
    if (in && std::getline(in, theirs) && !theirs.empty() && theirs != mine) {
        throw UsageError(fmt::format("{}: {} is rendered there from {}; give this scene another --out (or rename it)", out.string(),
            (out / (stem + ".exr")).string(), theirs));
    }
    if (theirs == mine) return {};
    writeAtomically(claim.string(), [&](const std::string& tmp) {
        std::ofstream file(tmp);
        file << mine << "\n";
        if (!file) throw Error(fmt::format("{}: cannot write", claim.string()));
    });
    return claim;
}

/// Whether @a entry is in the cache: when it is not, after waiting for a run that computes it
/// (holding its lock in @a lock from then on, for this run's own computation).
bool inCache(const fs::path& entry, std::optional<CacheLock>& lock, Interrupter* interrupter)
{
    if (fs::exists(entry)) return true;
    lock.emplace(entry, interrupter);
    return fs::exists(entry);
}

/// One run of the pipeline over a scene (runPipelineOnce): each stage reused from the cache or
/// run, in order, recording what it did.
struct PipelineRun
{
    const Scene& scene;
    const SceneSettings& s;
    const Material material;
    const fs::path out, cache;
    Interrupter* interrupter;
    const PipelineOptions& pipelineOptions;
    PipelineReport& report;
    std::optional<CacheLock> lock; ///< the entry being computed

    bool wants(const char* output) const { return std::find(s.outputs.begin(), s.outputs.end(), output) != s.outputs.end(); }

    template <typename F>
    static double timed(F&& f)
    {
        const auto start = std::chrono::steady_clock::now();
        f();
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }

    void record(const char* stage, const char* action, std::string why, const fs::path& file, double seconds)
    {
        report.stages.push_back({stage, action, std::move(why), file.string(), seconds});
    }

    /// What a stage left: its cache entry, the key later stages chain from, and the voxel set
    /// when it computed one (empty when reused: read on demand).
    struct Entry
    {
        fs::path file;
        std::string hash;
        VoxelSet set;
    };

    Entry voxelizeStage()
    {

        // Voxelize: the media (mesh bytes, transforms, materials when several, coefficient
        // grids), the voxel settings.
        json media = json::array();
        for (const auto& o : scene.objects) {
            if (o.role != SceneObject::Role::Medium) continue;
            const Material& m = *o.material;
            const std::string& file = o.isVolume() ? o.volume : o.mesh;
            media.push_back({{o.isVolume() ? "volume" : "mesh", file}, {"grid", o.isVolume() ? json(o.grid) : json()},
                {"placement", o.isVolume() && o.placement != VoxelPlacement::Auto ? json(int(o.placement)) : json()},
                {"bytes", fileFingerprint(file)}, {"transform", matrixJson(o.objectToWorld)},
                {"sigma", mediaCount(scene) > 1 ? json{vecJson(m.sigmaA), vecJson(m.sigmaS)} : json()},
                {"grids", m.gridsFile.empty() ? json() : json{fileFingerprint(m.gridsFile), m.sigmaAGrid, m.sigmaSGrid}}});
        }
        // The program too: the light and scatter stages' keys chain from this one.
        const json voxelInputs = {{"media", media}, {"settings", stageSettingsKey(s, Stage::Voxelize)}, {"program", programFingerprint()}};
        const std::string voxelHash = hashOf(voxelInputs);
        const fs::path voxelFile = cache / ("voxelize-" + voxelHash + ".vdb");
        VoxelSet set;
        std::string note; // what was done to a volume object's voxels
        if (inCache(voxelFile, lock, interrupter)) {
            record("voxelize", "reused", "mesh and voxel settings unchanged", voxelFile, 0.0);
        } else {
            const double seconds = timed([&] {
                set = voxelizeMedia(scene, sceneVoxelizeOptions(s), interrupter, &note);
                set.setProvenance("voxelize", voxelInputs.dump());
                writeVoxelSet(voxelFile.string(), set);
            });
            record("voxelize", "ran", "no cached voxel set for these inputs" + (note.empty() ? "" : "; " + note), voxelFile, seconds);
        }
        lock.reset();
        return {voxelFile, voxelHash, std::move(set)};
    }

    Entry lightStage(Entry voxels)
    {
        const std::string& voxelHash = voxels.hash;
        const fs::path& voxelFile = voxels.file;
        VoxelSet& set = voxels.set;

        // Light: the voxel set, the material, the lights.
        json lights = json::array();
        for (const auto& l : scene.lights) lights.push_back(lightJson(l));
        json occluders = json::array();
        for (const auto& o : scene.objects) {
            if (o.role == SceneObject::Role::Occluder) occluders.push_back({fileFingerprint(o.mesh), matrixJson(o.objectToWorld)});
        }
        for (const auto& l : scene.lights) {
            if (!l.file.empty()) lights.push_back(fileFingerprint(l.file)); // environment map, emission grid: their bytes
        }
        json lightInputs = {{"voxels", voxelHash}, {"sigma_a", vecJson(material.sigmaA)}, {"sigma_s", vecJson(material.sigmaS)},
            {"lights", lights}, {"occluders", occluders}, {"settings", stageSettingsKey(s, Stage::Light)}};
        // A forward phase's first moment is carried by the accelerated sweeps alone (Scatter.h);
        // for any other scatter the light stage lights the similarity relation's medium too.
        const bool carriesMoment = !lightOptionsFrom(s).similarity;
        if (material.phaseG != 0.0) { // an isotropic medium is lit alike either way
            lightInputs["phase_g"] = material.phaseG;
            lightInputs["phase_scaling"] = carriesMoment ? "delta-M 3, Henyey-Greenstein lobe" : "similarity";
        }
        const std::string lightHash = hashOf(lightInputs);
        const fs::path lightFile = cache / ("light-" + lightHash + ".vdb");
        if (inCache(lightFile, lock, interrupter)) {
            record("light", "reused", "voxels, material and lights unchanged", lightFile, 0.0);
        } else {
            const double seconds = timed([&] {
                if (set.empty()) set = readCacheEntry(voxelFile);
                const DirectLightOptions options = lightOptionsFrom(s);
                const DirectLightReport lit = lightScene(set, scene, options, interrupter);
                report.warnings.insert(report.warnings.end(), lit.warnings.begin(), lit.warnings.end());
                set.setProvenance("light", lightInputs.dump());
                writeVoxelSet(lightFile.string(), set);
            });
            record("light", "ran", "no cached lighting for these inputs", lightFile, seconds);
            set = VoxelSet();
        }
        lock.reset();
        return {lightFile, lightHash, VoxelSet()};
    }

    /// The volume the render reads: the scatter stage's entry, or the light stage's when it does not run.
    Entry scatterStage(const Entry& lighting)
    {
        const fs::path& lightFile = lighting.file;
        const std::string& lightHash = lighting.hash;

        // Scatter, only when it matters.
        fs::path volumeFile = lightFile;
        std::string volumeHash = lightHash;
        const bool needScatter = wants("image") || wants("scatter") || wants("illumination") || wants("scatter_passes");
        if (!material.scatters() && material.sigmaSGrid.empty()) { // (several media: the maximum of their σs)
            record("scatter", "skipped", "the material does not scatter (sigma_s = 0)", "", 0.0);
        } else if (!needScatter) {
            record("scatter", "skipped", "no requested output needs it", "", 0.0);
        } else {
            json scatterInputs = {{"lit", lightHash}, {"settings", stageSettingsKey(s, Stage::Scatter)}, {"keep", wants("scatter_passes")}};
            const fs::path warmFile = pipelineOptions.warmStart;
            const bool warm = !warmFile.empty() && fs::exists(warmFile);
            if (warm) scatterInputs["warm_start"] = warmFile.filename().string();
            volumeHash = hashOf(scatterInputs);
            volumeFile = cache / ("scatter-" + volumeHash + ".vdb");
            if (inCache(volumeFile, lock, interrupter)) {
                record("scatter", "reused", "lighting and scatter settings unchanged", volumeFile, 0.0);
            } else {
                ScatterReport scattered;
                const double seconds = timed([&] {
                    VoxelSet lit = readCacheEntry(lightFile, scatterInputRead());
                    ScatterOptions scatterOptions = scatterOptionsFrom(s);
                    if (warm) scatterOptions.warmStart = readCacheEntry(warmFile).get<openvdb::Vec3SGrid>(grids::kScatter);
                    scattered = scatter(lit, scatterMedium(lit, material, scatterOptions), scatterOptions, interrupter);
                    readGridsInto(lit, lightFile.string(), {grids::kDirect}, scatterInputRead());
                    putIllumination(lit);
                    lit.setProvenance("scatter", scatterInputs.dump());
                    writeVoxelSet(volumeFile.string(), lit);
                });
                record("scatter", "ran",
                    fmt::format("{} passes{}: {}", scattered.passes.size(), scattered.warmStarted ? " from the frame before" : "",
                        scattered.stopReason),
                    volumeFile, seconds);
            }
            lock.reset();
        }
        return {volumeFile, volumeHash, VoxelSet()};
    }

    void renderStage(const fs::path& volumeFile, const std::string& stem)
    {

        // Render: always when an image is asked for (it is the cheap end of the chain).
        if (!wants("image")) {
            record("render", "skipped", "no image requested", "", 0.0);
            return;
        }
        report.image = (out / (stem + ".exr")).string();
        report.preview = (out / (stem + ".png")).string();
        std::string why = "images are always rendered from the (cached) volume";
        const double seconds = timed([&] {
            const RenderOptions options = renderOptionsFrom(s);
            const VoxelSet volume = readCacheEntry(volumeFile, renderInputRead(options)); // its grids alone
            const Medium medium(volume, material);
            const SceneRayScenes meshes = sceneRayScenes(scene);
            const RenderedImage image =
                render(volume, medium, scene, options, {&meshes.visible, &meshes.occluders, &meshes.media}, interrupter);
            writeExr(report.image, image);
            writePng(report.preview, image);
            if (image.refinedPixels > 0) why += "; " + refinedSummary(image, options);
        });
        record("render", "ran", why, report.image, seconds);
    }
};

std::string sceneStem(const Scene& scene)
{
    const std::string stem = fs::path(scene.path).stem().string();
    return stem.empty() ? "scene" : stem;
}

PipelineReport runPipelineOnce(const Scene& scene, const std::string& outDir, Interrupter* interrupter, const PipelineOptions& options)
{
    PipelineReport report;
    const Material material = sceneMaterial(scene);
    const SceneSettings& s = scene.settings;

    const fs::path out(outDir), cache = out / "cache";
    fs::create_directories(cache);
    PipelineRun run{scene, s, material, out, cache, interrupter, options, report, std::nullopt};
    const PipelineRun::Entry lit = run.lightStage(run.voxelizeStage());
    const PipelineRun::Entry volume = run.scatterStage(lit);
    report.volume = volume.file.string();
    run.renderStage(volume.file, fs::path(sceneImagePath(scene, outDir)).stem().string());
    return report;
}

} // namespace

PipelineReport runPipeline(const Scene& scene, const std::string& outDir, Interrupter* interrupter, const PipelineOptions& options)
{
    std::vector<std::string> warnings;
    const SceneSettings& s = scene.settings;
    fs::create_directories(outDir);
    fs::path claim; // made by this run: removed when it fails
    if (std::find(s.outputs.begin(), s.outputs.end(), "image") != s.outputs.end() && !scene.path.empty())
        claim = claimImageName(outDir, sceneStem(scene), scene.path);
    try {
        // Each pass over an unreadable entry removes it; the chain has three entries to lose.
        for (int attempt = 0;; ++attempt) {
            try {
                PipelineReport report = runPipelineOnce(scene, outDir, interrupter, options);
                report.warnings.insert(report.warnings.begin(), warnings.begin(), warnings.end());
                return report;
            } catch (const UnreadableCacheEntry& stale) {
                if (attempt >= 3) throw Error(stale.warning);
                warnings.push_back(stale.warning);
            }
        }
    } catch (...) {
        std::error_code ignored;
        if (!claim.empty()) fs::remove(claim, ignored);
        throw;
    }
}

std::string sceneImagePath(const Scene& scene, const std::string& outDir)
{
    return (fs::path(outDir) / (sceneStem(scene) + (scene.frame ? "." + paddedFrame(*scene.frame) : std::string()) + ".exr")).string();
}

std::vector<SceneInputFile> sceneInputFiles(const Scene& scene)
{
    std::vector<SceneInputFile> files;
    const auto add = [&](std::string owner, const char* kind, const std::string& path) {
        if (!path.empty() && path.rfind("builtin:", 0) != 0) files.push_back({std::move(owner), kind, path});
    };
    for (const SceneObject& o : scene.objects) {
        const std::string owner = fmt::format("object '{}'", o.name);
        add(owner, o.isVolume() ? "volume" : "mesh", o.isVolume() ? o.volume : o.mesh);
        if (o.material) add(owner, "coefficient grids", o.material->gridsFile);
    }
    for (const Light& l : scene.lights) add(fmt::format("light '{}'", l.name), "file", l.file);
    return files;
}

void requireSceneInputs(const Scene& scene)
{
    for (const SceneInputFile& f : sceneInputFiles(scene)) {
        std::error_code error;
        if (!fs::exists(f.path, error)) {
            // (An object's own file and a light's go by their owner's name alone.)
            const std::string what = f.kind == std::string("coefficient grids") ? f.owner + "'s " + f.kind : f.owner;
            throw InputError(scene.path, 0, 0,
                fmt::format(
                    "{}{}: {} does not exist", scene.frame ? fmt::format("at frame {}: ", *scene.frame) : std::string(), what, f.path));
        }
    }
}

} // namespace vxf
