// vxf — meshes made by the project (the embedded default scene needs no downloads).
#pragma once

#include <vxf/core/TriangleMesh.h>

#include <optional>
#include <string>
#include <vector>

namespace vxf {

/// Closed UV sphere of @a radius around @a center, outward-oriented, watertight.
TriangleMesh makeSphere(const openvdb::Vec3d& center, double radius, int rings = 64, int segments = 128);

/// Closed axis-aligned box, outward-oriented, 12 triangles.
TriangleMesh makeBox(const openvdb::Vec3d& min, const openvdb::Vec3d& max);

/// A pillar candle standing on z = 0: radius 1, height 3, a rounded rim and the shallow
/// melt pool around the wick on top (world units); closed and outward-oriented.
TriangleMesh makeCandle(int segments = 128);

/// A candle flame: a teardrop about the z axis, base at the origin, tip at z = 1, 0.44 wide;
/// closed and outward-oriented.
TriangleMesh makeFlame(int segments = 64);

/// Surface of revolution about the z axis of a profile of (radius, z) points that starts
/// and ends on the axis (radius 0), in order from bottom to top. Closed and outward-oriented.
TriangleMesh makeRevolution(const std::vector<openvdb::Vec2d>& profile, int segments);

/// Names accepted where a mesh path is expected: "builtin:candle", "builtin:flame", "builtin:sphere"
/// (radius 1 at the origin), "builtin:box" (the cube [-1,1]^3).
const std::vector<std::string>& builtinMeshNames();

/// The built-in mesh called @a name, or nothing when @a name is not one.
std::optional<TriangleMesh> builtinMesh(const std::string& name);

} // namespace vxf
