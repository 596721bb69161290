// vxf — reading and repairing triangle meshes (.obj .ply .off .stl) through CGAL.
#pragma once

#include <vxf/core/Interrupter.h>
#include <vxf/core/TriangleMesh.h>

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace vxf {

/// The largest vertex coordinate readMesh accepts (world units): voxelizing runs in float index
/// space, where a mesh reaching past this has lost every digit of its shape (and its area in
/// voxels overflows).
inline constexpr double kMaxMeshCoordinate = 1e15;

struct MeshReadOptions
{
    /// Close each hole (border loop) with a flat triangulation so the interior is defined.
    bool fillHoles = true;
    /// Look for intersecting faces (reported, never changed). A clean closed mesh read without
    /// a report skips it: there the check would only report.
    bool checkSelfIntersections = true;
};

/// What reading found and did; every entry of @c warnings is one sentence for a person,
/// saying what is wrong and what voxelization will do about it.
struct MeshReport
{
    std::size_t inputPoints = 0, inputPolygons = 0;
    std::size_t mergedPoints = 0; ///< duplicate or unused points removed
    std::size_t removedPolygons = 0; ///< degenerate or duplicate polygons removed
    std::size_t splitPoints = 0; ///< points duplicated to make the mesh manifold
    std::size_t borderEdges = 0, holes = 0, holesFilled = 0;
    bool selfIntersecting = false;
    bool outwardOriented = false; ///< whether the result bounds its volume outward
    std::size_t triangles = 0;
    std::vector<std::string> warnings;
    std::vector<std::pair<std::string, double>> stepSeconds; ///< wall time of each step, in order
};

/// Read a polygon soup from @a path (format from the extension: .obj .ply .off .stl),
/// merge duplicate points, drop degenerate and duplicate polygons, orient consistently
/// (splitting non-manifold points), triangulate, fill holes when asked, orient outward
/// when closed. Throws vxf::Error naming the file when it cannot be read or holds no
/// triangles. Never prints: findings go to @a report.
TriangleMesh readMesh(
    const std::string& path, const MeshReadOptions& options = {}, MeshReport* report = nullptr, Interrupter* interrupter = nullptr);

/// Test @a mesh for intersecting faces; on a hit set report.selfIntersecting and add the
/// warning. Parallel (TBB). Separate from readMesh() so callers can overlap it with other
/// work (`vxf voxelize` runs it beside the voxelization).
void checkSelfIntersections(const TriangleMesh& mesh, MeshReport& report);

/// File extensions readMesh() accepts, lower case with the dot.
const std::vector<std::string>& meshFileExtensions();

} // namespace vxf
