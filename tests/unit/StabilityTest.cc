// Hard cases through voxelize → light → scatter → render: every output finite and bounded.
#include <vxf/light/DirectLight.h>
#include <vxf/render/Render.h>
#include <vxf/scatter/Scatter.h>

#include <vxf/core/ProceduralMesh.h>
#include <vxf/voxelize/Voxelize.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

namespace {

struct Bounds
{
    double maxDirect = 0.0, maxScatter = 0.0, maxPixel = 0.0;
    bool finite = true;
};

/// The whole chain on @a mesh with a point light 1.5 longest sides above its centre.
Bounds runChain(const vxf::TriangleMesh& mesh, const vxf::Material& m, int dim)
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
    vxf::ScatterOptions options;
    options.passes = 4;
    options.pass.directions = 16;
    options.extrapolateTail = true;
    vxf::scatter(set, medium, options);
    vxf::Scene view;
    view.camera.position = box.getCenter() + openvdb::Vec3d(0, -3.0 * box.extents().length(), 0);
    view.camera.lookAt = box.getCenter();
    vxf::RenderOptions render;
    render.width = 24;
    render.height = 16;
    render.samples = 1;
    const vxf::RenderedImage image = vxf::render(set, medium, view, render);

    Bounds b;
    for (const char* name : {"direct", "scatter"}) {
        for (auto it = set.get<openvdb::Vec3SGrid>(name)->cbeginValueOn(); it; ++it) {
            for (int c = 0; c < 3; ++c) {
                const double v = (*it)[c];
                b.finite = b.finite && std::isfinite(v) && v >= 0.0;
                double& peak = std::string(name) == "direct" ? b.maxDirect : b.maxScatter;
                peak = std::max(peak, v);
            }
        }
    }
    for (const auto& p : image.combined) {
        for (int c = 0; c < 3; ++c) {
            b.finite = b.finite && std::isfinite(p[c]) && p[c] >= 0.0f;
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
            CHECK(b.maxDirect <= 4.0 + 1e-6);
            CHECK(b.maxScatter <= 4.0 + 1e-6);
        }
    }
    SECTION("albedo 0.9999")
    {
        const Bounds b = runChain(sphere, vxf::test::albedoMaterial(10.0, 0.9999), 24);
        CHECK(b.finite);
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
        const Bounds b = runChain(vxf::makeBox(openvdb::Vec3d(-1, -1, -0.02), openvdb::Vec3d(1, 1, 0.02)), vxf::test::albedoMaterial(20.0, 0.9), 48);
        CHECK(b.finite);
        CHECK(b.maxDirect <= 4.0 + 1e-6);
    }
}
