#include <vxf/io/MeshFile.h>

#include <vxf/core/Error.h>
#include <vxf/io/InputFile.h>

#include <CGAL/exceptions.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/triangulate_faces.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Surface_mesh.h>

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cctype>
#include <filesystem>
#include <iterator>
#include <fstream>
#include <sstream>
#include <vector>

namespace vxf {

namespace {

/// CGAL 5.5's PLY reader adds each `property` to the last `element` declared without checking
/// there is one: a header with a property first read past an empty vector (found by fuzzing,
/// tests/regress/fuzz/mesh). Checked here before CGAL reads the file.
/// Its element counts too: "element vertex -104" read as 2^64 − 104 vertices and ran for 48 s
/// (found by fuzzing); a count must be one the file's bytes can hold (a byte an item at least).
void checkPlyHeader(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    const auto bytes = std::uintmax_t(std::filesystem::file_size(path));
    std::string line;
    bool element = false;
    for (std::size_t number = 1; std::getline(in, line); ++number) {
        std::istringstream words(line);
        std::string keyword;
        words >> keyword;
        if (keyword == "end_header") return;
        if (keyword == "element") {
            element = true;
            std::string name, count;
            words >> name >> count;
            const bool digits = !count.empty() && count.find_first_not_of("0123456789") == std::string::npos;
            if (!digits || count.size() > 19 || std::stoull(count) > bytes) {
                throw InputError(path, number, 1,
                    fmt::format("PLY header: element '{}' has {} items, more than a file of {} bytes holds", name,
                        count.empty() ? "no count of" : count, bytes));
            }
        }
        if (keyword == "property" && !element) throw InputError(path, number, 1, "PLY header: 'property' before any 'element'");
    }
}

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
namespace PMP = CGAL::Polygon_mesh_processing;

std::string lowerExtension(const std::string& path)
{
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

/// Records the wall time between successive lap() calls.
class StepTimer
{
public:
    explicit StepTimer(MeshReport& report)
        : mReport(report)
        , mStart(std::chrono::steady_clock::now())
    {
    }
    void lap(const char* step)
    {
        const auto now = std::chrono::steady_clock::now();
        mReport.stepSeconds.emplace_back(step, std::chrono::duration<double>(now - mStart).count());
        mStart = now;
    }

private:
    MeshReport& mReport;
    std::chrono::steady_clock::time_point mStart;
};

/// Whether the soup already is an oriented 2-manifold (possibly with boundary): every
/// directed edge appears once, and the polygons around each vertex form a single fan.
/// O(n log n) (CGAL's is_polygon_soup_a_polygon_mesh is ~15x slower on the bunny).
/// @a borderEdges counts the border edges of a manifold soup (one per open fan).
bool isOrientedManifoldSoup(std::size_t pointCount, const std::vector<std::vector<std::size_t>>& polygons, std::size_t& borderEdges)
{
    borderEdges = 0;
    std::vector<std::uint64_t> directed;
    std::vector<std::uint32_t> cornerStart(pointCount + 1, 0);
    for (const auto& polygon : polygons) {
        for (std::size_t i = 0; i < polygon.size(); ++i) {
            directed.push_back(std::uint64_t(polygon[i]) << 32 | std::uint64_t(polygon[(i + 1) % polygon.size()]));
            ++cornerStart[polygon[i] + 1];
        }
    }
    std::sort(directed.begin(), directed.end());
    if (std::adjacent_find(directed.begin(), directed.end()) != directed.end()) return false;

    // Corners grouped by vertex: (previous, next) vertex of each.
    for (std::size_t v = 0; v < pointCount; ++v) cornerStart[v + 1] += cornerStart[v];
    std::vector<std::pair<std::uint32_t, std::uint32_t>> corners(cornerStart[pointCount]);
    std::vector<std::uint32_t> fill(cornerStart.begin(), cornerStart.end() - 1);
    for (const auto& polygon : polygons) {
        const std::size_t n = polygon.size();
        for (std::size_t i = 0; i < n; ++i) {
            corners[fill[polygon[i]]++] = {std::uint32_t(polygon[(i + n - 1) % n]), std::uint32_t(polygon[(i + 1) % n])};
        }
    }
    // Around a vertex, the corner after c is the one whose next vertex is c's previous one.
    for (std::size_t v = 0; v < pointCount; ++v) {
        const auto begin = corners.begin() + cornerStart[v], end = corners.begin() + cornerStart[v + 1];
        const auto k = std::size_t(end - begin);
        if (k == 0) continue;
        auto start = begin; // a chain starts at a corner that no other corner leads to
        for (auto c = begin; c != end; ++c) {
            const bool hasPredecessor = std::any_of(begin, end, [&](const auto& o) { return o.first == c->second; });
            if (!hasPredecessor) { // an open fan: the edge to c's next vertex is a border
                start = c;
                ++borderEdges;
                break;
            }
        }
        std::size_t visited = 1;
        for (auto c = start; visited <= k;) {
            const auto next = std::find_if(begin, end, [&](const auto& o) { return o.second == c->first; });
            if (next == end || next == start) break;
            c = next;
            ++visited;
        }
        if (visited != k) return false;
    }
    return true;
}

void reportSelfIntersections(const Mesh& mesh, MeshReport& report)
{
    // Sequential: on 2 cores the parallel version is no faster (0.11 s vs 0.10 s on the bunny),
    // and `vxf voxelize` runs this beside the voxelization, which has the cores busy.
    // CGAL's test requires triangles: a face triangulate_faces could not split (a degenerate
    // polygon) failed its precondition (found by fuzzing, tests/regress/fuzz/mesh).
    if (!CGAL::is_triangle_mesh(mesh)) {
        report.warnings.push_back("some faces could not be triangulated (degenerate polygons): the self-intersection test was skipped");
        return;
    }
    report.selfIntersecting = PMP::does_self_intersect<CGAL::Sequential_tag>(mesh);
    if (report.selfIntersecting) {
        report.warnings.push_back("the mesh intersects itself; voxelization takes the union of the enclosed regions "
                                  "(the interior is what no path from outside reaches)");
    }
}

/// CGAL 5.5's OFF reader sizes each face by the count its line starts with before reading the
/// indices: "30000000000 0 1 2" asked for 240 GB, written as zeros (found by fuzzing,
/// tests/regress/fuzz/mesh). A text OFF's counts are checked here against what the file can
/// hold (an index takes two bytes at least), before CGAL reads it. Binary OFF ("OFF BINARY") is
/// left to CGAL.
void checkOffCounts(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    const auto bytes = std::uintmax_t(std::filesystem::file_size(path));
    std::string line;
    std::size_t number = 0, vertices = 0, faces = 0, seen = 0;
    bool header = false, counts = false;
    while (std::getline(in, line)) {
        ++number;
        const std::string content = line.substr(0, line.find('#'));
        if (counts) { // vertices, then faces: the count a face line starts with
            if (content.find_first_not_of(" \t\r") == std::string::npos || seen++ < vertices) continue;
            std::istringstream face(content);
            std::uintmax_t count = 0;
            if (!(face >> count)) return;
            if (count > bytes / 2) {
                throw InputError(
                    path, number, 1, fmt::format("OFF face lists {} vertices, more than a file of {} bytes holds", count, bytes));
            }
            if (seen >= vertices + faces) return;
            continue;
        }
        std::istringstream words(content);
        std::vector<std::string> tokens{std::istream_iterator<std::string>(words), std::istream_iterator<std::string>()};
        if (!header && !tokens.empty() && tokens[0].find("OFF") != std::string::npos) { // "OFF", "COFF", "NOFF", ...
            header = true;
            if (std::find(tokens.begin(), tokens.end(), "BINARY") != tokens.end()) return;
            tokens.erase(tokens.begin()); // the counts may follow on the same line
        }
        if (tokens.empty()) continue; // blank or comment
        header = true;
        counts = true;
        std::istringstream numbers(tokens[0] + " " + (tokens.size() > 1 ? tokens[1] : ""));
        if (!(numbers >> vertices >> faces)) return; // CGAL reports the malformed header
        if (vertices > bytes || faces > bytes) {
            throw InputError(path, number, 1,
                fmt::format("OFF header: {} vertices and {} faces, more than a file of {} bytes holds", vertices, faces, bytes));
        }
    }
}

} // namespace

void checkSelfIntersections(const TriangleMesh& triangles, MeshReport& report)
{
    Mesh mesh;
    mesh.reserve(Mesh::size_type(triangles.points.size()), Mesh::size_type(3 * triangles.triangles.size() / 2),
        Mesh::size_type(triangles.triangles.size()));
    std::vector<Mesh::Vertex_index> vertices;
    vertices.reserve(triangles.points.size());
    for (const auto& p : triangles.points) vertices.push_back(mesh.add_vertex(Point(p[0], p[1], p[2])));
    for (const auto& t : triangles.triangles) {
        if (mesh.add_face(vertices[t[0]], vertices[t[1]], vertices[t[2]]) == Mesh::null_face()) {
            // Not a valid polygon mesh (readMesh's output always is): test as a soup instead.
            std::vector<std::vector<std::size_t>> polygons;
            for (const auto& u : triangles.triangles) polygons.push_back({u[0], u[1], u[2]});
            std::vector<Point> points;
            for (const auto& p : triangles.points) points.emplace_back(p[0], p[1], p[2]);
            PMP::orient_polygon_soup(points, polygons);
            mesh.clear();
            PMP::polygon_soup_to_polygon_mesh(points, polygons, mesh);
            break;
        }
    }
    reportSelfIntersections(mesh, report);
}

const std::vector<std::string>& meshFileExtensions()
{
    static const std::vector<std::string> extensions = {".obj", ".ply", ".off", ".stl"};
    return extensions;
}

namespace {

/// Read @a path's polygon soup (CGAL), its counts checked first where the format has them.
void readPolygonSoup(
    const std::string& path, const std::string& ext, std::vector<Point>& points, std::vector<std::vector<std::size_t>>& polygons)
{
    if (ext == ".ply") checkPlyHeader(path);
    if (ext == ".off") checkOffCounts(path);
    bool ok = false;
    try {
        ok = CGAL::IO::read_polygon_soup(path, points, polygons, CGAL::parameters::verbose(false));
    } catch (const std::exception& e) {
        throw Error(fmt::format("{}: cannot parse mesh: {}", path, e.what()));
    }
    if (!ok) throw Error(fmt::format("{}: cannot parse mesh (not a valid {} file)", path, ext));
}

/// Every vertex finite and within ±kMaxMeshCoordinate, every face's indices within the vertices.
void checkSoup(const std::string& path, const std::vector<Point>& points, const std::vector<std::vector<std::size_t>>& polygons)
{
    for (std::size_t i = 0; i < points.size(); ++i) {
        const auto& p = points[i];
        const bool finite = std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z());
        if (!finite || std::abs(p.x()) > kMaxMeshCoordinate || std::abs(p.y()) > kMaxMeshCoordinate ||
            std::abs(p.z()) > kMaxMeshCoordinate) {
            throw Error(fmt::format("{}: vertex {} (counting from 0) at ({:.6g}, {:.6g}, {:.6g}) is {}", path, i, p.x(), p.y(), p.z(),
                finite ? fmt::format("beyond ±{:.0e}, the coordinates vxf voxelizes", kMaxMeshCoordinate) : "not a finite point"));
        }
    }
    for (const auto& polygon : polygons) {
        for (std::size_t index : polygon) {
            if (index >= points.size()) {
                throw Error(fmt::format("{}: a face refers to vertex {} but there are only {}", path, index, points.size()));
            }
        }
    }
}

/// Repair a soup that is not already clean (duplicate points merged, degenerate and duplicate
/// polygons and unused points dropped), noting it in @a report; whether it is then an oriented
/// manifold, its border edges in @a borderEdges.
bool repairSoup(const std::string& path, std::vector<Point>& points, std::vector<std::vector<std::size_t>>& polygons, MeshReport& report,
    std::size_t& borderEdges)
{
    const auto degenerate = [&](const std::vector<std::size_t>& polygon) {
        for (std::size_t i = 2; i < polygon.size(); ++i) {
            if (!CGAL::collinear(points[polygon[0]], points[polygon[1]], points[polygon[i]])) return false;
        }
        return true;
    };
    // A soup that is already clean — triangles with distinct corners and area, every point
    // used, an oriented closed manifold — needs no repair (the common case; saves a sort).
    bool manifold = false;
    std::vector<bool> used(points.size(), false);
    bool clean = true;
    for (const auto& p : polygons) {
        clean = clean && p.size() == 3 && p[0] != p[1] && p[1] != p[2] && p[0] != p[2];
        if (!clean) break;
        used[p[0]] = used[p[1]] = used[p[2]] = true;
    }
    clean = clean && std::all_of(used.begin(), used.end(), [](bool u) { return u; }) &&
        std::none_of(polygons.begin(), polygons.end(), degenerate);
    manifold = clean && isOrientedManifoldSoup(points.size(), polygons, borderEdges);
    if (!manifold || borderEdges > 0) {
        // Repair: merge duplicate points, drop degenerate and duplicate polygons and unused points.
        PMP::repair_polygon_soup(points, polygons);
        polygons.erase(std::remove_if(polygons.begin(), polygons.end(), degenerate), polygons.end());
        report.mergedPoints = report.inputPoints - std::min(report.inputPoints, points.size());
        report.removedPolygons = report.inputPolygons - std::min(report.inputPolygons, polygons.size());
        if (polygons.empty()) {
            throw Error(fmt::format("{}: the mesh has no usable faces ({} read, all degenerate)", path, report.inputPolygons));
        }
        if (report.removedPolygons > 0) {
            report.warnings.push_back(
                fmt::format("removed {} degenerate or duplicate faces; voxelization ignores them", report.removedPolygons));
        }
        manifold = isOrientedManifoldSoup(points.size(), polygons, borderEdges);
    }
    return manifold;
}

/// Count the border edges and holes; fill the holes (options.fillHoles) or say they are left open.
void closeHoles(Mesh& mesh, const MeshReadOptions& options, MeshReport& report, Interrupter* interrupter)
{
    for (auto h : mesh.halfedges()) {
        if (mesh.is_border(h)) ++report.borderEdges;
    }
    if (report.borderEdges == 0) return;
    std::vector<Mesh::Halfedge_index> loops;
    PMP::extract_boundary_cycles(mesh, std::back_inserter(loops));
    report.holes = loops.size();
    if (options.fillHoles) {
        InterruptStep step(interrupter, "filling holes");
        for (auto h : loops) {
            std::vector<Mesh::Face_index> patch;
            PMP::triangulate_hole(mesh, h, std::back_inserter(patch));
            if (!patch.empty()) ++report.holesFilled;
            checkInterrupt(interrupter);
        }
        report.warnings.push_back(fmt::format("the mesh is open: {} holes ({} border edges); filled {} of them with flat "
                                              "triangulations before voxelizing{}",
            report.holes, report.borderEdges, report.holesFilled,
            report.holesFilled < report.holes ? "; the interior may leak through the rest and is then left empty" : ""));
    } else {
        report.warnings.push_back(fmt::format("the mesh is open: {} holes ({} border edges), left open as asked; the interior "
                                              "is what no path from outside reaches, so it leaks through holes wider than the band",
            report.holes, report.borderEdges));
    }
}

/// Turn a closed mesh's faces outward.
void orientOutward(Mesh& mesh, MeshReport& report)
{
    // CGAL's orientation tests assume faces that are not flat around the extreme vertex; where
    // they are (a self-intersecting or degenerate mesh) its checked builds stop on a failed
    // assertion (found by fuzzing, tests/regress/fuzz/mesh). The orientation is then left as
    // the file gives it: the voxelization decides inside by flood fill, not by orientation.
    try {
        if (!report.selfIntersecting && report.splitPoints == 0) {
            PMP::orient_to_bound_a_volume(mesh);
        } else if (!PMP::is_outward_oriented(mesh)) {
            PMP::reverse_face_orientations(mesh);
        }
        report.outwardOriented = true;
    } catch (const CGAL::Failure_exception&) {
        report.warnings.push_back("the mesh's orientation could not be determined (flat faces around its extreme "
                                  "vertex); its faces are left as the file orients them");
    }
}

/// The mesh's points and triangles.
TriangleMesh exportTriangles(const Mesh& mesh)
{
    TriangleMesh result;
    result.points.reserve(mesh.number_of_vertices());
    std::vector<openvdb::Index> remap(mesh.num_vertices(), 0);
    for (auto v : mesh.vertices()) {
        const Point& p = mesh.point(v);
        remap[v.idx()] = openvdb::Index(result.points.size());
        result.points.emplace_back(p.x(), p.y(), p.z());
    }
    result.triangles.reserve(mesh.number_of_faces());
    for (auto f : mesh.faces()) {
        openvdb::Vec3I tri;
        int corner = 0;
        for (auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) {
            if (corner < 3) tri[corner] = remap[v.idx()];
            ++corner;
        }
        if (corner == 3) result.triangles.push_back(tri);
    }
    return result;
}

} // namespace

TriangleMesh readMesh(const std::string& path, const MeshReadOptions& options, MeshReport* reportOut, Interrupter* interrupter)
{
    MeshReport report;
    const std::string ext = lowerExtension(path);
    const auto& known = meshFileExtensions();
    if (std::find(known.begin(), known.end(), ext) == known.end()) {
        throw Error(fmt::format("{}: unsupported mesh format '{}' (expected one of .obj .ply .off .stl)", path, ext));
    }
    requireRegularFile(path);
    if (!std::ifstream(path).good()) throw Error(fmt::format("{}: cannot open mesh file", path));

    StepTimer timer(report);
    std::vector<Point> points;
    std::vector<std::vector<std::size_t>> polygons;
    {
        InterruptStep step(interrupter, "reading mesh");
        readPolygonSoup(path, ext, points, polygons);
    }
    report.inputPoints = points.size();
    report.inputPolygons = polygons.size();
    checkSoup(path, points, polygons);
    checkInterrupt(interrupter);
    timer.lap("read");

    std::size_t soupBorderEdges = 0;
    const bool manifold = repairSoup(path, points, polygons, report, soupBorderEdges);
    timer.lap("check and repair");

    // Fast path, the common case: a closed, oriented, manifold triangle soup needs no
    // half-edge mesh; it is only turned outward as a whole when its volume is negative.
    const bool allTriangles = std::all_of(polygons.begin(), polygons.end(), [](const auto& p) { return p.size() == 3; });
    if (manifold && soupBorderEdges == 0 && allTriangles) {
        TriangleMesh result;
        result.points.reserve(points.size());
        for (const Point& p : points) result.points.emplace_back(p.x(), p.y(), p.z());
        result.triangles.reserve(polygons.size());
        for (const auto& p : polygons) result.triangles.emplace_back(p[0], p[1], p[2]);
        if (result.volume() < 0.0) {
            for (auto& t : result.triangles) std::swap(t[1], t[2]);
        }
        report.outwardOriented = true;
        timer.lap("export");
        // Here the check only reports: with nobody to read the report it would change nothing
        // (the slow path below needs it to choose how to orient).
        if (options.checkSelfIntersections && reportOut) {
            InterruptStep step(interrupter, "checking self-intersections");
            checkSelfIntersections(result, report);
            timer.lap("self-intersections");
        }
        report.triangles = result.triangles.size();
        if (reportOut) *reportOut = std::move(report);
        return result;
    }

    // Consistent orientation; non-manifold points are split so the soup becomes a mesh.
    const std::size_t before = points.size();
    if (!manifold && !PMP::orient_polygon_soup(points, polygons)) {
        report.splitPoints = points.size() - before;
        report.warnings.push_back(fmt::format("the mesh is not manifold: {} vertices were duplicated to orient it; the surface is "
                                              "voxelized as given, and the interior is what no path from outside reaches",
            report.splitPoints));
    }
    checkInterrupt(interrupter);
    timer.lap("orient soup");

    Mesh mesh;
    PMP::polygon_soup_to_polygon_mesh(points, polygons, mesh);
    PMP::triangulate_faces(mesh);
    timer.lap("build and triangulate");

    closeHoles(mesh, options, report, interrupter);

    timer.lap("holes");

    if (options.checkSelfIntersections) {
        InterruptStep step(interrupter, "checking self-intersections");
        reportSelfIntersections(mesh, report);
    }

    timer.lap("self-intersections");

    if (CGAL::is_closed(mesh)) orientOutward(mesh, report);

    TriangleMesh result = exportTriangles(mesh);
    report.triangles = result.triangles.size();
    timer.lap("orient outward and export");
    if (reportOut) *reportOut = std::move(report);
    return result;
}

} // namespace vxf
