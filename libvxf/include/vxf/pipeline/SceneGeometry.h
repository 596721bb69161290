// vxf — a scene's objects as geometry: world-space meshes and Embree scenes of them.
#pragma once

#include <vxf/core/RayScene.h>
#include <vxf/core/TriangleMesh.h>
#include <vxf/core/Scene.h>

#include <string>
#include <vector>

namespace vxf {

/// The world-space triangles of @a object: its mesh file (read and repaired as by
/// `vxf voxelize`; a file is read once per process while its bytes stay the same) or
/// built-in mesh, moved by its transform. Throws vxf::InputError for a bad mesh file, and
/// vxf::UsageError for a volume object (it has no mesh; the Embree scenes below leave them out).
TriangleMesh objectMesh(const SceneObject& object);

/// What reading and repairing @a object's mesh file found (MeshReport::warnings, each one
/// sentence: holes filled, non-manifold points split, degenerate faces dropped; the
/// self-intersection check is `vxf voxelize`'s), from the read objectMesh keeps; none for
/// built-in meshes and volume objects. Throws as objectMesh does.
std::vector<std::string> objectMeshWarnings(const SceneObject& object);

/// An Embree scene of the scene's objects of @a role, each with its index in scene.objects as
/// id: the occluders (shadow rays in the light stage) or the media (the surfaces their level
/// set was made from). Empty when none has it.
RayScene sceneGeometry(const Scene& scene, SceneObject::Role role);

/// The three Embree scenes a render needs (every object, the occluders, the media), each
/// object's mesh read once.
struct SceneRayScenes
{
    RayScene visible, occluders, media;
};
SceneRayScenes sceneRayScenes(const Scene& scene);

} // namespace vxf
