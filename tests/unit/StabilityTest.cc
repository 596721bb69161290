// Hard cases through voxelize → light → scatter → render: every output finite and bounded.
#include <vxf/light/DirectLight.h>
#include <vxf/render/Render.h>
#include <vxf/scatter/Scatter.h>

#include <vxf/core/ProceduralMesh.h>
#include <vxf/io/MeshFile.h>
#include <vxf/voxelize/Voxelize.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <functional>

namespace {

struct Bounds
{
    double maxDirect = 0.0, maxScatter = 0.0, maxPixel = 0.0;
    bool finite = true, nonNegative = true;
    std::size_t passes = 0;
    std::string stopReason;
};

vxf::ScatterOptions fewPassesWithTail()
{
    vxf::ScatterOptions options;
    options.passes = 4;
    options.pass.directions = 16;
    options.extrapolateTail = true;
    options.accelerate = false; // plain passes and their tail (accelerated gathers: SweepSolveTest)
    return options;
}

/// The whole chain on @a mesh with a point light 1.5 longest sides above its centre;
/// @a edit changes the lit set before scattering, as an artist might.
Bounds runChain(const vxf::TriangleMesh& mesh, const vxf::Material& m, int dim, const vxf::ScatterOptions& options = fewPassesWithTail(),
    const std::function<void(vxf::VoxelSet&)>& edit = {})
{
    vxf::VoxelizeOptions voxelize;
    voxelize.dim = dim;
    vxf::VoxelSet set = vxf::voxelize(mesh, voxelize);
    const vxf::Medium medium(set, m);
    const openvdb::BBoxd box = mesh.bounds();
    vxf::Light light;
    light.type = vxf::Light::Type::Point;
    light.position = box.getCenter() + openvdb::Vec3d(0, 0, 1.5 * box.extents()[box.maxExtent()]);
    light.intensity = 1.0;
    vxf::computeDirectLight(set, medium, {light});
    if (edit) edit(set);
    const vxf::Medium edited(set, m);
    const auto report = vxf::scatter(set, edited, options);
    vxf::Scene view;
    view.camera.position = box.getCenter() + openvdb::Vec3d(0, -3.0 * box.extents().length(), 0);
    view.camera.lookAt = box.getCenter();
    vxf::RenderOptions render;
    render.width = 24;
    render.height = 16;
    render.samples = 1;
    const vxf::RenderedImage image = vxf::render(set, edited, view, render);

    Bounds b;
    b.passes = report.passes.size();
    b.stopReason = report.stopReason;
    for (const char* name : {"direct", "scatter"}) {
        for (auto it = set.get<openvdb::Vec3SGrid>(name)->cbeginValueOn(); it; ++it) {
            for (int c = 0; c < 3; ++c) {
                const double v = (*it)[c];
                b.finite = b.finite && std::isfinite(v);
                b.nonNegative = b.nonNegative && v >= 0.0;
                double& peak = std::string(name) == "direct" ? b.maxDirect : b.maxScatter;
                peak = std::max(peak, v);
            }
        }
    }
    for (const auto& p : image.combined) {
        for (int c = 0; c < 3; ++c) {
            b.finite = b.finite && std::isfinite(p[c]);
            b.nonNegative = b.nonNegative && p[c] >= 0.0f;
            b.maxPixel = std::max(b.maxPixel, double(p[c]));
        }
    }
    return b;
}

} // namespace

TEST_CASE("hard cases stay finite and bounded through the whole chain", "[stability]")
{
    const auto sphere = vxf::makeSphere(openvdb::Vec3d(0.0), 1.0, 32, 64);
    // Point light at distance >= 0.5 from the sphere: φ0 <= I / 0.5^2 = 4, and the scatter sum
    // is at most φ0 · a / (1 − a) with the extrapolated tail capped at 0.99.
    SECTION("extinction from 1e-6 to 1e6 per unit")
    {
        for (double sigmaT : {1e-6, 1.0, 1e6}) {
            INFO("sigma_t " << sigmaT);
            const Bounds b = runChain(sphere, vxf::test::albedoMaterial(sigmaT, 0.5), 24);
            CHECK(b.finite);
            CHECK(b.nonNegative);
            CHECK(b.maxDirect <= 4.0 + 1e-6);
            CHECK(b.maxScatter <= 4.0 + 1e-6);
        }
    }
    SECTION("albedo 0.9999")
    {
        const Bounds b = runChain(sphere, vxf::test::albedoMaterial(10.0, 0.9999), 24);
        CHECK(b.finite);
        CHECK(b.nonNegative);
        CHECK(b.maxScatter <= 4.0 * 100.0);
    }
    SECTION("a mesh 1e5 units from the origin")
    {
        const Bounds far = runChain(vxf::makeSphere(openvdb::Vec3d(1e5, -1e5, 1e5), 1.0, 32, 64), vxf::test::albedoMaterial(4.0, 0.8), 24);
        const Bounds near = runChain(sphere, vxf::test::albedoMaterial(4.0, 0.8), 24);
        CHECK(far.finite);
        CHECK(far.maxDirect == Approx(near.maxDirect).epsilon(0.02)); // the same scene, translated
    }
    SECTION("a one-voxel-thin shell")
    {
        // Box 0.04 thick at a voxel size of 1/24 of its width: thinner than a voxel.
        const Bounds b =
            runChain(vxf::makeBox(openvdb::Vec3d(-1, -1, -0.02), openvdb::Vec3d(1, 1, 0.02)), vxf::test::albedoMaterial(20.0, 0.9), 48);
        CHECK(b.finite);
        CHECK(b.nonNegative);
        CHECK(b.maxDirect <= 4.0 + 1e-6);
    }
}

TEST_CASE("a medium of many mean free paths a voxel stays non-negative and bounded with either accelerated kernel", "[stability][dense]")
{
    // Radius 1 at dim 32 (a voxel 0.0625) and a mean free path of 0.003: 20 mean free paths a
    // voxel, albedo 0.99. The diffusion correction (and the gathers' sweeps) overshot by tens of
    // times a sweep there, the iterates alternating in sign: the sum reached -1.7e26 in 16
    // sweeps with exit 0. The correction is dropped when it amplifies the change, and the
    // iteration restarts from zero; what a correction leaves below zero is set to zero.
    const auto sphere = vxf::makeSphere(openvdb::Vec3d(0.0), 1.0, 32, 64);
    for (const vxf::ScatterKernel kernel : {vxf::ScatterKernel::Sweep, vxf::ScatterKernel::Gather}) {
        INFO((kernel == vxf::ScatterKernel::Sweep ? "sweeps" : "gathers"));
        vxf::ScatterOptions options;
        options.passes = 16;
        options.pass.directions = 16;
        options.pass.kernel = kernel;
        const Bounds b = runChain(sphere, vxf::test::albedoMaterial(1.0 / 0.003, 0.99), 32, options);
        CHECK(b.finite);
        CHECK(b.nonNegative);
        CHECK(b.maxDirect <= 4.0 + 1e-6);
        CHECK(b.maxScatter <= 4.0 * 99.0); // φ0·a/(1−a): an infinite medium's
        if (kernel == vxf::ScatterKernel::Sweep) CHECK_THAT(b.stopReason, Catch::Contains("restarted from zero"));
    }
}

TEST_CASE("albedo 0.9999 converges on coarse passes, finite and bounded", "[stability][coarse]")
{
    // σt R = 20, albedo 0.9999: the plain iteration needs thousands of passes; the coarse
    // lattice takes them in seconds, and once their ratio settles the rest of the series is
    // added. Light escapes the ball, so the sum stays far below the infinite-medium bound
    // φ0·a/(1−a) = 4·9999. A tolerance ten times tighter runs more passes to the same sum.
    vxf::ScatterOptions options;
    options.passes = 20000;
    options.tolerance = 1e-3;
    options.pass.directions = 16;
    options.finePasses = 2;
    options.coarseFactor = 4;
    const vxf::TriangleMesh ball = vxf::makeSphere(openvdb::Vec3d(0.0), 1.0, 32, 64);
    const vxf::Material m = vxf::test::albedoMaterial(20.0, 0.9999);
    const Bounds b = runChain(ball, m, 24, options);
    INFO(b.passes << " passes: " << b.stopReason);
    CHECK(b.finite);
    CHECK(b.nonNegative);
    CHECK(b.stopReason.find("known to within") != std::string::npos); // the tolerance, not the cap, stopped it
    CHECK(b.maxScatter < 4.0 * 9999.0);
    options.tolerance = 1e-4;
    const Bounds tight = runChain(ball, m, 24, options);
    INFO(tight.passes << " passes: " << tight.stopReason);
    CHECK(tight.passes > b.passes);
    CHECK(b.maxScatter == Approx(tight.maxScatter).epsilon(5e-3));
}

TEST_CASE("open, non-manifold and self-intersecting meshes light and render finitely", "[stability]")
{
    const vxf::Material m = vxf::test::albedoMaterial(10.0, 0.9);
    SECTION("two cubes sharing an edge (non-manifold), voxelized as they are")
    {
        vxf::TriangleMesh mesh = vxf::makeBox(openvdb::Vec3d(0, 0, 0), openvdb::Vec3d(1, 1, 1));
        const vxf::TriangleMesh other = vxf::makeBox(openvdb::Vec3d(1, 1, 0), openvdb::Vec3d(2, 2, 1));
        const auto offset = openvdb::Index32(mesh.points.size());
        mesh.points.insert(mesh.points.end(), other.points.begin(), other.points.end());
        for (auto t : other.triangles) mesh.triangles.push_back(t + openvdb::Vec3I(offset));
        const Bounds b = runChain(mesh, m, 32);
        CHECK(b.finite);
        CHECK(b.nonNegative);
        CHECK(b.maxDirect > 0.0);
    }
    SECTION("an open cube (one face missing) read, its hole filled")
    {
        vxf::test::TempDir dir;
        // A unit cube's eight corners and five of its six faces (the top, z = 1, is open).
        vxf::test::spit(dir.path("open.off"),
            "OFF\n8 5 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
            "4 0 3 2 1\n4 0 1 5 4\n4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n");
        vxf::MeshReport report;
        const vxf::TriangleMesh mesh = vxf::readMesh(dir.path("open.off"), {}, &report);
        CHECK(report.holesFilled == 1);
        const Bounds b = runChain(mesh, m, 32);
        CHECK(b.finite);
        CHECK(b.nonNegative);
        CHECK(b.maxDirect > 0.0);
    }
    SECTION("a box pierced by a triangle (self-intersecting)")
    {
        vxf::TriangleMesh mesh = vxf::makeBox(openvdb::Vec3d(0, 0, 0), openvdb::Vec3d(1, 1, 1));
        const auto n = openvdb::Index32(mesh.points.size());
        mesh.points.insert(
            mesh.points.end(), {openvdb::Vec3d(0.5, -0.5, 0.5), openvdb::Vec3d(0.5, 1.5, 0.3), openvdb::Vec3d(0.5, 0.5, 1.5)});
        mesh.triangles.push_back(openvdb::Vec3I(n, n + 1, n + 2));
        const Bounds b = runChain(mesh, m, 32);
        CHECK(b.finite);
        CHECK(b.nonNegative);
    }
}

TEST_CASE("artist grids with negative values scatter and render finitely", "[stability]")
{
    const auto sphere = vxf::makeSphere(openvdb::Vec3d(0.0), 1.0, 32, 64);
    const vxf::Material m = vxf::test::albedoMaterial(10.0, 0.9);
    SECTION("scatter_source negated in half the volume")
    {
        const Bounds plain = runChain(sphere, m, 24);
        const Bounds b = runChain(sphere, m, 24, fewPassesWithTail(), [](vxf::VoxelSet& set) {
            auto j = set.get<openvdb::Vec3SGrid>("scatter_source");
            for (auto it = j->beginValueOn(); it; ++it) {
                if (it.getCoord().x() < 0) it.setValue(-*it);
            }
        });
        CHECK(b.finite);
        CHECK(b.maxScatter <= plain.maxScatter * 1.0001); // negative light only takes away
    }
    SECTION("density -0.5 in half the volume")
    {
        const Bounds plain = runChain(sphere, m, 24);
        Bounds b = runChain(sphere, m, 24, fewPassesWithTail(), [](vxf::VoxelSet& set) {
            auto density = set.get<openvdb::FloatGrid>("density");
            density->tree().voxelizeActiveTiles();
            for (auto it = density->beginValueOn(); it; ++it) {
                if (it.getCoord().x() < 0) it.setValue(-0.5f);
            }
        });
        // Negative extinction is clamped to none: it never amplifies light.
        CHECK(b.finite);
        CHECK(std::isfinite(b.maxPixel));
        CHECK(b.maxPixel < 100.0 * std::max(plain.maxPixel, 1e-6));
    }
}
