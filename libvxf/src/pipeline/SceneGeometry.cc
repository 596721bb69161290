#include <vxf/pipeline/SceneGeometry.h>

#include <vxf/core/Error.h>
#include <vxf/core/ProceduralMesh.h>
#include <vxf/io/ContentHash.h>
#include <vxf/io/MeshFile.h>

#include <fmt/format.h>

#include <deque>
#include <fstream>
#include <memory>
#include <mutex>
#include <utility>

namespace vxf {

namespace {

/// A mesh file as read and repaired, with what the repair found.
struct ReadMesh
{
    std::shared_ptr<const TriangleMesh> mesh;
    std::vector<std::string> warnings; ///< MeshReport::warnings (no self-intersection check)
};

/// The meshes this process has read, so that the stages of one `vxf run` (voxelize, light,
/// render) or one `vxf graph` read and repair each file once: on the accuracy bench's bunny
/// (75k triangles) a read is 0.17 s, and it was done three times in a 2.6 s run. A file is
/// known by its path and the hash of its bytes (a few ms), so an edited file is read again.
/// The few most recent are kept. The self-intersection check (0.13 s of the bunny's read,
/// reporting only) is `vxf voxelize`'s; the repairs' warnings are kept for the caller to show.
class ReadMeshes
{
public:
    static ReadMeshes& instance()
    {
        static ReadMeshes read;
        return read;
    }

    ReadMesh get(const std::string& path)
    {
        if (!std::ifstream(path).good()) return {std::make_shared<const TriangleMesh>(readMesh(path)), {}}; // it names the problem
        const Key key{path, fileFingerprint(path)};
        {
            std::lock_guard<std::mutex> lock(mMutex);
            for (const auto& [k, read] : mEntries) {
                if (k == key) return read;
            }
        }
        MeshReadOptions options;
        options.checkSelfIntersections = false;
        MeshReport report;
        ReadMesh read{std::make_shared<const TriangleMesh>(readMesh(path, options, &report)), std::move(report.warnings)};
        std::lock_guard<std::mutex> lock(mMutex);
        mEntries.emplace_front(key, read);
        if (mEntries.size() > kKept) mEntries.pop_back();
        return read;
    }

private:
    using Key = std::pair<std::string, std::string>; ///< path, fileFingerprint
    static constexpr std::size_t kKept = 8;
    std::mutex mMutex;
    std::deque<std::pair<Key, ReadMesh>> mEntries; ///< newest first
};

} // namespace

TriangleMesh objectMesh(const SceneObject& object)
{
    if (object.isVolume()) {
        throw UsageError(fmt::format("object '{}' is a volume ({}), not a mesh", object.name, object.volume));
    }
    TriangleMesh mesh;
    if (object.mesh.rfind("builtin:", 0) == 0) {
        auto builtin = builtinMesh(object.mesh);
        if (!builtin) {
            std::string names;
            for (const auto& n : builtinMeshNames()) names += (names.empty() ? "" : ", ") + n;
            throw UsageError(fmt::format("object '{}': no built-in mesh '{}' (there are {})", object.name, object.mesh, names));
        }
        mesh = std::move(*builtin);
    } else {
        mesh = *ReadMeshes::instance().get(object.mesh).mesh;
    }
    for (auto& p : mesh.points) p = object.objectToWorld.transform(p);
    return mesh;
}

std::vector<std::string> objectMeshWarnings(const SceneObject& object)
{
    if (object.isVolume() || object.mesh.rfind("builtin:", 0) == 0) return {};
    return ReadMeshes::instance().get(object.mesh).warnings;
}

RayScene sceneGeometry(const Scene& scene, SceneObject::Role role)
{
    RayScene geometry;
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
        if (scene.objects[i].role == role && !scene.objects[i].isVolume()) geometry.add(objectMesh(scene.objects[i]), int(i));
    }
    geometry.commit();
    return geometry;
}

SceneRayScenes sceneRayScenes(const Scene& scene)
{
    SceneRayScenes g;
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
        const SceneObject& object = scene.objects[i];
        if (object.isVolume()) continue; // no surface: camera rays march it (render)
        const TriangleMesh mesh = objectMesh(object);
        g.visible.add(mesh, int(i));
        if (object.role == SceneObject::Role::Occluder) g.occluders.add(mesh, int(i));
        if (object.role == SceneObject::Role::Medium) g.media.add(mesh, int(i)); // (emitters: seen, casting no shadows)
    }
    g.visible.commit();
    g.occluders.commit();
    g.media.commit();
    return g;
}

} // namespace vxf
