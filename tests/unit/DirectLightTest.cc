#include <vxf/light/DirectLight.h>
#include <vxf/transport/AdaptiveBand.h>
#include <vxf/core/ProceduralMesh.h>
#include <vxf/core/RayScene.h>
#include <vxf/io/ImageFile.h>
#include <vxf/voxelize/Voxelize.h>

#include <functional>

#include "TestSupport.h"

#include <catch2/catch.hpp>
#include <tbb/global_control.h>

namespace {

/// A box of density 1 (voxels in @a box), voxel size dx, all leaf voxels (no tiles).
vxf::VoxelSet boxMedium(const openvdb::CoordBBox& box, double dx, bool tiles = false)
{
    vxf::VoxelSet set(openvdb::math::Transform::createLinearTransform(dx));
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->setTransform(set.transformPtr());
    density->tree().fill(box, 1.0f, true);
    if (!tiles) density->tree().voxelizeActiveTiles();
    set.put(density);
    return set;
}

vxf::Light pointLight(const openvdb::Vec3d& p, double intensity)
{
    vxf::Light l;
    l.type = vxf::Light::Type::Point;
    l.name = "point";
    l.position = p;
    l.intensity = intensity;
    return l;
}

} // namespace

TEST_CASE("point light: I/r^2 in a thin medium", "[light][direct]")
{
    const vxf::VoxelSet set = boxMedium(openvdb::CoordBBox(openvdb::Coord(-20), openvdb::Coord(20)), 0.1);
    const vxf::Medium medium(set, vxf::test::greyMaterial(5e-7, 5e-7));
    vxf::Medium::Sampler sampler(medium);
    const vxf::Light light = pointLight(openvdb::Vec3d(0.0), 3.0);
    for (const openvdb::Coord c : {openvdb::Coord(10, 0, 0), openvdb::Coord(3, -4, 12), openvdb::Coord(-20, 20, 1)}) {
        const double r = c.asVec3d().length() * 0.1;
        const openvdb::Vec3d phi = vxf::lightFluence(vxf::LightSampler(light), sampler, medium, c, {});
        CHECK(phi.x() == Approx(3.0 / (r * r)).epsilon(1e-4));
    }
    // At the light's own position: finite (r is taken as half a voxel).
    const openvdb::Vec3d atLight = vxf::lightFluence(vxf::LightSampler(light), sampler, medium, openvdb::Coord(0), {});
    CHECK(std::isfinite(atLight.x()));
    CHECK(atLight.x() == Approx(3.0 / (0.05 * 0.05)).epsilon(1e-4));
}

TEST_CASE("directional light: E exp(-sigma_t depth)", "[light][direct]")
{
    const double dx = 0.05;
    const vxf::VoxelSet set = boxMedium(openvdb::CoordBBox(openvdb::Coord(0, -30, -30), openvdb::Coord(39, 30, 30)), dx);
    const vxf::Medium medium(set, vxf::test::greyMaterial(0.5, 1.5));
    vxf::Medium::Sampler sampler(medium);
    vxf::Light sun;
    sun.type = vxf::Light::Type::Directional;
    sun.direction = openvdb::Vec3d(1, 0, 0); // shining toward +x: enters at x = 0
    sun.color = openvdb::Vec3d(1.0, 0.5, 0.25);
    sun.intensity = 2.0;
    for (int i : {0, 5, 17}) {
        // Optical depth from voxel centre i back to the face: i voxels + the half-voxel ramp.
        const double expected = 2.0 * std::exp(-2.0 * dx * (i + 0.5));
        const openvdb::Vec3d phi = vxf::lightFluence(vxf::LightSampler(sun), sampler, medium, openvdb::Coord(i, 0, 0), {});
        CHECK(phi.x() == Approx(expected).margin(1e-4));
        CHECK(phi.z() == Approx(0.25 * expected).margin(1e-4));
    }
}

TEST_CASE("a rim voxel is lit where its medium is, not at its centre outside the surface", "[light][direct]")
{
    // A sphere of radius 1 (voxels 0.1, mean free path 0.2) under a sun shining toward +x. A
    // voxel whose centre lies outside the surface holds medium only inside it; on the shadowed
    // side its centre sees the sun pass by the limb, and that unattenuated light went into
    // the passes' source (the shadowed side of a thick sphere came out 12% too bright).
    vxf::VoxelizeOptions options;
    options.voxelSize = 0.1;
    const vxf::VoxelSet set = vxf::voxelize(vxf::makeSphere(openvdb::Vec3d(0.0), 1.0, 128, 256), options);
    const vxf::Medium medium(set, vxf::test::greyMaterial(1.0, 4.0));
    vxf::Medium::Sampler sampler(medium);
    vxf::Light sun;
    sun.type = vxf::Light::Type::Directional;
    sun.direction = openvdb::Vec3d(1, 0, 0);
    sun.intensity = 1.0;
    const vxf::LightSampler light(sun);
    int shadowed = 0, passedByLimb = 0;
    for (auto it = medium.density().cbeginValueOn(); it; ++it) {
        const openvdb::Coord c = it.getCoord();
        const openvdb::Vec3d centre = set.transform().indexToWorld(c);
        const double outside = centre.length() - 1.0;
        if (outside <= 0.0 || outside >= 0.05) continue; // the rim: centres outside, within half a voxel
        const openvdb::Vec3d at = set.transform().indexToWorld(sampler.mediumPoint(c));
        INFO("voxel " << c << " at " << centre << ", lit at " << at);
        CHECK(at.length() == Approx(1.0).margin(0.01)); // on the surface
        if (at.x() < 0.1) continue;
        // From the surface point the sun's path crosses a chord of 2x (optical depth 10x ≥ 1);
        // a factor 2 allows for the voxelized sphere's chord near grazing.
        ++shadowed;
        if (centre.y() * centre.y() + centre.z() * centre.z() > 1.0) ++passedByLimb;
        CHECK(vxf::lightFluence(light, sampler, medium, c, {}).x() < 2.0 * std::exp(-5.0 * 2.0 * at.x()));
    }
    CHECK(shadowed > 100);
    CHECK(passedByLimb > 20); // voxels whose centre the sun passes by the limb to reach, unattenuated
}

TEST_CASE("environment light: 4 pi L with no extinction", "[light][direct]")
{
    const vxf::VoxelSet set = boxMedium(openvdb::CoordBBox(openvdb::Coord(-5), openvdb::Coord(5)), 0.1);
    const vxf::Medium medium(set, vxf::test::greyMaterial(0.0, 0.0));
    vxf::Medium::Sampler sampler(medium);
    vxf::Light sky;
    sky.type = vxf::Light::Type::Environment;
    sky.color = openvdb::Vec3d(0.5);
    sky.samples = 32;
    CHECK(vxf::lightFluence(vxf::LightSampler(sky), sampler, medium, openvdb::Coord(1, 2, 3), {}).x() == Approx(4.0 * M_PI * 0.5));
    sky.file = "no-such-sky.exr";
    CHECK_THROWS_AS(vxf::LightSampler(sky), vxf::InputError);
}

namespace {

/// Write a lat-long map whose pixels are f(u, v) (grey) as OpenEXR.
void writeMap(const std::string& path, int width, int height, const std::function<float(double, double)>& f)
{
    vxf::RenderedImage map;
    map.width = width;
    map.height = height;
    const std::size_t n = std::size_t(width) * std::size_t(height);
    map.combined.resize(n);
    map.surface = map.direct = map.scatter = map.normal = std::vector<openvdb::Vec3f>(n, openvdb::Vec3f(0.0f));
    map.alpha = map.depth = std::vector<float>(n, 1.0f);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) map.combined[std::size_t(y * width + x)] = openvdb::Vec3f(f((x + 0.5) / width, (y + 0.5) / height));
    vxf::writeExr(path, map);
}

} // namespace

TEST_CASE("environment maps: lat-long convention, energy kept for any direction count, bad pixels refused", "[light][direct]")
{
    // Blender's convention, +Z up.
    CHECK((vxf::latLongDirection(0.5, 0.5) - openvdb::Vec3d(1, 0, 0)).length() < 1e-12);
    CHECK((vxf::latLongDirection(0.75, 0.5) - openvdb::Vec3d(0, -1, 0)).length() < 1e-12);
    CHECK((vxf::latLongDirection(0.3, 0.0) - openvdb::Vec3d(0, 0, 1)).length() < 1e-12);

    vxf::test::TempDir dir;
    const std::string sky = dir.path("sky.exr");
    writeMap(sky, 128, 64, [](double, double v) { return v < 0.5 ? 2.0f : 0.0f; }); // upper hemisphere L = 2
    const vxf::VoxelSet set = boxMedium(openvdb::CoordBBox(openvdb::Coord(-5), openvdb::Coord(5)), 0.1);
    const vxf::Medium medium(set, vxf::test::greyMaterial(0.0, 0.0));
    vxf::Medium::Sampler sampler(medium);
    vxf::Light light;
    light.type = vxf::Light::Type::Environment;
    light.file = sky;
    for (int samples : {7, 64, 300}) {
        light.samples = samples;
        INFO(samples << " directions");
        // φ = ∫ L dω = 2π·2 with no extinction, however the texels are binned.
        CHECK(vxf::lightFluence(vxf::LightSampler(light), sampler, medium, openvdb::Coord(1, 2, 3), {}).x() ==
            Approx(4.0 * M_PI).epsilon(1e-3));
    }
    // A thick medium below... lit from above only: the top face sees more than the bottom face.
    const vxf::Medium thick(set, vxf::test::greyMaterial(5.0, 0.0));
    vxf::Medium::Sampler thickSampler(thick);
    light.samples = 64;
    const vxf::LightSampler sampled(light);
    CHECK(vxf::lightFluence(sampled, thickSampler, thick, openvdb::Coord(0, 0, 5), {}).x() >
        5.0 * vxf::lightFluence(sampled, thickSampler, thick, openvdb::Coord(0, 0, -5), {}).x());

    const std::string bad = dir.path("bad.exr");
    writeMap(bad, 8, 4, [](double u, double v) { return u > 0.5 && v > 0.5 ? std::nanf("") : 1.0f; });
    light.file = bad;
    CHECK_THROWS_WITH(vxf::LightSampler(light), Catch::Contains("bad.exr") && Catch::Contains("pixel (4, 2)"));
}

TEST_CASE("spot and area lights agree with their point-light limits", "[light][direct]")
{
    const vxf::VoxelSet set = boxMedium(openvdb::CoordBBox(openvdb::Coord(-20), openvdb::Coord(20)), 0.1);
    const vxf::Medium medium(set, vxf::test::greyMaterial(0.2, 0.3));
    vxf::Medium::Sampler sampler(medium);
    const vxf::Light point = pointLight(openvdb::Vec3d(0, 0, 3), 2.0);
    vxf::Light spot = point;
    spot.type = vxf::Light::Type::Spot;
    spot.direction = openvdb::Vec3d(0, 0, -1);
    spot.coneAngleDegrees = 60.0;
    spot.coneSoftnessDegrees = 10.0;
    const openvdb::Coord below(0, 0, 10), edge(16, 0, 0), outside(20, 0, 18);
    CHECK(vxf::lightFluence(vxf::LightSampler(spot), sampler, medium, below, {}).x() ==
        Approx(vxf::lightFluence(vxf::LightSampler(point), sampler, medium, below, {}).x()));
    const double soft = vxf::lightFluence(vxf::LightSampler(spot), sampler, medium, edge, {}).x(); // ~28 degrees off axis: in the soft edge
    CHECK(soft > 0.0);
    CHECK(soft < vxf::lightFluence(vxf::LightSampler(point), sampler, medium, edge, {}).x());
    CHECK(vxf::lightFluence(vxf::LightSampler(spot), sampler, medium, outside, {}).x() == 0.0);

    // A small square facing the voxel, far away, acts as a point of intensity L A.
    vxf::Light area;
    area.type = vxf::Light::Type::Area;
    area.shape = vxf::Light::Shape::Rectangle;
    area.position = openvdb::Vec3d(0, 0, 3);
    area.direction = openvdb::Vec3d(0, 0, -1);
    area.width = area.height = 0.02;
    area.intensity = 2.0 / (0.02 * 0.02);
    area.samples = 16;
    CHECK(vxf::lightFluence(vxf::LightSampler(area), sampler, medium, below, {}).x() ==
        Approx(vxf::lightFluence(vxf::LightSampler(point), sampler, medium, below, {}).x()).epsilon(1e-3));
    // One-sided: nothing behind it.
    area.direction = openvdb::Vec3d(0, 0, 1);
    CHECK(vxf::lightFluence(vxf::LightSampler(area), sampler, medium, below, {}).x() == 0.0);
}

TEST_CASE("the light stage writes direct and scatter_source on the medium's topology", "[light][direct]")
{
    vxf::VoxelSet set = boxMedium(openvdb::CoordBBox(openvdb::Coord(-64), openvdb::Coord(63)), 0.02, /*tiles=*/true);
    const vxf::Material m = vxf::test::greyMaterial(0.5, 2.0);
    const vxf::Medium medium(set, m);
    vxf::Light dark = pointLight(openvdb::Vec3d(0.0), 0.0);
    dark.name = "off";
    const std::vector<vxf::Light> lights = {pointLight(openvdb::Vec3d(0, 0, 2), 1.0), dark};
    vxf::DirectLightOptions coarse;
    coarse.coarseTiles = true;
    const auto report = vxf::computeDirectLight(set, medium, lights, coarse);
    REQUIRE(report.lights.size() == 2);
    CHECK_FALSE(report.lights[0].skipped);
    CHECK(report.lights[0].fluenceSum.x() > 0.0);
    CHECK(report.lights[1].skipped);
    CHECK(report.lights[1].why == "zero colour or intensity");

    auto direct = set.get<openvdb::Vec3SGrid>("direct");
    auto source = set.get<openvdb::Vec3SGrid>("scatter_source");
    const auto density = set.get<openvdb::FloatGrid>("density");
    CHECK(direct->activeVoxelCount() > density->activeVoxelCount()); // one voxel beyond the medium
    CHECK(direct->tree().activeTileCount() > 0); // with coarseTiles the deep interior stays tiles
    {
        vxf::VoxelSet fine = boxMedium(openvdb::CoordBBox(openvdb::Coord(-64), openvdb::Coord(63)), 0.02, true);
        vxf::computeDirectLight(fine, vxf::Medium(fine, m), {lights[0]});
        CHECK(fine.find("direct")->baseTree().activeTileCount() == 0); // full resolution by default
        CHECK(fine.find("direct")->activeVoxelCount() == 130ull * 130 * 130); // 128^3 + one voxel around
    }
    // J0 = sigma_s phi / 4 pi at a leaf voxel.
    const openvdb::Coord c(0, 0, 60);
    CHECK(source->tree().getValue(c).x() == Approx(2.0 * direct->tree().getValue(c).x() / (4.0 * M_PI)).epsilon(1e-6));
    bool finite = true;
    for (auto it = direct->cbeginValueOn(); it; ++it) finite = finite && std::isfinite((*it)[0]) && (*it)[0] >= 0.0f;
    CHECK(finite);

    // Identical with 1 and 2 threads.
    vxf::VoxelSet one = boxMedium(openvdb::CoordBBox(openvdb::Coord(-64), openvdb::Coord(63)), 0.02, true);
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        vxf::computeDirectLight(one, vxf::Medium(one, m), lights, coarse);
    }
    std::string why;
    CHECK(vxf::test::identicalGrids(*one.find("direct"), *direct, &why));
    INFO(why);
    CHECK(vxf::test::identicalGrids(*one.find("scatter_source"), *source, &why));
}

TEST_CASE("with a band the light stage writes the deep leaves as tiles of their means", "[light][direct][band]")
{
    // A cube of 64³ voxels (dx 0.02), a point light above it; a band of 10 voxels (0.2): the
    // leaves whose voxels all lie 10 deep (L∞: voxels [-22, 21] per axis) are [-16, 15]³, 64.
    const openvdb::CoordBBox box(openvdb::Coord(-32), openvdb::Coord(31));
    const vxf::Material m = vxf::test::greyMaterial(0.5, 2.0);
    const std::vector<vxf::Light> lights = {pointLight(openvdb::Vec3d(0, 0, 2), 1.0)};
    vxf::VoxelSet full = boxMedium(box, 0.02), banded = boxMedium(box, 0.02);
    const auto fullReport = vxf::computeDirectLight(full, vxf::Medium(full, m), lights);
    vxf::DirectLightOptions options;
    options.band = 0.2;
    const auto bandReport = vxf::computeDirectLight(banded, vxf::Medium(banded, m), lights, options);
    CHECK(bandReport.lights[0].fluenceSum.x() == Approx(fullReport.lights[0].fluenceSum.x()).epsilon(1e-12)); // lit per voxel alike

    for (const char* name : {"direct", "scatter_source"}) {
        INFO(name);
        const auto fine = full.get<openvdb::Vec3SGrid>(name);
        const auto coarse = banded.get<openvdb::Vec3SGrid>(name);
        CHECK(coarse->tree().activeTileCount() == 64);
        CHECK(coarse->activeVoxelCount() == fine->activeVoxelCount());
        // A deep leaf: one tile, its voxels' mean (the scatter stage's band makes the same).
        const openvdb::Coord deepLeaf(0, 0, 0), nearSurface(0, 0, 24);
        CHECK(coarse->tree().probeConstLeaf(deepLeaf) == nullptr);
        const auto* leaf = fine->tree().probeConstLeaf(deepLeaf);
        REQUIRE(leaf != nullptr);
        openvdb::Vec3d sum(0.0);
        for (auto v = leaf->cbeginValueOn(); v; ++v) sum += openvdb::Vec3d(*v);
        CHECK(coarse->tree().getValue(openvdb::Coord(3, 5, 7)) == openvdb::Vec3f(sum / 512.0));
        CHECK(fine->tree().getValue(openvdb::Coord(0, 0, 7)) > fine->tree().getValue(deepLeaf)); // (the light falls across it)
        // The band's voxels as at full resolution.
        CHECK(coarse->tree().getValue(nearSurface) == fine->tree().getValue(nearSurface));
        CHECK(coarse->tree().probeConstLeaf(nearSurface) != nullptr);
        // What the scatter stage's band makes of full resolution, the light stage made already.
        vxf::AdaptiveBandReport made;
        const auto rebanded = vxf::coarsenedBeyondBand(*fine, *full.get<openvdb::FloatGrid>("density"), 0.2, made);
        std::string why;
        const bool same = vxf::test::identicalGrids(*rebanded, *coarse, &why);
        INFO(why);
        CHECK(same);
    }
}

TEST_CASE("occluder meshes cast shadows in the light stage", "[light][direct][rayscene]")
{
    const vxf::VoxelSet set = boxMedium(openvdb::CoordBBox(openvdb::Coord(-20), openvdb::Coord(20)), 0.1);
    const vxf::Medium medium(set, vxf::test::greyMaterial(0.0, 0.0)); // clear: only the occluder attenuates
    vxf::Medium::Sampler sampler(medium);
    vxf::RayScene occluders;
    occluders.add(vxf::makeBox(openvdb::Vec3d(-0.5, -0.5, 2.9), openvdb::Vec3d(0.5, 0.5, 3.1)), 0);
    occluders.commit();
    const vxf::LightSampler light(pointLight(openvdb::Vec3d(0, 0, 5), 10.0));
    // Under the occluder: nothing arrives.
    CHECK(vxf::lightFluence(light, sampler, medium, openvdb::Coord(0), {}, &occluders).x() == 0.0);
    // Beside its shadow (the line to the light passes x = 0.6 at z = 3): I/r².
    const double r2 = 1.5 * 1.5 + 25.0;
    CHECK(vxf::lightFluence(light, sampler, medium, openvdb::Coord(15, 0, 0), {}, &occluders).x() == Approx(10.0 / r2));
    // Without occluders the centre is lit.
    CHECK(vxf::lightFluence(light, sampler, medium, openvdb::Coord(0), {}).x() == Approx(10.0 / 25.0));
}

namespace {

/// `direct` of @a set lit by @a lights, swept (the default) or every light marched.
openvdb::Vec3SGrid::Ptr litDirect(const vxf::VoxelSet& medium, const vxf::Material& material, const std::vector<vxf::Light>& lights,
    bool sweep, const vxf::RayScene* boundary = nullptr)
{
    vxf::VoxelSet set = medium;
    vxf::DirectLightOptions options;
    options.sweep = sweep;
    options.boundary = boundary;
    vxf::computeDirectLight(set, vxf::Medium(set, material), lights, options);
    return set.get<openvdb::Vec3SGrid>("direct");
}

} // namespace

TEST_CASE("a directional light by sweeps: E exp(-sigma_t depth / cos) in a slab, exact along the front", "[light][direct][sweep]")
{
    // No surface: the box's density ends with a half-voxel ramp, which the sweep's first step
    // (σt from 0 outside to σt inside) integrates as the march does. Optical depth is linear in
    // x along any front, so the sweep's blend of upwind depths is exact here.
    const double dx = 0.05, sigmaT = 2.0;
    const vxf::VoxelSet set = boxMedium(openvdb::CoordBBox(openvdb::Coord(0, -40, -40), openvdb::Coord(29, 40, 40)), dx);
    vxf::Light sun;
    sun.type = vxf::Light::Type::Directional;
    sun.direction = openvdb::Vec3d(1.0, 0.5, -0.3).unit(); // enters at x = 0, obliquely
    sun.intensity = 2.0;
    const auto direct = litDirect(set, vxf::test::greyMaterial(0.5, 1.5), {sun}, true);
    for (int i : {0, 3, 11, 29}) {
        const double expected = 2.0 * std::exp(-sigmaT * dx * (i + 0.5) / sun.direction.x());
        INFO("voxel x = " << i);
        CHECK(direct->tree().getValue(openvdb::Coord(i, 0, 0)).x() == Approx(expected).epsilon(1e-4));
    }
}

TEST_CASE("an anisotropic phase: the source's mean direction is the light's direction of travel", "[light][direct][phase]")
{
    // The delta-M transport keeps J0's mean direction (Phase.h): one sun, swept or
    // marched, gives a = its direction of travel at every lit voxel; a point light, the direction
    // away from it. An isotropic medium writes no such grid (and drops a stale one).
    const double dx = 0.05;
    vxf::VoxelSet set = boxMedium(openvdb::CoordBBox(openvdb::Coord(0, -20, -20), openvdb::Coord(19, 20, 20)), dx);
    vxf::Material m = vxf::test::greyMaterial(0.5, 1.5);
    m.phaseG = 0.6;
    vxf::Light sun;
    sun.type = vxf::Light::Type::Directional;
    sun.direction = openvdb::Vec3d(1.0, 0.5, -0.3).unit();
    for (const bool sweep : {true, false}) {
        vxf::DirectLightOptions options;
        options.sweep = sweep;
        vxf::computeDirectLight(set, vxf::Medium(set, m), {sun}, options);
        const auto a = set.get<openvdb::Vec3SGrid>("scatter_source_anisotropy");
        INFO("swept " << sweep);
        for (const openvdb::Coord c : {openvdb::Coord(0, 0, 0), openvdb::Coord(10, -5, 7), openvdb::Coord(19, 3, -2)}) {
            CHECK((openvdb::Vec3d(a->tree().getValue(c)) - sun.direction).length() < 1e-5);
        }
    }
    vxf::computeDirectLight(set, vxf::Medium(set, m), {pointLight(openvdb::Vec3d(-1.0, 0.0, 0.0), 1.0)});
    const openvdb::Coord c(10, 5, 0);
    const openvdb::Vec3d away = (c.asVec3d() * dx - openvdb::Vec3d(-1.0, 0.0, 0.0)).unit();
    CHECK((openvdb::Vec3d(set.get<openvdb::Vec3SGrid>("scatter_source_anisotropy")->tree().getValue(c)) - away).length() < 1e-4);
    vxf::computeDirectLight(set, vxf::Medium(set, vxf::test::greyMaterial(0.5, 1.5)), {sun});
    CHECK_FALSE(set.find("scatter_source_anisotropy"));
}

TEST_CASE("a directional light by sweeps: shadows cast across vacuum wider than a leaf", "[light][direct][sweep]")
{
    // Two slabs 24 voxels apart: no leaf of the lattice lies between them, so the sweep alone
    // would light the far slab as if the near one were not there (the bunny's head over its
    // chest). The depth entering from outside the lattice is marched instead.
    const double dx = 0.05, sigmaT = 2.0;
    vxf::VoxelSet set = boxMedium(openvdb::CoordBBox(openvdb::Coord(0, -20, -20), openvdb::Coord(7, 20, 20)), dx);
    set.get<openvdb::FloatGrid>("density")->tree().fill(
        openvdb::CoordBBox(openvdb::Coord(32, -20, -20), openvdb::Coord(47, 20, 20)), 1.0f, true);
    set.get<openvdb::FloatGrid>("density")->tree().voxelizeActiveTiles();
    vxf::Light sun;
    sun.type = vxf::Light::Type::Directional;
    sun.direction = openvdb::Vec3d(1.0, 0.0, 0.0); // through the near slab, then the far one
    sun.intensity = 2.0;
    const vxf::Material material = vxf::test::greyMaterial(0.5, 1.5);
    const auto swept = litDirect(set, material, {sun}, true), marched = litDirect(set, material, {sun}, false);
    for (int i : {32, 35, 47}) {
        INFO("voxel x = " << i);
        // 8 voxels of the near slab, then i − 32 + ½ of the far one.
        const double expected = 2.0 * std::exp(-sigmaT * dx * (8.0 + (i - 32) + 0.5));
        CHECK(swept->tree().getValue(openvdb::Coord(i, 0, 0)).x() == Approx(expected).epsilon(1e-3));
        CHECK(marched->tree().getValue(openvdb::Coord(i, 0, 0)).x() == Approx(expected).epsilon(1e-3));
    }
    // A point light on the axis, 200 voxels before the near slab: the far slab's light crossed
    // the gap (marched through the lattice's leaves only, the vacuum between skipped) and the
    // near slab, I/r² dimmed by the same depths.
    const vxf::Light point = pointLight(openvdb::Vec3d(-10.0, 0.0, 0.0), 3.0);
    const auto pointSwept = litDirect(set, material, {point}, true), pointMarched = litDirect(set, material, {point}, false);
    for (int i : {32, 35, 47}) {
        INFO("voxel x = " << i << ", point light");
        const double r = 10.0 + i * dx;
        const double expected = 3.0 / (r * r) * std::exp(-sigmaT * dx * (8.0 + (i - 32) + 0.5));
        CHECK(pointSwept->tree().getValue(openvdb::Coord(i, 0, 0)).x() == Approx(expected).epsilon(1e-3));
        CHECK(pointMarched->tree().getValue(openvdb::Coord(i, 0, 0)).x() == Approx(expected).epsilon(1e-3));
    }
}

TEST_CASE("directional and environment lights by sweeps match the march through a sphere's surface", "[light][direct][sweep]")
{
    // A sphere of radius 1 at 20 voxels per unit, mean free path 0.065 (0.77 voxels per mean
    // free path, the accuracy bench's thick bunny at dim 64): light enters through a curved
    // surface. Blending upwind optical depths across the surface's kink (0 outside, rising inside)
    // left the voxels a voxel beneath the surface 7% darker than the march (5.6% with the sun
    // continued only where it enters at cosines above 0.85; 16% on the bunny at dim 64).
    vxf::VoxelizeOptions options;
    options.voxelSize = 0.05;
    const vxf::VoxelSet set = vxf::voxelize(vxf::makeSphere(openvdb::Vec3d(0.0), 1.0, 128, 256), options);
    const vxf::Material material = vxf::test::greyMaterial(1.5, 13.9);
    vxf::Light sun;
    sun.type = vxf::Light::Type::Directional;
    sun.name = "sun";
    sun.direction = openvdb::Vec3d(0.3, -0.5, -0.8).unit();
    vxf::Light sky;
    sky.type = vxf::Light::Type::Environment;
    sky.name = "sky";
    sky.samples = 16;
    sky.color = openvdb::Vec3d(0.2, 0.3, 0.4);
    for (const vxf::Light& light : {sun, sky}) {
        INFO(light.name);
        const auto swept = litDirect(set, material, {light}, true), marched = litDirect(set, material, {light}, false);
        const vxf::Medium medium(set, material);
        vxf::Medium::Sampler sampler(medium);
        // By depth below the surface: the skin (within half a voxel), the next voxel, deeper.
        double sums[3][2] = {};
        bool finite = true;
        for (auto it = marched->cbeginValueOn(); it; ++it) {
            const openvdb::Vec3f s = swept->tree().getValue(it.getCoord());
            finite = finite && std::isfinite(s[0]) && s[0] >= 0.0f;
            const double depth = -sampler.signedDistance(it.getCoord().asVec3d());
            if (depth < -0.5) continue;
            const int band = depth < 0.5 ? 0 : depth < 1.5 ? 1 : 2;
            sums[band][0] += s[0];
            sums[band][1] += (*it)[0];
        }
        CHECK(finite);
        CHECK(sums[0][0] / sums[0][1] == Approx(1.0).margin(0.04));
        CHECK(sums[1][0] / sums[1][1] == Approx(1.0).margin(0.02));
        // Deeper the sweep reads 3-4% bright: the depth under a convex entry is concave across
        // the light (σt times a chord), which blending upwind depths understates (~dx²·curvature).
        CHECK(sums[2][0] / sums[2][1] == Approx(1.0).margin(0.05));
    }
    // The sweeps' order is fixed: identical grids with 1 and 2 threads.
    const auto two = litDirect(set, material, {sun, sky}, true);
    openvdb::Vec3SGrid::Ptr one;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        one = litDirect(set, material, {sun, sky}, true);
    }
    std::string why;
    CHECK(vxf::test::identicalGrids(*one, *two, &why));
    INFO(why);
}

TEST_CASE(
    "with the medium's meshes, light crossing vacuum brings the depth the sweep holds where it left the medium", "[light][direct][sweep]")
{
    // Two spheres (radius 10 voxels) 30 voxels apart along the sun: the far one lies in the
    // near one's shadow, beyond a gap no leaf spans. With the meshes at hand the depth entering
    // the far sphere's leaves is read from the sweep a voxel or more behind the near sphere
    // (where the mesh ray meets it), and the rim's grazing marches hand over to the sweep two
    // voxels from the surface: both against every light marched, and the same with any thread count.
    const double dx = 0.05;
    vxf::TriangleMesh mesh = vxf::makeSphere(openvdb::Vec3d(0.0), 0.5, 48, 96);
    const vxf::TriangleMesh far = vxf::makeSphere(openvdb::Vec3d(2.0, 0.1, 0.0), 0.5, 48, 96);
    const unsigned base = unsigned(mesh.points.size());
    mesh.points.insert(mesh.points.end(), far.points.begin(), far.points.end());
    for (const auto& t : far.triangles) mesh.triangles.emplace_back(t[0] + base, t[1] + base, t[2] + base);
    vxf::VoxelizeOptions options;
    options.voxelSize = dx;
    const vxf::VoxelSet set = vxf::voxelize(mesh, options);
    vxf::RayScene boundary;
    boundary.add(mesh, 0);
    boundary.commit();
    const vxf::Material material = vxf::test::greyMaterial(1.0, 4.0); // a mean free path of 4 voxels
    vxf::Light sun;
    sun.type = vxf::Light::Type::Directional;
    sun.name = "sun";
    sun.direction = openvdb::Vec3d(1.0, 0.05, 0.1).unit(); // from the near sphere to the far one
    vxf::Light sky;
    sky.type = vxf::Light::Type::Environment;
    sky.name = "sky";
    sky.samples = 16;
    for (const vxf::Light& light : {sun, sky}) {
        INFO(light.name);
        const auto swept = litDirect(set, material, {light}, true, &boundary);
        const auto marched = litDirect(set, material, {light}, false, &boundary);
        // The far sphere (x > 1 world unit): shadowed where the sun's rays crossed the near one.
        double sum[2] = {}, shadowed[2] = {};
        for (auto it = marched->cbeginValueOn(); it; ++it) {
            if (it.getCoord().x() * dx < 1.0) continue;
            const double s = swept->tree().getValue(it.getCoord()).x(), m = (*it).x();
            REQUIRE(std::isfinite(s));
            sum[0] += s;
            sum[1] += m;
            if (light.type == vxf::Light::Type::Directional && m < 0.5 * light.intensity * std::exp(-1.0)) {
                shadowed[0] += s;
                shadowed[1] += m;
            }
        }
        // The sweep's own blend of upwind depths leaves the far sphere 5-7% dark under the sun
        // (as in the sphere above), and brightens its shadowed part by 18% (6% with every
        // entering depth marched): the shadow's edge, smeared by the sweep behind the near
        // sphere, is carried across the gap. Lost, the shadow would be e^5 = 150x too bright.
        CHECK(sum[0] / sum[1] == Approx(1.0).margin(0.08));
        if (light.type == vxf::Light::Type::Directional) {
            REQUIRE(shadowed[1] > 0.0);
            CHECK(shadowed[0] / shadowed[1] == Approx(1.0).margin(0.25));
        }
    }
    const auto two = litDirect(set, material, {sun, sky}, true, &boundary);
    openvdb::Vec3SGrid::Ptr one;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        one = litDirect(set, material, {sun, sky}, true, &boundary);
    }
    std::string why;
    CHECK(vxf::test::identicalGrids(*one, *two, &why));
    INFO(why);
}

TEST_CASE("a point light by a sweep around it: I exp(-sigma_t r) / r^2 in a box, every octant", "[light][direct][sweep]")
{
    // No surface: every voxel the sweep can blend is swept (from the light outward, octant by
    // octant), the voxels next to the light and to its three planes marched. Optical depth
    // grows linearly along each ray, which the blend of upwind depths holds to second order.
    const double dx = 0.05, sigmaT = 2.0;
    const vxf::VoxelSet set = boxMedium(openvdb::CoordBBox(openvdb::Coord(-24), openvdb::Coord(24)), dx);
    const vxf::Material material = vxf::test::greyMaterial(0.5, 1.5);
    const openvdb::Vec3d lightIjk(3.3, -2.6, 0.4);
    const vxf::Light light = pointLight(lightIjk * dx, 1.0);
    const auto swept = litDirect(set, material, {light}, true), marched = litDirect(set, material, {light}, false);
    double worst = 0.0, worstMarched = 0.0;
    for (const openvdb::Coord c : {openvdb::Coord(20, 0, 0), openvdb::Coord(-20, 5, 3), openvdb::Coord(10, -20, -15),
             openvdb::Coord(-15, 18, 20), openvdb::Coord(4, 9, -22), openvdb::Coord(-21, -21, -21), openvdb::Coord(3, -2, 0)}) {
        const double r = (c.asVec3d() - lightIjk).length() * dx;
        const double expected = std::exp(-sigmaT * r) / (r * r);
        INFO("voxel " << c);
        worst = std::max(worst, std::abs(swept->tree().getValue(c)[0] / expected - 1.0));
        worstMarched = std::max(worstMarched, std::abs(marched->tree().getValue(c)[0] / expected - 1.0));
    }
    CHECK(worstMarched < 1e-3);
    CHECK(worst < 5e-3);
    // Thread count independent.
    openvdb::Vec3SGrid::Ptr one;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        one = litDirect(set, material, {light}, true);
    }
    std::string why;
    CHECK(vxf::test::identicalGrids(*one, *swept, &why));
    INFO(why);
}

TEST_CASE("a point light by a sweep around it: the chord through a sphere, its surface band marched", "[light][direct][sweep]")
{
    // A sphere of radius 1 at 20 voxels per unit, 0.77 voxels per mean free path (the accuracy
    // bench's thick bunny at dim 64), a point light 0.9 outside it: the voxels within
    // kPointMarchedBand of the surface are marched, the deeper ones blended from them. Against
    // the closed form, σt times the chord of the segment to the light inside the sphere.
    vxf::VoxelizeOptions options;
    options.voxelSize = 0.05;
    const vxf::VoxelSet set = vxf::voxelize(vxf::makeSphere(openvdb::Vec3d(0.0), 1.0, 128, 256), options);
    const double sigmaT = 15.4;
    const vxf::Material material = vxf::test::greyMaterial(1.5, 13.9);
    const openvdb::Vec3d lightWorld = openvdb::Vec3d(1.1, -0.9, 1.0);
    const vxf::Light light = pointLight(lightWorld, 2.0);
    const auto swept = litDirect(set, material, {light}, true), marched = litDirect(set, material, {light}, false);
    const vxf::Medium medium(set, material);
    vxf::Medium::Sampler sampler(medium);
    const auto chord = [&](const openvdb::Vec3d& x) { // length of [x, light] inside the unit sphere
        const openvdb::Vec3d d = lightWorld - x;
        const double a = d.dot(d), b = 2.0 * x.dot(d), c = x.dot(x) - 1.0, disc = b * b - 4.0 * a * c;
        if (disc <= 0.0) return 0.0;
        const double t0 = std::max(0.0, (-b - std::sqrt(disc)) / (2.0 * a)), t1 = std::min(1.0, (-b + std::sqrt(disc)) / (2.0 * a));
        return t1 > t0 ? (t1 - t0) * std::sqrt(a) : 0.0;
    };
    // By depth below the surface: within the marched band, and deeper (swept), where the light
    // has not yet fallen below the march's cutoff.
    double sums[2][3] = {};
    bool finite = true;
    for (auto it = marched->cbeginValueOn(); it; ++it) {
        const openvdb::Vec3d x = set.transform().indexToWorld(it.getCoord());
        const double depth = -sampler.signedDistance(it.getCoord().asVec3d());
        const openvdb::Vec3f s = swept->tree().getValue(it.getCoord());
        finite = finite && std::isfinite(s[0]) && s[0] >= 0.0f;
        if (depth < 0.5) continue; // the rim and skin: lit on the surface
        const double r2 = (lightWorld - x).lengthSqr();
        const double expected = 2.0 * std::exp(-sigmaT * chord(x)) / r2;
        if (expected < 1e-3 * 2.0 / r2) continue;
        const int band = depth < 3.0 ? 0 : 1;
        sums[band][0] += s[0];
        sums[band][1] += (*it)[0];
        sums[band][2] += expected;
    }
    CHECK(finite);
    CHECK(sums[0][1] > 0.0);
    CHECK(sums[1][1] > 0.0);
    // The band is the march's, to the sweep's depth read 2 voxels off the surface.
    CHECK(sums[0][0] / sums[0][1] == Approx(1.0).margin(0.01));
    CHECK(sums[0][1] / sums[0][2] == Approx(1.0).margin(0.02));
    CHECK(sums[1][0] / sums[1][1] == Approx(1.0).margin(0.03));
    CHECK(sums[1][0] / sums[1][2] == Approx(1.0).margin(0.04));
}
