#include <vxf/transport/Transmittance.h>

#include <vxf/transport/UniformBricks.h>

#include <vxf/core/ProceduralMesh.h>
#include <vxf/core/RayScene.h>
#include <vxf/io/VoxelSetFile.h>
#include <vxf/voxelize/Voxelize.h>

#include <openvdb/tools/LevelSetSphere.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <functional>
#include <limits>

namespace {

/// A slab of density 1: voxels x in [0, n), |y|, |z| <= 20; voxel size dx.
vxf::VoxelSet slab(int n, double dx)
{
    vxf::VoxelSet set(openvdb::math::Transform::createLinearTransform(dx));
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->setTransform(set.transformPtr());
    density->tree().fill(openvdb::CoordBBox(openvdb::Coord(0, -20, -20), openvdb::Coord(n - 1, 20, 20)), 1.0f, true);
    density->tree().voxelizeActiveTiles();
    set.put(density);
    return set;
}

} // namespace

TEST_CASE("slab transmittance is exp(-sigma_t d)", "[light][transmittance]")
{
    const double dx = 0.05;
    const int n = 20; // d = n dx = 1
    const vxf::VoxelSet set = slab(n, dx);
    for (double sigmaT : {0.1, 1.0, 2.5, 6.0}) {
        const vxf::Medium medium(set, vxf::test::greyMaterial(0.25 * sigmaT, 0.75 * sigmaT));
        vxf::Medium::Sampler sampler(medium);
        // From 10 voxels before to 10 voxels after: the trilinear density integrates to n dx.
        const openvdb::Vec3d t = vxf::transmittance(sampler, medium, openvdb::Vec3d(-10, 0, 0), openvdb::Vec3d(n + 9, 0, 0), {});
        INFO("sigma_t " << sigmaT);
        CHECK(t.x() == Approx(std::exp(-sigmaT * n * dx)).margin(1e-4));
        CHECK(t.x() == t.z());
        // Reversed direction: the same.
        const openvdb::Vec3d back = vxf::transmittance(sampler, medium, openvdb::Vec3d(n + 9, 0, 0), openvdb::Vec3d(-10, 0, 0), {});
        CHECK(back.x() == Approx(t.x()).margin(1e-12));
    }
}

TEST_CASE("a march hands the rest of its way to whoever holds its depth", "[light][transmittance]")
{
    // Through the slab (x in [0, 20) voxels, its density ramping to 0 over the last half voxel)
    // toward +x from x = 2: the hand-off at x = 10 takes the depth from there on (here the
    // exact one, σt·9.5 dx, plus a marker), and the march's own part stops there.
    const double dx = 0.05, sigmaT = 2.0;
    const vxf::VoxelSet set = slab(20, dx);
    const vxf::Medium medium(set, vxf::test::greyMaterial(0.5 * sigmaT, 0.5 * sigmaT));
    vxf::Medium::Sampler sampler(medium);
    const vxf::MarchOptions march{0.5, 1e-12};
    const openvdb::Vec3d from(2.0, 0.0, 0.0), along(1.0, 0.0, 0.0);
    const double whole = vxf::transmittanceToBoundary(sampler, medium, from, along, march).x();
    CHECK(whole == Approx(std::exp(-sigmaT * dx * 17.5)).epsilon(1e-3)); // the density ramps over the last half voxel
    std::vector<double> asked;
    const double marker = 0.25;
    const double handed =
        vxf::transmittanceToBoundary(sampler, medium, from, along, march, [&](const openvdb::Vec3d& at, double, openvdb::Vec3f& depth) {
            asked.push_back(at.x());
            if (at.x() < 10.0 - 1e-9) return false;
            depth = openvdb::Vec3f(float(sigmaT * dx * (19.5 - at.x()) + marker));
            return true;
        }).x();
    // Asked a voxel or more apart (further after a uniform stretch crossed at once), first a
    // voxel along, and taken inside the slab.
    REQUIRE(asked.size() >= 2);
    CHECK(asked.front() == Approx(3.0));
    for (std::size_t i = 1; i < asked.size(); ++i) CHECK(asked[i] - asked[i - 1] >= 1.0 - 1e-9);
    CHECK(asked.back() >= 10.0);
    CHECK(asked.back() < 19.5);
    CHECK(handed == Approx(whole * std::exp(-marker)).epsilon(1e-4));
    // Never taken: the march itself, to the bit.
    const double declined =
        vxf::transmittanceToBoundary(sampler, medium, from, along, march, [](const openvdb::Vec3d&, double, openvdb::Vec3f&) {
            return false;
        }).x();
    CHECK(declined == whole);
}

TEST_CASE("transmittance stays finite and in [0,1] at extreme coefficients", "[light][transmittance][stability]")
{
    const vxf::VoxelSet set = slab(20, 0.05);
    for (double sigmaT : {0.0, 1e-6, 1e6}) {
        const vxf::Medium medium(set, vxf::test::greyMaterial(sigmaT, 0.0));
        vxf::Medium::Sampler sampler(medium);
        const openvdb::Vec3d t = vxf::transmittance(sampler, medium, openvdb::Vec3d(-10, 0, 0), openvdb::Vec3d(30, 0, 0), {});
        INFO("sigma_t " << sigmaT);
        CHECK(std::isfinite(t.x()));
        CHECK(t.x() >= 0.0);
        CHECK(t.x() <= 1.0);
        if (sigmaT == 0.0) CHECK(t.x() == 1.0);
        if (sigmaT == 1e-6) CHECK(t.x() == Approx(std::exp(-1e-6)).epsilon(1e-9));
        if (sigmaT == 1e6) CHECK(t.x() == 0.0);
    }
    // Outside the medium entirely, and a zero-length segment.
    const vxf::Medium medium(set, vxf::test::greyMaterial(1.0, 1.0));
    vxf::Medium::Sampler sampler(medium);
    CHECK(vxf::transmittance(sampler, medium, openvdb::Vec3d(-50, 0, 0), openvdb::Vec3d(-40, 5, 0), {}) == openvdb::Vec3d(1.0));
    CHECK(vxf::transmittance(sampler, medium, openvdb::Vec3d(3, 0, 0), openvdb::Vec3d(3, 0, 0), {}) == openvdb::Vec3d(1.0));
}

TEST_CASE("negative artist coefficients never amplify light", "[light][transmittance][stability]")
{
    vxf::VoxelSet set = slab(20, 0.05);
    auto sigmaA = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    sigmaA->setName("sigma_a");
    sigmaA->setTransform(set.transformPtr());
    sigmaA->tree().fill(
        openvdb::CoordBBox(openvdb::Coord(0, -20, -20), openvdb::Coord(19, 20, 20)), openvdb::Vec3f(-5.0f, 1.0f, 0.0f), true);
    set.put(sigmaA);
    const vxf::Medium medium(set, vxf::test::greyMaterial(0.0, 0.0));
    vxf::Medium::Sampler sampler(medium);
    const openvdb::Vec3d t = vxf::transmittance(sampler, medium, openvdb::Vec3d(-10, 0, 0), openvdb::Vec3d(29, 0, 0), {});
    CHECK(t.x() == 1.0); // sigma_t < 0 counts as 0
    CHECK(t.y() == Approx(std::exp(-1.0)).margin(1e-4));
    CHECK(t.z() == 1.0);
}

TEST_CASE("transmittance to the boundary through a concave gap counts only the medium", "[light][transmittance]")
{
    // Two slabs of 10 voxels with a 20-voxel gap between them: the gap adds nothing.
    vxf::VoxelSet set(openvdb::math::Transform::createLinearTransform(0.1));
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->setTransform(set.transformPtr());
    density->tree().fill(openvdb::CoordBBox(openvdb::Coord(0, -8, -8), openvdb::Coord(9, 8, 8)), 1.0f, true);
    density->tree().fill(openvdb::CoordBBox(openvdb::Coord(30, -8, -8), openvdb::Coord(39, 8, 8)), 1.0f, true);
    set.put(density);
    const vxf::Medium medium(set, vxf::test::greyMaterial(1.0, 0.0));
    vxf::Medium::Sampler sampler(medium);
    // From the centre of voxel 5 toward +x: centres 5..9 (4 voxels) + the half-voxel ramp out,
    // then the second slab: ramp in + centres 30..39 + ramp out = 10 voxels. The gap adds 0.
    const double expected = std::exp(-1.0 * 0.1 * (4.0 + 0.5 + 10.0));
    const openvdb::Vec3d t = vxf::transmittanceToBoundary(sampler, medium, openvdb::Vec3d(5, 0, 0), openvdb::Vec3d(1, 0, 0), {});
    CHECK(t.x() == Approx(expected).margin(1e-4));
}

TEST_CASE("grazing chords through a sphere keep their length", "[light][transmittance]")
{
    // A sphere of 10 voxels' radius, chords from 1 down to 0.1 voxel under its silhouette,
    // marched at whole-voxel steps (the render's and the scatter's) and at 3 voxels, where the
    // shortest chords (2.8 voxels) lie between two step ends outside. Along a grazing ray the
    // signed distance is a parabola: the trilinear level set (convex where the surface is)
    // lies inside the sphere by up to dx²/8R, and the line between step ends shortens the
    // chord again: 7.5% and 4% short at 0.1 voxel deep before the level set was read
    // triquadratically and the crossings found on it.
    const double radius = 1.0, dx = 0.1, sigmaT = 4.0;
    vxf::VoxelizeOptions options;
    options.voxelSize = dx;
    const vxf::VoxelSet set = vxf::voxelize(vxf::makeSphere(openvdb::Vec3d(0.0), radius, 128, 256), options);
    const vxf::Medium medium(set, vxf::test::greyMaterial(sigmaT, 0.0));
    vxf::Medium::Sampler sampler(medium);
    for (double step : {1.0, 3.0}) {
        for (double b : {0.9, 0.95, 0.98, 0.99}) {
            const double exact = sigmaT * 2.0 * std::sqrt(radius * radius - b * b);
            for (double start : {-1.0, -1.03, -1.07}) { // the steps' phase along the chord
                const openvdb::Vec3d from(start, b * 0.8, b * 0.6), to(start + 2.0, b * 0.8, b * 0.6);
                const double tau = -std::log(vxf::transmittance(sampler, medium, from / dx, to / dx, {step, 1e-12}).x());
                INFO("step " << step << ", offset " << b << ", start " << start << ": tau " << tau << ", exact " << exact);
                CHECK(tau == Approx(exact).epsilon(0.01));
            }
        }
    }
}

TEST_CASE("through a voxelized sphere, transmittance follows the exact surface", "[light][transmittance]")
{
    // Sphere of radius 1 at voxel size 0.1 (σt·dx = 0.4): a voxel's volume fraction read
    // trilinearly smears the boundary over a voxel; with the `surface` level set the medium
    // ends where the mesh does, so chords and depths below a voxel come out right.
    const double radius = 1.0, dx = 0.1, sigmaT = 4.0;
    vxf::VoxelizeOptions options;
    options.voxelSize = dx;
    const vxf::VoxelSet set = vxf::voxelize(vxf::makeSphere(openvdb::Vec3d(0.0), radius, 128, 256), options);
    const vxf::Medium medium(set, vxf::test::greyMaterial(sigmaT, 0.0));
    REQUIRE(medium.surface() != nullptr);
    vxf::Medium::Sampler sampler(medium);
    const auto tau = [&](const openvdb::Vec3d& from, const openvdb::Vec3d& to) {
        const openvdb::Vec3d t = vxf::transmittance(sampler, medium, from / dx, to / dx, {0.5, 1e-12});
        return -std::log(t.x());
    };
    // Chords at offsets b from the centre, down to grazing: optical depth σt·2√(1 − b²).
    for (double b : {0.0, 0.5, 0.8, 0.95}) {
        const double chord = 2.0 * std::sqrt(radius * radius - b * b);
        INFO("offset " << b);
        CHECK(tau(openvdb::Vec3d(-2.0, b, 0.013), openvdb::Vec3d(2.0, b, 0.013)) == Approx(sigmaT * chord).epsilon(0.02));
    }
    // From a point a fraction of a voxel under the surface straight out: σt·depth.
    const openvdb::Vec3d out = openvdb::Vec3d(1.0, 0.7, 0.4).unit();
    for (double depth : {0.02, 0.05, 0.1, 0.3}) {
        INFO("depth " << depth);
        CHECK(tau(out * (radius - depth), out * 2.0) == Approx(sigmaT * depth).epsilon(0.1));
    }
}

TEST_CASE("with the mesh, grazing shadow rays cross the surface where the mesh does", "[light][transmittance]")
{
    // A coarse polyhedral sphere (8 rings, 16 segments: facets 5 voxels across, edges where
    // the distance to it is not smooth). Light leaving from points under a facet at a grazing
    // angle crosses a chord whose length changes by 4R/c for a change of depth: the level set
    // alone, a few thousandths of a voxel off the facets, misplaces where such rays leave.
    // With the mesh (Medium::Sampler::snapCrossingsTo) the optical depth is the mesh's own
    // chord, from Embree, to 0.1%.
    const double dx = 0.05, sigmaT = 20.0;
    const vxf::TriangleMesh mesh = vxf::makeSphere(openvdb::Vec3d(0.0), 1.0, 8, 16);
    vxf::VoxelizeOptions options;
    options.voxelSize = dx;
    const vxf::VoxelSet set = vxf::voxelize(mesh, options);
    const vxf::Medium medium(set, vxf::test::greyMaterial(sigmaT, 0.0));
    vxf::RayScene boundary;
    boundary.add(mesh, 0);
    boundary.commit();
    vxf::Medium::Sampler levelSet(medium), snapped(medium), placedOnly(medium);
    snapped.snapCrossingsTo(&boundary);
    // The light stage's: the crossings the level set finds placed on the mesh, no ray asked for
    // one it missed within a step. Rays that climb out at 1 in 50 from 0.2 voxels under a facet
    // keep the level set's inside a step past the mesh's exit: 0.4% of their depth over.
    placedOnly.snapCrossingsTo(&boundary, vxf::Medium::Sampler::MissedCrossings::Ignored);
    double worstLevelSet = 0.0, worstSnapped = 0.0, worstPlaced = 0.0;
    int rays = 0;
    for (std::size_t t = 0; t < mesh.triangles.size(); t += 7) {
        const auto& tri = mesh.triangles[t];
        const openvdb::Vec3d a = mesh.points[tri[0]], b = mesh.points[tri[1]], c = mesh.points[tri[2]];
        openvdb::Vec3d n = (b - a).cross(c - a);
        if (!(n.length() > 1e-9)) continue;
        n.normalize();
        const openvdb::Vec3d centre = (a + b + c) / 3.0;
        const openvdb::Vec3d along = (b - a).unit(); // in the facet's plane
        for (double depth : {0.2, 0.5, 1.0}) { // voxels under the facet
            for (double rise : {0.02, 0.05, 0.1}) { // the ray's climb per unit length: grazing
                const openvdb::Vec3d from = centre - n * (depth * dx);
                const openvdb::Vec3d dir = (along + n * rise).unit();
                const auto exit = boundary.intersect(from, dir);
                REQUIRE(exit);
                const double exact = sigmaT * exit->distance;
                if (exact > 12.0) continue; // the light that matters
                const openvdb::Vec3d to = (from + dir * 4.0) / dx;
                const double plain = -std::log(vxf::transmittance(levelSet, medium, from / dx, to, {1.0, 1e-12}).x());
                const double onMesh = -std::log(vxf::transmittance(snapped, medium, from / dx, to, {1.0, 1e-12}).x());
                const double placed = -std::log(vxf::transmittance(placedOnly, medium, from / dx, to, {1.0, 1e-12}).x());
                worstLevelSet = std::max(worstLevelSet, std::abs(plain - exact));
                worstSnapped = std::max(worstSnapped, std::abs(onMesh - exact));
                worstPlaced = std::max(worstPlaced, std::abs(placed - exact));
                INFO("triangle " << t << ", depth " << depth << ", rise " << rise << ": exact " << exact << ", level set " << plain);
                CHECK(onMesh == Approx(exact).epsilon(1e-3).margin(1e-4));
                CHECK(placed == Approx(exact).epsilon(5e-3).margin(1e-4));
                ++rays;
            }
        }
    }
    INFO("worst optical depth error: level set " << worstLevelSet << ", with the mesh " << worstSnapped << ", placed only " << worstPlaced);
    CHECK(rays > 100);
    CHECK(worstSnapped < 0.1 * worstLevelSet);
    CHECK(worstPlaced < 0.1 * worstLevelSet);
    // Asked directly: a ray out through the sphere meets the mesh, unless missed crossings are ignored.
    double t = 0.0;
    bool entering = true;
    const openvdb::Vec3d centre(0.0), out(1.0, 0.0, 0.0);
    CHECK(snapped.boundaryHit(centre, out, 0.0, 2.0 / dx, t, entering));
    CHECK(t * dx == Approx(1.0).epsilon(0.02));
    CHECK_FALSE(entering);
    CHECK_FALSE(placedOnly.boundaryHit(centre, out, 0.0, 2.0 / dx, t, entering));
}

TEST_CASE("thin sheets keep their optical depth", "[light][transmittance]")
{
    // A flat sheet t voxels thick, starting between voxel centres or just before one. Where no
    // voxel centre or only one lies inside, the level set cannot place both faces (its zero
    // crossing between centres is first-order across a feature this thin), so the medium keeps
    // the voxels' volume fractions there (soft edge) instead of vanishing behind the sharp
    // boundary, which lost all of a half-voxel sheet and a fifth of a one-voxel one.
    const double dx = 0.1, sigmaT = 1.0;
    for (double x0 : {0.03, -0.005}) {
        for (double t : {0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0}) {
            vxf::VoxelizeOptions options;
            options.voxelSize = dx;
            const vxf::VoxelSet set = vxf::voxelize(vxf::makeBox({x0, -1.0, -1.0}, {x0 + t * dx, 1.0, 1.0}), options);
            const vxf::Medium medium(set, vxf::test::greyMaterial(sigmaT, 0.0));
            vxf::Medium::Sampler sampler(medium);
            for (double angle : {0.0, 30.0}) {
                const double c = std::cos(angle * M_PI / 180.0), s = std::sin(angle * M_PI / 180.0);
                const openvdb::Vec3d from(-0.5, -0.5 * s / c + 0.013, 0.027), to(0.5, 0.5 * s / c + 0.013, 0.027);
                const double tau = -std::log(vxf::transmittance(sampler, medium, from / dx, to / dx, {0.5, 1e-12}).x());
                const double exact = sigmaT * t * dx / c;
                INFO("start " << x0 << ", thickness " << t << " voxels, angle " << angle << ": tau " << tau << ", exact " << exact);
                if (t >= 1.0) {
                    CHECK(tau == Approx(exact).epsilon(0.05));
                } else {
                    // A voxel's fraction clamp(½ − φ/dx) sees one face: exact when no voxel centre
                    // lies inside the sheet, up to half a voxel of medium over when one does.
                    CHECK(tau >= 0.95 * exact);
                    CHECK(tau <= exact + 0.5 * sigmaT * dx / c + 1e-6);
                }
            }
        }
    }
}

TEST_CASE("marches cross uniform regions in one go with the same optical depth", "[light][transmittance]")
{
    // A sphere 20 voxels in radius: inside its surface band the density is 1 in tiles, outside
    // nothing. The same medium given as per-voxel sigma grids has no UniformBricks table, so its
    // marches take every step: the two must agree to rounding along any ray.
    const double radius = 1.0, dx = 0.05, sigmaA = 1.0, sigmaS = 3.0;
    vxf::VoxelizeOptions options;
    options.voxelSize = dx;
    vxf::VoxelSet set = vxf::voxelize(vxf::makeSphere(openvdb::Vec3d(0.0), radius, 96, 192), options);
    const vxf::Medium medium(set, vxf::test::greyMaterial(sigmaA, sigmaS));
    const vxf::UniformBricks* uniform = medium.uniformBricks();
    REQUIRE(uniform != nullptr);
    CHECK(uniform->uniformBrickCount() > 0);
    openvdb::Vec3d lo, hi;
    float density = -1.0f;
    CHECK(uniform->find(openvdb::Vec3d(0.3), 0.5, lo, hi, density)); // the centre: inside
    CHECK(density == 1.0f);
    CHECK(uniform->find(openvdb::Vec3d(0.8 * radius / dx), 0.5, lo, hi, density)); // the bounds' corner, beyond the surface: outside
    CHECK(density == 0.0f);
    CHECK_FALSE(uniform->find(openvdb::Vec3d(radius / dx, 0.2, 0.1), 0.5, lo, hi, density)); // on it: neither

    vxf::VoxelSet grids = set;
    const auto& d = *set.get<openvdb::FloatGrid>("density");
    for (const auto& [name, sigma] : {std::pair<const char*, double>{"sigma_a", sigmaA}, {"sigma_s", sigmaS}}) {
        auto grid = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
        grid->setName(name);
        grid->setTransform(d.transformPtr()->copy());
        grid->tree().topologyUnion(d.tree());
        for (auto it = grid->tree().beginValueOn(); it; ++it) it.setValue(openvdb::Vec3f(float(sigma * d.tree().getValue(it.getCoord()))));
        grids.put(grid);
    }
    const vxf::Medium stepped(grids, vxf::test::greyMaterial(0.0, 0.0));
    REQUIRE(stepped.uniformBricks() == nullptr);
    vxf::Medium::Sampler a(medium), b(stepped);
    for (double step : {0.5, 1.0, 3.0}) {
        for (const openvdb::Vec3d& direction :
            {openvdb::Vec3d(1, 0, 0), openvdb::Vec3d(1, 0.7, 0.4).unit(), openvdb::Vec3d(-0.2, 1, -0.9).unit()}) {
            for (const auto& [from, to] : {std::pair{openvdb::Vec3d(0.013), direction * 2.0}, // centre to outside
                     std::pair{-direction * 2.0 + openvdb::Vec3d(0.1), direction * 2.0}, // a chord
                     std::pair{direction * 0.97, -direction * 0.5}}) { // from under the surface inwards
                const vxf::MarchOptions march{step, 0.0};
                const double one = -std::log(vxf::transmittance(a, medium, from / dx, to / dx, march).x());
                const double other = -std::log(vxf::transmittance(b, stepped, from / dx, to / dx, march).x());
                INFO("step " << step << ", from " << from << " to " << to);
                CHECK(one > 0.0);
                CHECK(one == Approx(other).epsilon(1e-6));
            }
        }
    }
}

TEST_CASE("a grid too large for a dense copy: marches cross its tree's empty nodes and tiles in one go", "[light][transmittance][volume]")
{
    // Two puffs 4000 voxels apart along each axis (a box of 6.4e10 voxels: no dense copy): a
    // 16³ block of density 1 held as tiles, and a 16³ block whose density varies (leaf voxels).
    // The regions are the tree's (its tiles, and the background between its nodes), and the
    // optical depth along rays through both is the same, to rounding, as the same medium's
    // given as sigma grids, whose marches take every step.
    const double dx = 0.1, sigmaA = 0.5, sigmaS = 1.5;
    vxf::VoxelSet set(openvdb::math::Transform::createLinearTransform(dx));
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->setTransform(set.transformPtr());
    density->tree().fill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(15)), 1.0f, true);
    const openvdb::Coord far(4000);
    for (auto ijk = openvdb::CoordBBox(far, far.offsetBy(15)).begin(); ijk; ++ijk) {
        density->tree().setValueOn(*ijk, 0.5f + 0.03f * float(((*ijk)[0] + 2 * (*ijk)[1] + 3 * (*ijk)[2]) % 17));
    }
    set.put(density);
    const vxf::Medium medium(set, vxf::test::greyMaterial(sigmaA, sigmaS));
    const vxf::UniformBricks* uniform = medium.uniformBricks();
    REQUIRE(uniform != nullptr);
    openvdb::Vec3d lo, hi;
    float value = -1.0f;
    CHECK(uniform->find(openvdb::Vec3d(2000.5), 1.0, lo, hi, value)); // between the puffs: the background
    CHECK(value == 0.0f);
    CHECK(hi[0] - lo[0] >= 126.0); // a node of 128³ or more, less a voxel at either face
    CHECK(uniform->find(openvdb::Vec3d(3.5, 4.2, 2.9), 1.0, lo, hi, value)); // inside a tile of the first puff
    CHECK(value == 1.0f);
    CHECK_FALSE(uniform->find(openvdb::Vec3d(7.5, 4.2, 2.9), 1.0, lo, hi, value)); // a voxel from its face: reads the next tile
    CHECK_FALSE(uniform->find(far.asVec3d() + openvdb::Vec3d(4.5), 1.0, lo, hi, value)); // the second puff's voxels

    vxf::VoxelSet grids = set;
    for (const auto& [name, sigma] : {std::pair<const char*, double>{"sigma_a", sigmaA}, {"sigma_s", sigmaS}}) {
        auto grid = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
        grid->setName(name);
        grid->setTransform(density->transformPtr()->copy());
        grid->tree().topologyUnion(density->tree());
        grid->tree().voxelizeActiveTiles();
        for (auto it = grid->tree().beginValueOn(); it; ++it)
            it.setValue(openvdb::Vec3f(float(sigma * density->tree().getValue(it.getCoord()))));
        grids.put(grid);
    }
    const vxf::Medium stepped(grids, vxf::test::greyMaterial(0.0, 0.0));
    REQUIRE(stepped.uniformBricks() == nullptr);
    vxf::Medium::Sampler a(medium), b(stepped);
    for (const openvdb::Vec3d& aim : {openvdb::Vec3d(0.0), openvdb::Vec3d(0.3, -0.2, 0.1), openvdb::Vec3d(-0.4, 0.5, 0.2)}) {
        const openvdb::Vec3d from = openvdb::Vec3d(-20.0) + aim, to = far.asVec3d() + openvdb::Vec3d(40.0) - aim;
        const vxf::MarchOptions march{1.0, 0.0};
        const double one = -std::log(vxf::transmittance(a, medium, from, to, march).x());
        const double other = -std::log(vxf::transmittance(b, stepped, from, to, march).x());
        INFO("from " << from << " to " << to);
        CHECK(one > 1.0);
        CHECK(one == Approx(other).epsilon(1e-6));
    }
}

TEST_CASE("a surface on another lattice is refused by name", "[light][transmittance]")
{
    // Files may hold grids on other transforms (kept as read); the sharp boundary needs the
    // surface on the density's lattice.
    vxf::test::TempDir dir;
    auto density = openvdb::createGrid<openvdb::FloatGrid>(0.0f);
    density->setName("density");
    density->setTransform(openvdb::math::Transform::createLinearTransform(0.1));
    density->tree().setValueOn(openvdb::Coord(0), 1.0f);
    auto surface = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(1.0f, openvdb::Vec3f(0.0f), 0.2f);
    surface->setName("surface");
    openvdb::io::File(dir.path("mixed.vdb")).write({density, surface});
    const vxf::VoxelSet set = vxf::readVoxelSet(dir.path("mixed.vdb"));
    CHECK_THROWS_WITH(
        vxf::Medium(set, vxf::test::greyMaterial(1.0, 0.0)), Catch::Contains("grid 'surface' does not share the transform of 'density'"));
}

TEST_CASE("a step's emission integral is exact for quadratic emission", "[light][transmittance]")
{
    // ∫_0^h J(s) e^{−σt s} ds by a fine midpoint sum, for comparison.
    const auto numeric = [](const std::function<double(double)>& J, double sigmaT, double h) {
        const int n = 200000;
        double sum = 0.0;
        for (int i = 0; i < n; ++i) {
            const double s = (i + 0.5) * h / n;
            sum += J(s) * std::exp(-sigmaT * s);
        }
        return sum * h / n;
    };
    SECTION("Simpson's rule without extinction")
    {
        const vxf::EmissionWeights w = vxf::emissionWeights(0.0, 0.6);
        CHECK(w.start == Approx(0.1));
        CHECK(w.middle == Approx(0.4));
        CHECK(w.end == Approx(0.1));
        CHECK(w.total == Approx(0.6));
    }
    SECTION("a quadratic J at optical depths across the series/closed-form switch")
    {
        const double h = 0.5;
        const auto J = [h](double s) { return 2.0 - 3.0 * (s / h) + 4.0 * (s / h) * (s / h); };
        for (double k : {1e-6, 0.01, 0.3, 0.499, 0.501, 2.0, 30.0}) {
            const double sigmaT = k / h;
            const vxf::EmissionWeights w = vxf::emissionWeights(sigmaT, h);
            INFO("sigma_t h = " << k);
            CHECK(w.start * J(0.0) + w.middle * J(0.5 * h) + w.end * J(h) == Approx(numeric(J, sigmaT, h)).epsilon(1e-8));
            CHECK(w.total == Approx(-std::expm1(-k) / sigmaT).epsilon(1e-12));
            CHECK(w.transmittance == Approx(std::exp(-k)).epsilon(1e-15));
        }
    }
    SECTION("per channel: each channel's own weights")
    {
        const auto w = vxf::emissionWeights(openvdb::Vec3d(2.0, 2.0, 0.3), 0.5);
        for (int c = 0; c < 3; ++c) {
            const vxf::EmissionWeights one = vxf::emissionWeights(c < 2 ? 2.0 : 0.3, 0.5);
            CHECK(w[c].start == one.start);
            CHECK(w[c].middle == one.middle);
            CHECK(w[c].end == one.end);
            CHECK(w[c].transmittance == one.transmittance);
        }
    }
    SECTION("light falling off over a mean free path: the midpoint value alone is 7% low")
    {
        const double sigmaT = 1.0, h = 0.77;
        const auto J = [sigmaT](double s) { return std::exp(-sigmaT * s); };
        const double exact = numeric(J, sigmaT, h);
        const vxf::EmissionWeights w = vxf::emissionWeights(sigmaT, h);
        CHECK(vxf::emissionIntegral(w, J(0.0), J(0.5 * h), J(h)) == Approx(exact).epsilon(1e-3));
        CHECK(J(0.5 * h) * w.total < 0.94 * exact);
    }
    SECTION("extreme extinction stays finite and between J's bounds")
    {
        for (double sigmaT : {1e6, 1e300, std::numeric_limits<double>::infinity()}) {
            const vxf::EmissionWeights w = vxf::emissionWeights(sigmaT, 0.1);
            const double v = vxf::emissionIntegral(w, 0.0, 5.0, 100.0);
            INFO("sigma_t " << sigmaT);
            CHECK(std::isfinite(v));
            CHECK(v >= 0.0);
            CHECK(v <= 100.0 * w.total);
        }
        // An overshooting quadratic (J jumps at the end of a thick step) is kept in bounds.
        const vxf::EmissionWeights thick = vxf::emissionWeights(50.0, 1.0);
        CHECK(vxf::emissionIntegral(thick, 0.0, 0.0, 1.0) >= 0.0);
    }
}
