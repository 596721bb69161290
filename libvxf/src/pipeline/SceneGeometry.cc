#include <vxf/pipeline/SceneGeometry.h>

#include <vxf/core/Error.h>
#include <vxf/core/ProceduralMesh.h>
#include <vxf/io/MeshFile.h>

#include <fmt/format.h>

namespace vxf {

TriangleMesh objectMesh(const SceneObject& object)
{
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
        mesh = readMesh(object.mesh);
    }
    for (auto& p : mesh.points) p = object.objectToWorld.transform(p);
    return mesh;
}

RayScene sceneGeometry(const Scene& scene, SceneObject::Role role)
{
    RayScene geometry;
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
        if (scene.objects[i].role == role) geometry.add(objectMesh(scene.objects[i]), int(i));
    }
    geometry.commit();
    return geometry;
}

SceneRayScenes sceneRayScenes(const Scene& scene)
{
    SceneRayScenes g;
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
        const SceneObject& object = scene.objects[i];
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
