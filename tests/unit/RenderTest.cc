#include <vxf/render/Render.h>

#include <vxf/core/GridStats.h>
#include <vxf/core/Hash.h>
#include <vxf/core/ProceduralMesh.h>
#include <vxf/core/RayScene.h>
#include <vxf/io/ImageFile.h>
#include <vxf/io/VoxelSetFile.h>
#include <vxf/light/DirectLight.h>
#include <vxf/pipeline/SceneGeometry.h>
#include <vxf/transport/AdaptiveBand.h>
#include <vxf/voxelize/Voxelize.h>

#include "TestSupport.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <catch2/catch.hpp>

namespace {

/// The unit sphere voxelized, with a constant `direct` φ over its medium (no scatter).
vxf::VoxelSet litSphere(double phi)
{
    vxf::VoxelizeOptions options;
    options.dim = 64;
    vxf::VoxelSet set = vxf::voxelize(vxf::makeSphere(openvdb::Vec3d(0.0), 1.0), options);
    vxf::test::putConstantFluence(set, "direct", phi);
    return set;
}

vxf::Scene frontView()
{
    vxf::Camera camera;
    camera.orthographic = true;
    camera.position = openvdb::Vec3d(0, -5, 0);
    camera.lookAt = openvdb::Vec3d(0.0);
    camera.up = openvdb::Vec3d(0, 0, 1);
    camera.width = 3.0;
    vxf::Scene scene;
    scene.camera = camera;
    return scene;
}

/// A directional light of irradiance @a irradiance travelling along @a direction.
vxf::Light sunAlong(const openvdb::Vec3d& direction, double irradiance)
{
    vxf::Light sun;
    sun.type = vxf::Light::Type::Directional;
    sun.direction = direction;
    sun.intensity = irradiance;
    return sun;
}

/// 31x31 pixels, one camera ray each, the volume term alone, single scattering marched to the lights.
vxf::RenderOptions marchedToLights()
{
    vxf::RenderOptions options;
    options.width = options.height = 31;
    options.samples = 1;
    options.surface = false;
    options.directFromLights = true;
    return options;
}

} // namespace

TEST_CASE("view mode: a constant source in a thick sphere gives J/sigma_t", "[render]")
{
    vxf::Material m;
    m.sigmaA = openvdb::Vec3d(2.0, 4.0, 8.0);
    m.sigmaS = openvdb::Vec3d(8.0, 6.0, 2.0); // sigma_t = 10 per channel, d = 2: e^-20 is nothing
    const double phi = 3.0;
    const vxf::VoxelSet set = litSphere(phi);
    const vxf::Medium medium(set, m);
    vxf::RenderOptions options;
    options.width = 31;
    options.height = 31;
    options.samples = 1;
    options.background = openvdb::Vec3d(0.25);
    const vxf::RenderedImage image = vxf::render(set, medium, frontView(), options);
    const std::size_t centre = 15 * 31 + 15;
    // L = ∫ T J dt = J (1 − e^{−σt d})/σt with J = σs φ / 4π (the same ratio inside the ramp).
    for (int c = 0; c < 3; ++c) {
        const double expected = m.sigmaS[c] * phi / (4.0 * M_PI) / 10.0;
        CHECK(image.combined[centre][c] == Approx(expected).epsilon(0.01));
        CHECK(image.direct[centre][c] == Approx(expected).epsilon(0.01));
        CHECK(image.scatter[centre][c] == 0.0f);
    }
    CHECK(image.alpha[centre] == 1.0f);
    CHECK(image.depth[centre] == Approx(4.0).margin(0.05)); // the sphere's front at y = -1
    CHECK(image.normal[centre].y() == Approx(-1.0).margin(0.05));
    // A corner misses: background, alpha 0.
    CHECK(image.alpha[0] == 0.0f);
    CHECK(image.combined[0] == openvdb::Vec3f(0.25f));
}

TEST_CASE("view mode through a thin sphere: J (1 - e^{-tau}) / sigma_t plus the background", "[render]")
{
    vxf::Material m;
    m.sigmaA = openvdb::Vec3d(0.1);
    m.sigmaS = openvdb::Vec3d(0.4); // sigma_t = 0.5
    const vxf::VoxelSet set = litSphere(1.0);
    const vxf::Medium medium(set, m);
    vxf::RenderOptions options;
    options.width = options.height = 31;
    options.samples = 1;
    options.background = openvdb::Vec3d(1.0);
    const vxf::RenderedImage image = vxf::render(set, medium, frontView(), options);
    // Optical depth along the central chord: σt ∫ρ ds with ∫ρ ds = the chord, 2 (density is
    // each voxel's volume fraction, so the medium ends at the surface).
    const double tau = 0.5 * 2.0;
    const double j = 0.4 / (4.0 * M_PI);
    const double expected = j * (1.0 - std::exp(-tau)) / 0.5 + std::exp(-tau) * 1.0;
    CHECK(image.combined[15 * 31 + 15].x() == Approx(expected).epsilon(0.01));
}

TEST_CASE("a camera inside the medium sees J (1 - e^{-sigma_t R}) / sigma_t around it, and the background through it", "[render]")
{
    // The camera at the centre of the lit sphere (radius R = 1): every ray crosses R of medium
    // from the camera, whatever its direction. Thick, the infinite medium's σs φ / (4π σt); thin,
    // plus the background seen through e^{−σt R}. The same with the sphere's mesh (Embree).
    const double phi = 2.0;
    const vxf::VoxelSet set = litSphere(phi);
    const vxf::TriangleMesh mesh = vxf::makeSphere(openvdb::Vec3d(0.0), 1.0);
    vxf::RayScene meshes;
    meshes.add(mesh, 0);
    meshes.commit();
    vxf::Scene scene;
    scene.camera.position = openvdb::Vec3d(0.0);
    scene.camera.lookAt = openvdb::Vec3d(0.3, 1.0, 0.2);
    scene.camera.up = openvdb::Vec3d(0, 0, 1);
    scene.camera.fovDegrees = 90.0;
    vxf::RenderOptions options;
    options.width = 9;
    options.height = 9;
    options.samples = 1;
    options.step = 0.5;
    options.background = openvdb::Vec3d(0.5);
    for (double sigmaT : {20.0, 0.7}) {
        vxf::Material m;
        m.sigmaA = openvdb::Vec3d(0.25 * sigmaT);
        m.sigmaS = openvdb::Vec3d(0.75 * sigmaT);
        const vxf::Medium medium(set, m);
        vxf::SceneObject sphere;
        sphere.name = "sphere";
        sphere.mesh = "builtin:sphere";
        sphere.material = m;
        scene.objects = {sphere};
        const double transmitted = std::exp(-sigmaT * 1.0);
        const double expected = 0.75 * phi / (4.0 * M_PI) * (1.0 - transmitted) + 0.5 * transmitted;
        for (bool withMeshes : {false, true}) {
            vxf::RenderMeshes rayMeshes;
            if (withMeshes) rayMeshes.visible = rayMeshes.media = &meshes;
            const vxf::RenderedImage image = vxf::render(set, medium, scene, options, rayMeshes);
            INFO("sigma_t " << sigmaT << (withMeshes ? ", meshes" : ", level set"));
            for (std::size_t p : {std::size_t(0), std::size_t(40), std::size_t(80)}) { // corner, centre, corner
                INFO("pixel " << p);
                CHECK(image.combined[p][0] == Approx(expected).epsilon(0.02));
                CHECK(image.alpha[p] == 1.0f);
            }
        }
    }
}

TEST_CASE("view mode with the media's meshes: rays enter and leave where the mesh does, to the silhouette", "[render][rayscene]")
{
    // A coarse polyhedral sphere (8 rings, 16 segments) of a thin medium glowing uniformly
    // (a constant `scatter` fluence, J = σs·φ/4π): a camera ray's radiance is
    // J (1 − e^{−σt c})/σt for its chord c through the mesh, which Embree gives exactly. Near
    // the silhouette c changes by 4R/c for a change of depth, and the level set's crossings,
    // a few thousandths of a voxel off the facets, misplace such chords; with the meshes as
    // RenderMeshes::media the march crosses the surface where they do.
    const double dx = 0.05, sigmaA = 0.1, sigmaS = 0.4, phi = 2.0;
    const vxf::TriangleMesh mesh = vxf::makeSphere(openvdb::Vec3d(0.0), 1.0, 8, 16);
    vxf::VoxelizeOptions voxelize;
    voxelize.voxelSize = dx;
    vxf::VoxelSet set = vxf::voxelize(mesh, voxelize);
    vxf::test::putConstantFluence(set, "scatter", phi);
    vxf::Material material;
    material.sigmaA = openvdb::Vec3d(sigmaA);
    material.sigmaS = openvdb::Vec3d(sigmaS);
    const vxf::Medium medium(set, material);
    vxf::Scene scene = frontView();
    vxf::SceneObject ball; // the medium object the meshes' id 0 names
    ball.name = "ball";
    ball.material = material;
    scene.objects.push_back(ball);
    vxf::RayScene visible, occluders, media;
    visible.add(mesh, 0);
    visible.commit();
    occluders.commit();
    media.add(mesh, 0);
    media.commit();
    vxf::RenderOptions options;
    options.width = options.height = 91;
    options.samples = 1;
    options.surface = false;
    const vxf::RenderedImage onMesh = vxf::render(set, medium, scene, options, {&visible, &occluders, &media});
    const vxf::RenderedImage onLevelSet = vxf::render(set, medium, scene, options, {&visible, &occluders});
    const double j = sigmaS * phi / (4.0 * M_PI), sigmaT = sigmaA + sigmaS;
    double worstMesh = 0.0, worstLevelSet = 0.0;
    int rays = 0;
    for (int y = 0; y < options.height; ++y) {
        for (int x = 0; x < options.width; ++x) {
            // The pixel's one camera ray, jittered as render() does (Render.cc, tracePixel), of
            // frontView's orthographic camera: 3 units wide, along +y.
            const std::size_t pixel = std::size_t(y) * std::size_t(options.width) + std::size_t(x);
            const double px = x + vxf::unitHash(pixel, 0, 0), py = y + vxf::unitHash(pixel, 0, 1);
            const openvdb::Vec3d origin(1.5 * (2.0 * px / options.width - 1.0), -5.0, 1.5 * (1.0 - 2.0 * py / options.height));
            const openvdb::Vec3d dir(0, 1, 0);
            const auto in = visible.intersect(origin, dir);
            if (!in) continue;
            const auto out = visible.intersect(origin, dir, in->distance + 1e-5);
            REQUIRE(out);
            const double chord = out->distance - in->distance;
            const double expected = j * (1.0 - std::exp(-sigmaT * chord)) / sigmaT;
            INFO("pixel " << x << ", " << y << ": chord " << chord << " (" << chord / dx << " voxels)");
            // (a chord of a hundredth of a voxel right at the tangent, which the level set
            // never enters, is 1e-3 of the brightest pixel: the margin)
            CHECK(onMesh.scatter[pixel].x() == Approx(expected).epsilon(0.002).margin(1e-4));
            worstMesh = std::max(worstMesh, std::abs(onMesh.scatter[pixel].x() - expected));
            worstLevelSet = std::max(worstLevelSet, std::abs(onLevelSet.scatter[pixel].x() - expected));
            ++rays;
        }
    }
    INFO("worst error: on the mesh " << worstMesh << ", on the level set " << worstLevelSet << " (brightest pixel ~0.08)");
    CHECK(rays > 1000);
    CHECK(worstMesh < 0.2 * worstLevelSet);

    // Hits name scene objects by the meshes' ids: an id the scene lacks is an error, not a read past its objects.
    vxf::RayScene stray;
    stray.add(mesh, 1);
    stray.commit();
    CHECK_THROWS_WITH(vxf::render(set, medium, scene, options, {&visible, &occluders, &stray}),
        Catch::Contains("object 1") && Catch::Contains("1 object(s)"));
}

TEST_CASE("gather mode and image files", "[render][io]")
{
    vxf::Material m;
    m.sigmaA = openvdb::Vec3d(1.0);
    m.sigmaS = openvdb::Vec3d(4.0);
    const vxf::VoxelSet set = litSphere(2.0);
    const vxf::Medium medium(set, m);
    vxf::RenderOptions options;
    options.width = 24;
    options.height = 16;
    options.samples = 2;
    options.gather = true;
    options.gatherDirections = 16;
    const vxf::RenderedImage image = vxf::render(set, medium, frontView(), options);
    bool finite = true;
    for (const auto& p : image.combined) finite = finite && std::isfinite(p[0]) && p[0] >= 0.0f;
    CHECK(finite);
    CHECK(image.combined[8 * 24 + 12].x() > 0.0f);

    vxf::test::TempDir dir;
    vxf::writeExr(dir.path("a.exr"), image);
    vxf::writePng(dir.path("a.png"), image);
    Imf::InputFile exr(dir.path("a.exr").c_str());
    const Imf::ChannelList& channels = exr.header().channels();
    for (const char* name : {"R", "G", "B", "A", "direct.R", "scatter.B", "depth.Z", "normal.X", "samples.count"}) {
        INFO(name);
        CHECK(channels.findChannel(name) != nullptr);
    }
    CHECK(exr.header().dataWindow().max.x == 23);
    const std::string png = vxf::test::slurp(dir.path("a.png"));
    CHECK(png.substr(1, 3) == "PNG");
}

TEST_CASE("surface term: Lambert + normalized Blinn-Phong in closed form, occluder shadows, Embree hits", "[render][rayscene]")
{
    // A clear medium (no volume term), an occluder box whose face y = -1 faces the camera,
    // lit by a directional light of irradiance E = 2 from 45 degrees above the camera side.
    vxf::VoxelSet set = litSphere(0.0);
    const vxf::Medium medium(set, vxf::test::greyMaterial(0.0, 0.0));
    vxf::Scene scene = frontView();
    vxf::SceneObject wall;
    wall.name = "wall";
    wall.role = vxf::SceneObject::Role::Occluder;
    wall.surface.diffuse = openvdb::Vec3d(0.5);
    wall.surface.specular = openvdb::Vec3d(0.2);
    wall.surface.shininess = 10.0;
    scene.objects.push_back(wall);
    vxf::SceneObject blocker = wall;
    blocker.name = "blocker";
    scene.objects.push_back(blocker);
    vxf::Light sun;
    sun.type = vxf::Light::Type::Directional;
    sun.direction = openvdb::Vec3d(0, 1, -1).unit();
    sun.intensity = 2.0;
    scene.lights.push_back(sun);

    vxf::RayScene visible, occluders;
    const vxf::TriangleMesh wallMesh = vxf::makeBox(openvdb::Vec3d(-1.4), openvdb::Vec3d(1.4, 1.4, 1.0) + openvdb::Vec3d(0, -0.4, 0));
    // Its front face is y = -1.4; the blocker sits on the shadow ray of the centre, off the camera rays.
    const vxf::TriangleMesh blockerMesh = vxf::makeBox(openvdb::Vec3d(-0.2, -3.2, 1.6), openvdb::Vec3d(0.2, -2.8, 2.0));
    visible.add(wallMesh, 0);
    visible.add(blockerMesh, 1);
    visible.commit();
    occluders.add(wallMesh, 0);
    occluders.add(blockerMesh, 1);
    occluders.commit();

    vxf::RenderOptions options;
    options.width = 31;
    options.height = 21;
    options.samples = 1;
    const vxf::RenderedImage image = vxf::render(set, medium, scene, options, {&visible, &occluders});
    const auto at = [&](int x, int y) { return std::size_t(y) * std::size_t(options.width) + std::size_t(x); };
    // Lit pixel off the centre line (x = 0.9): L = E cosθ (kd/π + ks (e+8)/(8π) (n·h)^e),
    // cosθ = 1/√2, h halfway between the light (0,-1,1)/√2 and the viewer (0,-1,0).
    const openvdb::Vec3d n(0, -1, 0), toLight = openvdb::Vec3d(0, -1, 1).unit(), h = (toLight + n).unit();
    const double cosTheta = n.dot(toLight);
    const double expected = 2.0 * cosTheta * (0.5 / M_PI + 0.2 * 18.0 / (8.0 * M_PI) * std::pow(n.dot(h), 10.0));
    const std::size_t lit = at(24, 10); // x = (24.5/31·2 − 1)·1.5 ≈ 0.87
    CHECK(image.alpha[lit] == 1.0f);
    CHECK(image.surface[lit][0] == Approx(expected).epsilon(1e-5));
    CHECK(image.combined[lit][0] == Approx(expected).epsilon(1e-5));
    CHECK(image.depth[lit] == Approx(5.0 - 1.4).epsilon(1e-5));
    // The centre pixel's shadow ray meets the blocker.
    CHECK(image.surface[at(15, 10)][0] == 0.0f);
    CHECK(image.alpha[at(15, 10)] == 1.0f);

    // Without the surface term the occluder is black but still opaque.
    options.surface = false;
    const vxf::RenderedImage plain = vxf::render(set, medium, scene, options, {&visible, &occluders});
    CHECK(plain.combined[lit][0] == 0.0f);
    CHECK(plain.alpha[lit] == 1.0f);
}

TEST_CASE("surface term shadowed by a medium: Beer-Lambert along the chord, the vacuum before it skipped with the media's meshes",
    "[render][rayscene]")
{
    // A wall (front face y = 1.5, kd = 0.5) behind a unit sphere of medium (σt = 1), lit by a
    // directional light of irradiance E = 2 travelling along (0, 1, −1)/√2, seen by camera rays
    // that pass below and above the sphere (|z| = 1.26). Below, the wall's shadow ray crosses the
    // sphere along a chord c: E cosθ kd/π · e^{−σt c}; above, it misses it: E cosθ kd/π. With the
    // sphere's mesh as RenderMeshes::media the shadow ray marches only from 2 voxels before the
    // mesh (none met: nothing marched), without it the whole way; the two agree.
    const double dx = 0.05, sigmaT = 1.0, irradiance = 2.0, kd = 0.5;
    const vxf::TriangleMesh ballMesh = vxf::makeSphere(openvdb::Vec3d(0.0), 1.0);
    vxf::VoxelizeOptions voxelize;
    voxelize.voxelSize = dx;
    vxf::VoxelSet set = vxf::voxelize(ballMesh, voxelize);
    vxf::test::putConstantFluence(set, "direct", 0.0);
    vxf::Material material;
    material.sigmaA = openvdb::Vec3d(sigmaT);
    material.sigmaS = openvdb::Vec3d(0.0);
    const vxf::Medium medium(set, material);
    vxf::Scene scene = frontView();
    vxf::SceneObject ball;
    ball.name = "ball";
    ball.material = material;
    scene.objects.push_back(ball);
    vxf::SceneObject wall;
    wall.name = "wall";
    wall.role = vxf::SceneObject::Role::Occluder;
    wall.surface.diffuse = openvdb::Vec3d(kd);
    scene.objects.push_back(wall);
    const openvdb::Vec3d toLight = openvdb::Vec3d(0, -1, 1).unit();
    scene.lights.push_back(sunAlong(-toLight, irradiance));

    const vxf::TriangleMesh wallMesh = vxf::makeBox(openvdb::Vec3d(-2.0, 1.5, -2.0), openvdb::Vec3d(2.0, 2.0, 2.0));
    vxf::RayScene visible, occluders, media;
    visible.add(wallMesh, 1);
    visible.commit();
    occluders.add(wallMesh, 1);
    occluders.commit();
    media.add(ballMesh, 0);
    media.commit();
    vxf::RenderOptions options;
    options.width = options.height = 31;
    options.samples = 1;
    const vxf::RenderedImage onMesh = vxf::render(set, medium, scene, options, {&visible, &occluders, &media});
    const vxf::RenderedImage marched = vxf::render(set, medium, scene, options, {&visible, &occluders});

    const double unshadowed = irradiance * toLight.dot(openvdb::Vec3d(0, -1, 0)) * kd / M_PI;
    // Rows 2 and 28 of column 15: z = ±((2.5/31)·2 − 1)·1.5, x = 0; the shadow ray starts half a
    // voxel off the wall.
    const double z = (1.0 - 5.0 / 31.0) * 1.5;
    const openvdb::Vec3d start(0.0, 1.5 - 0.5 * dx, -z);
    const double miss = start.cross(toLight).length(); // the ray's distance from the centre
    const double chord = 2.0 * std::sqrt(1.0 - miss * miss);
    const double shadowed = unshadowed * std::exp(-sigmaT * chord);
    const std::size_t top = 2 * 31 + 15, bottom = 28 * 31 + 15;
    for (const vxf::RenderedImage* image : {&onMesh, &marched}) {
        const double dark = std::min(image->surface[top][0], image->surface[bottom][0]);
        const double bright = std::max(image->surface[top][0], image->surface[bottom][0]);
        CHECK(bright == Approx(unshadowed).epsilon(1e-5));
        CHECK(dark == Approx(shadowed).epsilon(0.01));
    }
    CHECK(onMesh.surface[top][0] == Approx(marched.surface[top][0]).epsilon(0.01));
    CHECK(onMesh.surface[bottom][0] == Approx(marched.surface[bottom][0]).epsilon(0.01));
}

TEST_CASE("an emitter is seen by its emission and casts no shadow, an occluder in its place does", "[render][rayscene]")
{
    // A wall (front face y = 1) lit by a point light inside a small emitting sphere between
    // it and the camera: the sphere covers the centre pixel, the light reaches the wall
    // through it. No medium object: camera rays meet only the two meshes.
    vxf::VoxelSet set = litSphere(0.0);
    const vxf::Medium medium(set, vxf::test::greyMaterial(0.0, 0.0));
    const auto placed = [](const char* mesh, const openvdb::Vec3d& scale, const openvdb::Vec3d& at) {
        vxf::SceneObject o;
        o.mesh = mesh;
        o.objectToWorld.setToScale(scale);
        o.objectToWorld.postTranslate(at);
        return o;
    };
    vxf::Scene scene = frontView();
    vxf::SceneObject wall = placed("builtin:box", {1.5, 0.2, 1.5}, {0, 1.2, 0});
    wall.role = vxf::SceneObject::Role::Occluder;
    wall.surface.diffuse = openvdb::Vec3d(0.5);
    vxf::SceneObject flame = placed("builtin:sphere", openvdb::Vec3d(0.3), {0, -1, 0});
    flame.role = vxf::SceneObject::Role::Emitter;
    flame.surface.emission = openvdb::Vec3d(3, 2, 1);
    scene.objects = {wall, flame};
    vxf::Light bulb;
    bulb.position = openvdb::Vec3d(0, -1, 0);
    bulb.intensity = 4.0;
    scene.lights.push_back(bulb);

    vxf::RenderOptions options;
    options.width = options.height = 21;
    options.samples = 1;
    const auto rendered = [&](const vxf::Scene& s) {
        const vxf::SceneRayScenes meshes = vxf::sceneRayScenes(s);
        return vxf::render(set, medium, s, options, {&meshes.visible, &meshes.occluders, &meshes.media});
    };
    const vxf::RenderedImage image = rendered(scene);
    const std::size_t centre = 10 * 21 + 10, behind = 10 * 21 + 14; // x = 0.57: the wall beside the sphere
    CHECK(image.combined[centre] == openvdb::Vec3f(3, 2, 1));
    CHECK(image.surface[centre] == openvdb::Vec3f(3, 2, 1));
    CHECK(image.alpha[centre] == 1.0f);
    CHECK(image.depth[centre] == Approx(5.0 - 1.3).epsilon(0.01));

    // The wall behind sees the light as if the sphere were not there.
    vxf::Scene bare = scene;
    bare.objects.pop_back();
    const vxf::RenderedImage without = rendered(bare);
    CHECK(image.combined[behind][0] > 0.0f);
    CHECK(image.combined[behind] == without.combined[behind]);
    // The same sphere as an occluder shadows the wall and shows its emission.
    vxf::Scene shut = scene;
    shut.objects.back().role = vxf::SceneObject::Role::Occluder;
    const vxf::RenderedImage shadowed = rendered(shut);
    CHECK(shadowed.combined[behind] == openvdb::Vec3f(0.0f));
    CHECK(shadowed.combined[centre] == openvdb::Vec3f(3, 2, 1));
}

TEST_CASE("direct from the lights: a thick sphere lit along the view gives sigma_s E / (8 pi sigma_t)", "[render]")
{
    // A directional light E shining along the camera's view (+y) into a thick sphere: at depth
    // s the light and the view ray have crossed the same medium, so
    // L = ∫ e^{−σt s}·σs E e^{−σt s}/(4π) ds = σs E / (8π σt). The direct grid is zero, so
    // only the marched light can give it; with the grid the direct layer is zero.
    vxf::Material m;
    m.sigmaA = openvdb::Vec3d(2.0, 4.0, 8.0);
    m.sigmaS = openvdb::Vec3d(8.0, 6.0, 2.0); // σt = 10: 0.33 per voxel at dim 64
    const vxf::VoxelSet set = litSphere(0.0);
    const vxf::Medium medium(set, m);
    vxf::Scene scene = frontView();
    vxf::Light sun;
    sun.type = vxf::Light::Type::Directional;
    sun.direction = openvdb::Vec3d(0, 1, 0);
    sun.intensity = 2.0;
    scene.lights.push_back(sun);
    vxf::RenderOptions options;
    options.width = options.height = 31;
    options.samples = 1;
    options.surface = false;
    const std::size_t centre = 15 * 31 + 15;
    CHECK(vxf::render(set, medium, scene, options).direct[centre] == openvdb::Vec3f(0.0f));
    options.directFromLights = true;
    const vxf::RenderedImage image = vxf::render(set, medium, scene, options);
    for (int c = 0; c < 3; ++c) {
        CHECK(image.direct[centre][c] == Approx(m.sigmaS[c] * 2.0 / (8.0 * M_PI * 10.0)).epsilon(0.02));
    }

    // A constant environment L around a nearly transparent sphere: φ = 4πL everywhere, so
    // L_view = σs·L·chord. Its 64 directions give one random sample per step, weighted by 64.
    vxf::Material thin;
    thin.sigmaA = openvdb::Vec3d(0.001);
    thin.sigmaS = openvdb::Vec3d(0.004);
    const vxf::Medium thinMedium(set, thin);
    vxf::Light sky;
    sky.type = vxf::Light::Type::Environment;
    sky.samples = 64;
    sky.intensity = 1.5;
    scene.lights = {sky};
    const vxf::RenderedImage lit = vxf::render(set, thinMedium, scene, options);
    CHECK(lit.direct[centre].x() == Approx(0.004 * 1.5 * 2.0).epsilon(0.02));
}

TEST_CASE("direct from the lights: a face lit at a grazing angle gives sigma_s E mu / (4 pi sigma_t (1 + mu))", "[render]")
{
    // A cube's face seen along its normal, a sun meeting it at cosine μ: at depth z the light
    // has come z/μ through the medium and the view ray z, so
    // L = ∫ σs E e^{−σt z/μ} e^{−σt z}/(4π) dz = σs E μ / (4π σt (1 + μ)). The light lives in
    // a layer μ/σt deep: 0.32 and 0.1 voxel. The cube is turned 20° about z, so the march's
    // steps meet the face at a different phase in every pixel. A quadratic through each
    // one-voxel step's three points gave 1.4% and 28% too much; the camera march now halves
    // such steps (Render.cc, Marcher::integrate): 0.04% and 0.1%.
    const double mu = GENERATE(0.1, 0.03), sigmaT = 10.0, albedo = 0.99, irradiance = 2.0;
    const openvdb::Mat3d turn = openvdb::math::rotation<openvdb::Mat3d>(openvdb::Vec3d(0, 0, 1), 20.0 * M_PI / 180.0);
    vxf::TriangleMesh cube = vxf::makeBox(openvdb::Vec3d(-1.0), openvdb::Vec3d(1.0));
    for (auto& p : cube.points) p = turn * p;
    vxf::VoxelizeOptions voxelize;
    voxelize.dim = 64;
    const vxf::VoxelSet set = vxf::voxelize(cube, voxelize);
    const vxf::Medium medium(set, vxf::test::albedoMaterial(sigmaT, albedo));
    vxf::Scene scene = frontView();
    scene.camera.position = turn * openvdb::Vec3d(0, -5, 0); // facing the turned face y = −1
    scene.lights.push_back(sunAlong(turn * openvdb::Vec3d(std::sqrt(1.0 - mu * mu), mu, 0.0), irradiance)); // into the face
    const vxf::RenderedImage image = vxf::render(set, medium, scene, marchedToLights());
    const double expected = albedo * sigmaT * irradiance * mu / (4.0 * M_PI * sigmaT * (1.0 + mu));
    // Pixels on the face away from its edges (light through the side x = −1 adds e^{−σt·0.9}).
    for (int y = 10; y <= 20; y += 5) {
        for (int x = 14; x <= 20; ++x) {
            INFO("mu " << mu << ", pixel " << x << ", " << y);
            CHECK(image.direct[std::size_t(y) * 31 + std::size_t(x)].x() == Approx(expected).epsilon(0.005));
        }
    }
}

TEST_CASE("adaptive sampling: more camera rays on the silhouette only (beside a differing neighbour too), the mean unbiased", "[render]")
{
    vxf::Material m;
    m.sigmaA = openvdb::Vec3d(0.1);
    m.sigmaS = openvdb::Vec3d(0.4);
    const vxf::VoxelSet set = litSphere(1.0);
    const vxf::Medium medium(set, m);
    vxf::RenderOptions options;
    options.width = options.height = 31;
    options.background = openvdb::Vec3d(1.0);
    const auto renderWith = [&](int samples, int maxSamples) {
        options.samples = samples;
        options.maxSamples = maxSamples;
        return vxf::render(set, medium, frontView(), options);
    };
    const vxf::RenderedImage plain = renderWith(4, 0), adaptive = renderWith(4, 64), truth = renderWith(1024, 0);
    CHECK(plain.refinedPixels == 0);
    REQUIRE(adaptive.refinedPixels > 0);
    CHECK(adaptive.refinedPixels < 31 * 31 / 3); // the interior and the corners keep 4 rays

    double plainError = 0.0, adaptiveError = 0.0, coverage = 0.0;
    for (std::size_t p = 0; p < truth.alpha.size(); ++p) {
        const bool edge = truth.alpha[p] > 0.0f && truth.alpha[p] < 1.0f;
        INFO("pixel " << p << " alpha " << truth.alpha[p]);
        if (edge && adaptive.alpha[p] > 0.0f && adaptive.alpha[p] < 1.0f) CHECK(adaptive.samples[p] == 64.0f);
        if (!edge) CHECK(adaptive.samples[p] >= 4.0f);
        plainError += std::pow(plain.combined[p].x() - truth.combined[p].x(), 2);
        adaptiveError += std::pow(adaptive.combined[p].x() - truth.combined[p].x(), 2);
        coverage += adaptive.alpha[p];
    }
    CHECK(adaptive.samples[15 * 31 + 15] == 4.0f);
    CHECK(adaptive.samples[0] == 4.0f);
    // Silhouette pixels are where 4 rays err; 64 there take most of it away.
    CHECK(std::sqrt(adaptiveError) < 0.5 * std::sqrt(plainError));
    // The unit disc covers π of the 3 x 3 picture: the rays stay uniform over each pixel.
    CHECK(coverage / (31.0 * 31.0) == Approx(M_PI / 9.0).epsilon(0.01));

    // One first ray per pixel never disagrees with itself: the neighbours whose first rays met
    // something else find the edge (one ray errs by up to the pixel's whole coverage).
    const vxf::RenderedImage single = renderWith(1, 64);
    double worst = 0.0;
    std::size_t edges = 0;
    for (std::size_t p = 0; p < truth.alpha.size(); ++p) {
        if (truth.alpha[p] <= 0.0f || truth.alpha[p] >= 1.0f) continue;
        INFO("pixel " << p << " alpha " << truth.alpha[p] << " vs " << single.alpha[p]);
        CHECK(single.samples[p] == 64.0f);
        worst = std::max(worst, double(std::abs(single.alpha[p] - truth.alpha[p])));
        ++edges;
    }
    CHECK(edges > 40);
    CHECK(worst < 0.1);
    CHECK(single.samples[15 * 31 + 15] == 1.0f);
    CHECK(single.refinedPixels < 31 * 31 / 3);
}

TEST_CASE("direct from an environment: the samples along a ray are spread over it, the mean unbiased", "[render]")
{
    // A thick sphere (σt = 10, 0.3 per voxel) in a constant environment: near the surface the
    // light comes from outside only, so which of the 64 directions each emission point samples
    // matters. One camera ray per pixel, and 16, against 256.
    vxf::Material m;
    m.sigmaA = openvdb::Vec3d(2.0);
    m.sigmaS = openvdb::Vec3d(8.0);
    const vxf::VoxelSet set = litSphere(0.0);
    const vxf::Medium medium(set, m);
    vxf::Scene scene = frontView();
    vxf::Light sky;
    sky.type = vxf::Light::Type::Environment;
    sky.samples = 64;
    sky.intensity = 1.0;
    scene.lights = {sky};
    vxf::RenderOptions options;
    options.width = options.height = 31;
    options.surface = false;
    options.directFromLights = true;
    const auto renderWith = [&](int samples) {
        options.samples = samples;
        return vxf::render(set, medium, scene, options);
    };
    const vxf::RenderedImage one = renderWith(1), some = renderWith(16), many = renderWith(256);
    double sumSome = 0.0, sumMany = 0.0, squared = 0.0;
    int pixels = 0;
    for (std::size_t p = 0; p < many.alpha.size(); ++p) {
        if (many.alpha[p] < 1.0f) continue; // the disc's inside only: no coverage noise
        const double b = many.direct[p].x();
        sumSome += some.direct[p].x();
        sumMany += b;
        squared += std::pow((one.direct[p].x() - b) / b, 2);
        ++pixels;
    }
    REQUIRE(pixels > 250);
    const double noise = std::sqrt(squared / pixels);
    INFO("relative RMS noise of one ray per pixel: " << noise);
    // 16 rays: about 7% noise per pixel, 0.4% on the mean of 293 pixels.
    CHECK(sumSome / sumMany == Approx(1.0).epsilon(0.015));
    // Independent picks at each point gave 0.37; the golden-ratio sequence along the ray 0.26.
    CHECK(noise < 0.30);
}

TEST_CASE("a volume object's grid: camera rays march it from the camera, alpha 1 - T, the background through it", "[render][volume]")
{
    // A fog box of density 1, 2 units across (40 voxels of 0.05, trilinear: ∫ρ ds = 2 along an
    // axis), no surface and no meshes, lit by a constant `direct` φ: the centre's radiance is
    // J (1 − e^{−τ}) / σt + e^{−τ}·background with J = σs φ / 4π, τ = 2 σt; its alpha 1 − e^{−τ}.
    const double dx = 0.05, phi = 2.0;
    vxf::VoxelSet set(openvdb::math::Transform::createLinearTransform(dx));
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->setGridClass(openvdb::GRID_FOG_VOLUME);
    density->setTransform(set.transformPtr());
    density->tree().denseFill(openvdb::CoordBBox(openvdb::Coord(-20), openvdb::Coord(19)), 1.0f, true);
    set.put(density);
    vxf::test::putConstantFluence(set, "direct", phi);
    vxf::Material m;
    m.sigmaA = openvdb::Vec3d(0.1, 0.2, 0.3);
    m.sigmaS = openvdb::Vec3d(0.4, 0.3, 0.2);
    const vxf::Medium medium(set, m);
    vxf::Scene scene = frontView();
    vxf::SceneObject cloud;
    cloud.name = "cloud";
    cloud.volume = "cloud.vdb"; // (the render reads the set it is given)
    cloud.material = m;
    scene.objects = {cloud};
    vxf::RenderOptions options;
    options.width = options.height = 31;
    options.samples = 1;
    options.background = openvdb::Vec3d(0.5, 1.0, 2.0);
    for (bool gather : {false, true}) {
        INFO((gather ? "gather" : "view") << " mode");
        options.gather = gather;
        const vxf::RenderedImage image = vxf::render(set, medium, scene, options);
        const std::size_t centre = 15 * 31 + 15;
        double meanT = 0.0;
        for (int c = 0; c < 3; ++c) {
            const double sigmaT = m.sigmaA[c] + m.sigmaS[c], t = std::exp(-2.0 * sigmaT);
            const double j = m.sigmaS[c] * phi / (4.0 * M_PI);
            CHECK(image.direct[centre][c] == Approx(j * (1.0 - t) / sigmaT).epsilon(0.01));
            CHECK(image.combined[centre][c] == Approx(j * (1.0 - t) / sigmaT + t * options.background[c]).epsilon(0.01));
            meanT += t / 3.0;
        }
        CHECK(image.alpha[centre] == Approx(1.0 - meanT).epsilon(0.01));
        // A corner misses the box: the background, alpha 0.
        CHECK(image.alpha[0] == 0.0f);
        CHECK(image.combined[0] == openvdb::Vec3f(options.background));
    }
}

TEST_CASE("a Henyey-Greenstein phase: a thin slab's single scattering in closed form for each g", "[render][phase]")
{
    // A slab D thick seen along its normal from the side the sun leaves through, the sun
    // crossing it at cosine μ0 to the normal. Single scattering is taken with the phase itself
    // through the transport's scaled medium σt* = σt − f·σs (delta-M's single-scattering
    // correction, Nakajima & Tanaka: the light kept in the beam is on its way), f = g⁴ where the
    // solve carried the phase's first moment (a `scatter_anisotropy` grid), g (the similarity
    // relation) where it did not, 0 for g ≤ 0. At depth z from the lit face the light has come
    // z/μ0 through the medium and the camera's ray D − z, so
    // L = σs E p(θ) ∫_0^D e^{−σt* z/μ0} e^{−σt* (D − z)} dz = σs E p(θ) e^{−σt* D} (1 − e^{−aD})/a,
    // a = σt* (1/μ0 − 1) (D as a → 0), θ the angle the light turns through: cosθ = μ0 here.
    // p is Henyey-Greenstein's, written out here: 4πp = (1 − g²)/(1 + g² − 2gμ)^{3/2}.
    const double g = GENERATE(-0.5, 0.0, 0.5, 0.9);
    const double degrees = GENERATE(0.0, 40.0);
    const bool firstMoment = GENERATE(false, true);
    const double sigmaT = 4.0, albedo = 0.8, irradiance = 2.0, depth = 0.2; // τ = 0.8 across
    vxf::VoxelizeOptions voxelize;
    voxelize.dim = 64; // 6.4 voxels across the slab
    vxf::VoxelSet set =
        vxf::voxelize(vxf::makeBox(openvdb::Vec3d(-1.0, -0.5 * depth, -1.0), openvdb::Vec3d(1.0, 0.5 * depth, 1.0)), voxelize);
    if (firstMoment) { // as the accelerated sweeps leave it: no light scattered, none of its direction
        vxf::test::putConstantFluence(set, "scatter", 0.0);
        vxf::test::putConstantFluence(set, "scatter_anisotropy", 0.0);
    }
    vxf::Material m = vxf::test::albedoMaterial(sigmaT, albedo);
    m.phaseG = g;
    const vxf::Medium medium(set, m);
    vxf::Scene scene = frontView();
    scene.camera.position = openvdb::Vec3d(0, 5, 0); // on the side the light leaves through
    const double mu0 = std::cos(degrees * M_PI / 180.0);
    scene.lights.push_back(sunAlong(openvdb::Vec3d(std::sqrt(1.0 - mu0 * mu0), mu0, 0.0), irradiance)); // in through y = −D/2
    vxf::RenderOptions options = marchedToLights();
    options.background = openvdb::Vec3d(0.25);
    const vxf::RenderedImage image = vxf::render(set, medium, scene, options);
    const double f = g <= 0.0 ? 0.0 : firstMoment && g != 0.0 ? std::pow(g, 4.0) : g;
    const double scaledT = sigmaT - f * albedo * sigmaT;
    const double a = scaledT * (1.0 / mu0 - 1.0);
    const double along = a > 0.0 ? -std::expm1(-a * depth) / a : depth;
    const double phase = (1.0 - g * g) / std::pow(1.0 + g * g - 2.0 * g * mu0, 1.5);
    const double expected = albedo * sigmaT * irradiance * phase / (4.0 * M_PI) * std::exp(-scaledT * depth) * along;
    for (int x = 13; x <= 17; x += 2) {
        INFO("g " << g << ", " << degrees << " degrees, first moment " << firstMoment << ", pixel " << x);
        CHECK(image.direct[15 * 31 + std::size_t(x)].x() == Approx(expected).epsilon(0.01));
        // The background behind it through the slab's own transmittance e^{−σt D}, not the scaled medium's.
        const std::size_t i = 15 * 31 + std::size_t(x);
        CHECK(image.combined[i].x() - image.direct[i].x() == Approx(0.25 * std::exp(-sigmaT * depth)).epsilon(0.01));
    }
}

TEST_CASE("a Henyey-Greenstein phase: the scattered light reaches the camera through the reduced medium", "[render][phase]")
{
    // A constant scatter fluence φ in a thick sphere, solved (as the passes solve it) in the
    // medium of σs' = (1 − g)σs, σt' = σt − gσs: L = σs'φ/(4π σt'), the similarity relation's
    // radiance; through the medium's own σt it would be σs'φ/(4π σt), darker by σt'/σt.
    const double g = GENERATE(-0.6, 0.7);
    vxf::Material m = vxf::test::greyMaterial(2.0, 8.0); // σt = 10, d = 2
    m.phaseG = g;
    const double phi = 3.0;
    vxf::VoxelSet set = litSphere(0.0);
    vxf::test::putConstantFluence(set, "scatter", phi);
    const vxf::Medium medium(set, m);
    vxf::RenderOptions options;
    options.width = options.height = 31;
    options.samples = 1;
    const vxf::RenderedImage image = vxf::render(set, medium, frontView(), options);
    const double reducedS = (1.0 - g) * 8.0, reducedT = 10.0 - g * 8.0;
    INFO("g " << g);
    CHECK(image.scatter[15 * 31 + 15].x() == Approx(reducedS * phi / (4.0 * M_PI) / reducedT).epsilon(0.01));
}

TEST_CASE("a Henyey-Greenstein phase: the grids' light scatters toward the camera by the rest of the phase from its mean direction",
    "[render][phase]")
{
    // The accelerated sweeps' scattered fluence φ with its mean direction a (`scatter_anisotropy`),
    // in the delta-M medium (f = g⁴ kept in the beam, Phase.h): toward the camera
    // J = σs*φ·R/4π, R = 1 + 3χ1·t + 5χ2·t² + 7χ3·t³ for a of length |t| along the line of
    // sight (t > 0 toward the camera; the light taken as a Henyey-Greenstein lobe of parameter
    // |t|, χ_l = (g^l − f)/(1 − f) the rest's moments), reaching it through σt* = σt − f·σs: in a
    // thick sphere L = J/σt*. The light travelling toward the camera (a along −y, the camera at
    // −y) is the brighter, away from it the darker. The `direct` grid's J (read, not marched to
    // the lights) alike from `scatter_source_anisotropy`.
    const double g = 0.6, phi = 3.0, f = std::pow(g, 4.0);
    vxf::Material m = vxf::test::greyMaterial(2.0, 8.0); // σt = 10
    m.phaseG = g;
    const double sigmaS = (1.0 - f) * 8.0, sigmaT = 10.0 - f * 8.0;
    double chi[3];
    for (int l = 0; l < 3; ++l) chi[l] = (std::pow(g, l + 1) - f) / (1.0 - f);
    const double direct = 2.0;
    for (const double toward : {0.6, -0.6}) {
        vxf::VoxelSet set = litSphere(direct);
        vxf::test::putConstantFluence(set, "scatter", phi);
        auto anisotropy = set.get<openvdb::Vec3SGrid>("scatter")->deepCopy();
        for (auto it = anisotropy->beginValueOn(); it; ++it) it.setValue(openvdb::Vec3f(0.0f, float(-toward), 0.0f));
        anisotropy->setName("scatter_anisotropy");
        set.put(anisotropy);
        auto sourceAnisotropy = anisotropy->deepCopy();
        sourceAnisotropy->setName("scatter_source_anisotropy");
        set.put(sourceAnisotropy);
        const vxf::Medium medium(set, m);
        vxf::RenderOptions options;
        options.width = options.height = 31;
        options.samples = 1;
        const vxf::RenderedImage image = vxf::render(set, medium, frontView(), options);
        INFO("a toward the camera " << toward);
        const double r = 1.0 + 3.0 * chi[0] * toward + 5.0 * chi[1] * toward * toward + 7.0 * chi[2] * toward * toward * toward;
        CHECK(image.scatter[15 * 31 + 15].x() == Approx(sigmaS * phi * r / (4.0 * M_PI) / sigmaT).epsilon(0.01));
        CHECK(image.direct[15 * 31 + 15].x() == Approx(sigmaS * direct * r / (4.0 * M_PI) / sigmaT).epsilon(0.01));
        // Read in the medium's index space: a grid on other voxels is refused, not misread.
        anisotropy->setTransform(openvdb::math::Transform::createLinearTransform(0.5));
        CHECK_THROWS_WITH(
            vxf::render(set, medium, frontView(), options), "grid 'scatter_anisotropy' does not share the transform of 'density'");
    }
}

TEST_CASE("a volume light: its emission x colour x intensity in J0, and seen along camera rays", "[render][light][volume]")
{
    // A glow of E = 0.5 per unit length (a float grid on its own voxels, as a simulation's
    // flame) in a purely absorbing sphere (σt = 10, chord 2): the camera sees
    // L = E·c·I (1 − e^{−σt d})/σt, and the light stage puts E·c·I in J0 for the passes.
    vxf::test::TempDir dir;
    auto glow = openvdb::FloatGrid::create(0.0f);
    glow->setName("flame");
    glow->setTransform(openvdb::math::Transform::createLinearTransform(0.1));
    glow->tree().fill(openvdb::CoordBBox(openvdb::Coord(-15), openvdb::Coord(15)), 0.5f, true);
    vxf::VoxelSet emitting(glow->transformPtr());
    emitting.put(glow);
    vxf::writeVoxelSet(dir.path("fire.vdb"), emitting);

    vxf::VoxelSet set = litSphere(0.0);
    const vxf::Medium medium(set, vxf::test::greyMaterial(10.0, 0.0));
    vxf::Scene scene = frontView();
    vxf::Light fire;
    fire.type = vxf::Light::Type::Volume;
    fire.name = "fire";
    fire.file = dir.path("fire.vdb");
    fire.grid = "flame";
    fire.color = openvdb::Vec3d(1.0, 0.5, 0.25);
    fire.intensity = 2.0;
    scene.lights.push_back(fire);
    vxf::computeDirectLight(set, medium, scene.lights);
    const openvdb::Vec3f j0 = set.get<openvdb::Vec3SGrid>("scatter_source")->tree().getValue(openvdb::Coord(0));
    CHECK(j0.x() == Approx(1.0));
    CHECK(j0.z() == Approx(0.25));

    vxf::RenderOptions options;
    options.width = options.height = 31;
    options.samples = 1;
    for (const bool marched : {false, true}) { // the direct grid read or the lights marched: emission seen alike
        options.directFromLights = marched;
        const vxf::RenderedImage image = vxf::render(set, medium, scene, options);
        INFO("direct from the lights: " << marched);
        CHECK(image.direct[15 * 31 + 15].x() == Approx(0.5 * 2.0 / 10.0).epsilon(0.01));
        CHECK(image.direct[15 * 31 + 15].z() == Approx(0.5 * 0.5 / 10.0).epsilon(0.01));
    }

    fire.grid = "nope";
    scene.lights = {fire};
    CHECK_THROWS_WITH(vxf::render(set, medium, scene, options), Catch::Contains("light 'fire': no grid 'nope' in " + dir.path("fire.vdb")));
}

TEST_CASE("the render's estimate counts the bytes its grids hold, from the file's metadata as from memory", "[render][memory]")
{
    vxf::VoxelSet set = litSphere(1.0);
    const vxf::RenderOptions options; // reads density, surface and direct (scatter where there is one)
    const std::set<std::string> read = vxf::renderGrids(options);
    std::vector<vxf::GridFootprint> inMemory;
    for (const auto& grid : set.grids())
        if (read.count(grid->getName())) inMemory.push_back(vxf::footprintOf(*grid));
    REQUIRE(inMemory.size() == 3);

    // Declared by the file (OpenVDB's file_mem_bytes and bounding box), its data not read: the same.
    vxf::test::TempDir dir;
    vxf::writeVoxelSet(dir.path("lit.vdb"), set);
    std::vector<vxf::GridFootprint> declared = vxf::declaredFootprints(dir.path("lit.vdb"), read);
    REQUIRE(declared.size() == inMemory.size());
    const auto byName = [](const vxf::GridFootprint& a, const vxf::GridFootprint& b) { return a.name < b.name; };
    std::sort(declared.begin(), declared.end(), byName);
    std::sort(inMemory.begin(), inMemory.end(), byName);
    for (std::size_t g = 0; g < declared.size(); ++g) {
        CAPTURE(declared[g].name);
        CHECK(declared[g].name == inMemory[g].name);
        CHECK(declared[g].bytes == inMemory[g].bytes);
        CHECK(declared[g].denseBytes == inMemory[g].denseBytes);
        CHECK(declared[g].denseBytes > 0.0); // 64³: every copy is made
    }
    // The direct grid banded (its deep leaves as tiles: AdaptiveBand.h): the estimate falls by
    // kRenderBytesPerGridByte times the bytes it no longer holds, the voxel count the same.
    const double before = vxf::renderMemory(inMemory, options).bytes;
    auto& direct = *set.get<openvdb::Vec3SGrid>("direct");
    const openvdb::Index64 voxels = direct.activeVoxelCount();
    const double held = double(direct.tree().memUsage());
    REQUIRE(vxf::coarsenBeyondBand(direct, *set.get<openvdb::FloatGrid>("density"), 0.1).leafTiles > 0);
    CHECK(direct.activeVoxelCount() == voxels);
    const double after = vxf::renderMemory({inMemory[0], vxf::footprintOf(direct), inMemory[2]}, options).bytes;
    const double saved = (held - double(direct.tree().memUsage())) * vxf::kRenderBytesPerGridByte;
    CHECK(inMemory[1].name == "direct");
    CHECK(before - after == Approx(saved).epsilon(1e-9));
    CHECK(saved > 0.0);
}
