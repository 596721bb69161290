// vxf — triangle meshes for ray queries (Embree): camera hits and shadows.
#pragma once

#include <vxf/core/TriangleMesh.h>

#include <memory>
#include <optional>

namespace vxf {

/// A set of world-space triangle meshes behind Embree's BVH, for closest hits (camera rays
/// meeting a mesh) and occlusion (shadow rays). Built once, then read-only and safe to query
/// from any number of threads. Vertices are stored relative to the scene's centre, so meshes
/// far from the origin keep float precision near them.
class RayScene
{
public:
    RayScene();
    ~RayScene();
    RayScene(RayScene&&) noexcept;
    RayScene& operator=(RayScene&&) noexcept;

    /// Add @a mesh (world units) as object @a id (reported by hits). Call before commit().
    void add(const TriangleMesh& mesh, int id);
    /// Build the BVH; no add() after this.
    void commit();
    bool empty() const;
    /// The largest object id given to add() (-1: none), so a caller can check the ids against its objects.
    int largestId() const;

    struct Hit
    {
        double distance = 0.0; ///< along the (unit) ray direction
        openvdb::Vec3d normal; ///< unit geometric normal, facing against the ray
        int id = -1; ///< the object id given to add()
        bool backFace = false; ///< the ray met the triangle from behind its orientation
    };

    /// The closest hit of origin + t·direction (direction unit length), t in (tNear, tFar).
    std::optional<Hit> intersect(const openvdb::Vec3d& origin, const openvdb::Vec3d& direction, double tNear = 0.0,
        double tFar = std::numeric_limits<double>::infinity()) const;

    /// Whether anything lies on origin + t·direction for t in (tNear, tFar).
    bool occluded(const openvdb::Vec3d& origin, const openvdb::Vec3d& direction, double tNear = 0.0,
        double tFar = std::numeric_limits<double>::infinity()) const;

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace vxf
