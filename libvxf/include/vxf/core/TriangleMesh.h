// vxf — an indexed triangle mesh in world units.
#pragma once

#include <openvdb/math/BBox.h>
#include <openvdb/math/Vec3.h>
#include <openvdb/Types.h>

#include <vector>

namespace vxf {

/// Indexed triangles; points in world units, double precision so that meshes far from the
/// origin keep their detail until voxelization moves them into index space.
struct TriangleMesh
{
    std::vector<openvdb::Vec3d> points;
    std::vector<openvdb::Vec3I> triangles;

    /// Bounds of the points (empty box for an empty mesh).
    openvdb::BBoxd bounds() const;
    /// Signed enclosed volume (divergence theorem); exact for a closed, outward-oriented mesh.
    double volume() const;
};

} // namespace vxf
