// bench/stability: the hard cases at full size through voxelize → light → scatter → render,
// in process: whether every output is finite, the largest value, the energy ratio of the
// last pass, the passes run (and why they stopped), and seconds. Prints a markdown table.
//
// Usage: bench_stability MESH_DIR   (MESH_DIR holds libcgal-demo's elephant-with-holes.off,
//        open_cube.off, mesh_with_border.off, tetra_intersected_by_triangle.off; see run)
#include <vxf/core/ProceduralMesh.h>
#include <vxf/io/MeshFile.h>
#include <vxf/light/DirectLight.h>
#include <vxf/ops/Normalize.h>
#include <vxf/render/Render.h>
#include <vxf/scatter/Scatter.h>
#include <vxf/voxelize/Voxelize.h>

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <iostream>

namespace {

struct Row
{
    std::string name;
    bool finite = true;
    double maxValue = 0.0, minValue = 0.0;
    double lastRatio = 0.0;
    std::size_t passes = 0;
    std::string stop;
    double seconds = 0.0;
    bool skipped = false; ///< not among the cases asked for (gOnly)
};

vxf::Material albedoMaterial(double sigmaT, double albedo)
{
    vxf::Material m;
    m.sigmaS = openvdb::Vec3d(sigmaT * albedo);
    m.sigmaA = openvdb::Vec3d(sigmaT * (1.0 - albedo));
    return m;
}

void scan(const openvdb::Vec3SGrid& grid, Row& row)
{
    for (auto it = grid.cbeginValueOn(); it; ++it) {
        for (int c = 0; c < 3; ++c) {
            const double v = (*it)[c];
            row.finite = row.finite && std::isfinite(v);
            row.maxValue = std::max(row.maxValue, v);
            row.minValue = std::min(row.minValue, v);
        }
    }
}

using Edit = std::function<void(vxf::VoxelSet&)>;

/// The whole chain on @a mesh: a point light 1.5 longest sides above its centre (intensity 1),
/// @a edit applied after the light stage (an artist's change), then scatter and a small render.
/// Only the cases whose name holds this (bench_stability's second argument; empty: every case).
std::string gOnly;

Row runChain(const std::string& name, const vxf::TriangleMesh& mesh, const vxf::Material& m, int dim, const vxf::ScatterOptions& scatter,
    const Edit& edit = {})
{
    const auto start = std::chrono::steady_clock::now();
    Row row;
    row.name = name;
    if (name.find(gOnly) == std::string::npos) {
        row.skipped = true;
        return row;
    }
    vxf::VoxelizeOptions voxelize;
    voxelize.dim = dim;
    vxf::VoxelSet set = vxf::voxelize(mesh, voxelize);
    const openvdb::BBoxd box = mesh.bounds();
    vxf::Light light;
    light.type = vxf::Light::Type::Point;
    light.position = box.getCenter() + openvdb::Vec3d(0, 0, 1.5 * box.extents()[box.maxExtent()]);
    {
        const vxf::Medium medium(set, m);
        vxf::computeDirectLight(set, medium, {light});
    }
    if (edit) edit(set);
    const vxf::Medium medium(set, m);
    const vxf::ScatterReport report = vxf::scatter(set, medium, scatter);
    row.passes = report.passes.size();
    row.lastRatio = report.passes.empty() ? 0.0 : report.passes.back().ratio;
    row.stop = report.stopReason;
    vxf::Scene view;
    view.camera.position = box.getCenter() + openvdb::Vec3d(0, -3.0 * box.extents().length(), 0);
    view.camera.lookAt = box.getCenter();
    vxf::RenderOptions render;
    render.width = 64;
    render.height = 48;
    render.samples = 1;
    const vxf::RenderedImage image = vxf::render(set, medium, view, render);
    for (const char* grid : {"direct", "scatter", "illumination"}) scan(*set.get<openvdb::Vec3SGrid>(grid), row);
    for (const auto& p : image.combined) {
        for (int c = 0; c < 3; ++c) {
            row.finite = row.finite && std::isfinite(p[c]);
            row.maxValue = std::max(row.maxValue, double(p[c]));
        }
    }
    row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return row;
}

vxf::ScatterOptions plainPasses(int passes)
{
    vxf::ScatterOptions o;
    o.passes = passes;
    o.tolerance = 1e-3;
    o.pass.directions = 16;
    o.accelerate = false;
    return o;
}

vxf::ScatterOptions coarsePasses()
{
    vxf::ScatterOptions o = plainPasses(10000);
    o.finePasses = 4;
    o.coarseFactor = 4;
    return o;
}

/// The sweep kernel solving the whole sum with diffusion synthetic acceleration (at most 40 sweeps).
vxf::ScatterOptions acceleratedSweeps()
{
    vxf::ScatterOptions o = plainPasses(40);
    o.pass.kernel = vxf::ScatterKernel::Sweep;
    o.accelerate = true;
    return o;
}

/// The gather solving the whole sum, each gather corrected by accelerated sweeps (at most 40 gathers).
vxf::ScatterOptions acceleratedGathers()
{
    vxf::ScatterOptions o = plainPasses(40);
    o.accelerate = true;
    return o;
}

/// Two unit cubes sharing one edge: a non-manifold edge.
vxf::TriangleMesh cubesSharingAnEdge()
{
    vxf::TriangleMesh a = vxf::makeBox(openvdb::Vec3d(0, 0, 0), openvdb::Vec3d(1, 1, 1));
    const vxf::TriangleMesh b = vxf::makeBox(openvdb::Vec3d(1, 1, 0), openvdb::Vec3d(2, 2, 1));
    const auto offset = openvdb::Index32(a.points.size());
    a.points.insert(a.points.end(), b.points.begin(), b.points.end());
    for (auto t : b.triangles) a.triangles.push_back(t + openvdb::Vec3I(offset));
    return a;
}

std::string row(const Row& r)
{
    return fmt::format("| {} | {} | {:.4g} | {:.4g} | {:.4f} | {} | {} | {:.2f} |", r.name, r.finite ? "yes" : "**NO**", r.maxValue,
        r.minValue, r.lastRatio, r.passes, r.stop, r.seconds);
}

} // namespace

int main(int argc, char** argv)
{
    if (argc != 2 && argc != 3) {
        std::cerr << "usage: bench_stability MESH_DIR [ONLY]  (ONLY: run just the cases whose name holds it)\n";
        return 2;
    }
    if (argc == 3) gOnly = argv[2];
    openvdb::initialize();
    const std::string meshes = argv[1];
    const auto sphere = vxf::makeSphere(openvdb::Vec3d(0.0), 1.0, 64, 128);
    std::cout << "| case | finite | max | min | last pass ratio | passes | stopped because | seconds |\n"
                 "|---|---|---|---|---|---|---|---|\n";
    std::cout.flush();
    const auto print = [](const Row& r) {
        if (!r.skipped) std::cout << row(r) << "\n" << std::flush;
    };

    // Albedo near 1: the plain iteration (at most 300 passes) against coarse passes.
    for (double albedo : {0.9, 0.99, 0.999, 0.9999}) {
        const vxf::Material m = albedoMaterial(50.0, albedo); // 100 mean free paths across
        print(runChain(fmt::format("albedo {}, sigma_t 50, plain passes (at most 300)", albedo), sphere, m, 48, plainPasses(300)));
        print(runChain(fmt::format("albedo {}, sigma_t 50, 4 fine passes then 4x coarser", albedo), sphere, m, 48, coarsePasses()));
        print(runChain(fmt::format("albedo {}, sigma_t 50, accelerated sweeps", albedo), sphere, m, 48, acceleratedSweeps()));
        print(runChain(fmt::format("albedo {}, sigma_t 50, accelerated gathers", albedo), sphere, m, 48, acceleratedGathers()));
    }
    // Extinction over twelve decades.
    for (double sigmaT : {1e-6, 1e-3, 1.0, 1e3, 1e6}) {
        print(runChain(fmt::format("sigma_t {:g} per unit, albedo 0.9", sigmaT), sphere, albedoMaterial(sigmaT, 0.9), 64, coarsePasses()));
        print(runChain(fmt::format("sigma_t {:g} per unit, albedo 0.9, accelerated sweeps", sigmaT), sphere, albedoMaterial(sigmaT, 0.9),
            64, acceleratedSweeps()));
        print(runChain(fmt::format("sigma_t {:g} per unit, albedo 0.9, accelerated gathers", sigmaT), sphere, albedoMaterial(sigmaT, 0.9),
            64, acceleratedGathers()));
    }
    // Geometry.
    // Voxel size 1/32: shells one and half a voxel thick (too thin for the level set to place
    // both faces, so their volume fractions carry the medium).
    for (double voxels : {1.0, 0.5}) {
        const double half = 0.5 * voxels / 32.0;
        print(runChain(fmt::format("shell {} voxel thick (box 2 x 2 x {} at dim 64)", voxels, 2.0 * half),
            vxf::makeBox(openvdb::Vec3d(-1, -1, -half), openvdb::Vec3d(1, 1, half)), albedoMaterial(20.0, 0.9), 64, coarsePasses()));
    }
    print(runChain("sphere 1e5 units from the origin", vxf::makeSphere(openvdb::Vec3d(1e5, -1e5, 1e5), 1.0, 64, 128),
        albedoMaterial(20.0, 0.9), 64, coarsePasses()));
    print(runChain("two cubes sharing an edge (non-manifold)", cubesSharingAnEdge(), albedoMaterial(10.0, 0.9), 64, coarsePasses()));
    for (const char* file : {"elephant-with-holes.off", "open_cube.off", "mesh_with_border.off", "tetra_intersected_by_triangle.off"}) {
        vxf::MeshReport report;
        const vxf::TriangleMesh mesh = vxf::readMesh(meshes + "/" + file, {}, &report);
        const double size = mesh.bounds().extents()[mesh.bounds().maxExtent()];
        print(
            runChain(fmt::format("{} ({} holes filled{})", file, report.holesFilled, report.selfIntersecting ? ", self-intersecting" : ""),
                mesh, albedoMaterial(20.0 / size, 0.9), 64, coarsePasses()));
    }
    // Artist grids.
    print(runChain("scatter_source negated in half the volume (artist edit)", sphere, albedoMaterial(20.0, 0.9), 64, coarsePasses(),
        [](vxf::VoxelSet& set) {
            auto j = set.get<openvdb::Vec3SGrid>("scatter_source");
            for (auto it = j->beginValueOn(); it; ++it) {
                if (it.getCoord().x() < 0) it.setValue(-*it);
            }
        }));
    print(runChain(
        "density -0.5 in half the volume (artist edit)", sphere, albedoMaterial(20.0, 0.9), 64, coarsePasses(), [](vxf::VoxelSet& set) {
            auto density = set.get<openvdb::FloatGrid>("density");
            density->tree().voxelizeActiveTiles();
            for (auto it = density->beginValueOn(); it; ++it) {
                if (it.getCoord().x() < 0) it.setValue(-0.5f);
            }
        }));
    {
        const auto start = std::chrono::steady_clock::now();
        auto zero = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
        zero->setName("zero");
        zero->tree().fill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(127)), openvdb::Vec3f(0.0f), true);
        zero->tree().voxelizeActiveTiles();
        vxf::ops::normalize(*zero);
        Row r;
        r.name = "an all-zero grid (2M voxels) through normalize";
        scan(*zero, r);
        r.stop = "(no passes)";
        r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        r.skipped = r.name.find(gOnly) == std::string::npos;
        print(r);
    }
    return 0;
}
