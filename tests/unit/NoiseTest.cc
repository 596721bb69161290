#include <vxf/ops/Noise.h>

#include <vxf/core/Error.h>

#include <catch2/catch.hpp>

#include <cmath>

TEST_CASE("noise: smooth, bounded, seeded, shifted, not 0 on voxels, and applied as set, add or multiply", "[ops]")
{
    vxf::ops::NoiseOptions one;
    one.octaves = 1;
    one.frequency = 1.0;
    // Smooth (a small step, a small change), and not 0 on whole coordinates (a grid of voxel
    // size 1/frequency would otherwise sit on gradient noise's zeros).
    const openvdb::Vec3d at(3, -2, 7);
    CHECK(vxf::ops::fractalNoise(at, one, 0) != 0.0);
    CHECK(std::abs(vxf::ops::fractalNoise(at, one, 0) - vxf::ops::fractalNoise(at + openvdb::Vec3d(1e-4), one, 0)) < 1e-3);
    double lo = 0.0, hi = 0.0, sum = 0.0;
    int n = 0;
    for (int i = 0; i < 4000; ++i) {
        const openvdb::Vec3d x(0.37 * i, 0.11 * i + 0.5, -0.23 * i + 0.25);
        const double v = vxf::ops::fractalNoise(x, vxf::ops::NoiseOptions{}, 7);
        lo = std::min(lo, v);
        hi = std::max(hi, v);
        sum += v;
        ++n;
    }
    CHECK(lo >= -1.0);
    CHECK(hi <= 1.0);
    CHECK(hi - lo > 0.5); // it varies
    CHECK(std::abs(sum / n) < 0.05); // about zero on average
    // Seeds give other patterns; a shift moves the pattern.
    const openvdb::Vec3d x(0.3, 0.6, 0.9);
    CHECK(vxf::ops::fractalNoise(x, one, 1) != vxf::ops::fractalNoise(x, one, 2));
    vxf::ops::NoiseOptions shifted = one;
    shifted.shift = openvdb::Vec3d(0.5, 0.0, 0.0);
    CHECK(vxf::ops::fractalNoise(x, shifted, 3) == vxf::ops::fractalNoise(x + openvdb::Vec3d(0.5, 0, 0), one, 3));

    auto g = openvdb::FloatGrid::create(0.0f);
    g->setTransform(openvdb::math::Transform::createLinearTransform(0.05));
    g->tree().fill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(15)), 2.0f, true); // a tile, voxelized by the noise
    vxf::ops::NoiseOptions o;
    o.mode = vxf::ops::NoiseMode::Multiply;
    o.offset = 1.0;
    o.amplitude = 0.5;
    o.seed = 11;
    auto times = g->deepCopy();
    vxf::ops::noise(*times, o);
    std::size_t changed = 0;
    for (auto it = times->cbeginValueOn(); it; ++it) {
        const double n = vxf::ops::fractalNoise(times->transform().indexToWorld(it.getCoord()), o, 11);
        REQUIRE(*it == Approx(2.0 * (1.0 + 0.5 * n)).epsilon(1e-6));
        changed += *it != 2.0f ? 1 : 0;
    }
    CHECK(changed > 1000);
    CHECK(times->activeVoxelCount() == 16 * 16 * 16);
    // On a selection only.
    auto selection = openvdb::BoolGrid::create(false);
    selection->setTransform(g->transformPtr());
    selection->tree().setValueOn(openvdb::Coord(3, 4, 5), true);
    auto some = g->deepCopy();
    o.mode = vxf::ops::NoiseMode::Set;
    vxf::ops::noise(*some, o, selection.get());
    CHECK(some->tree().getValue(openvdb::Coord(3, 4, 5)) ==
        Approx(1.0 + 0.5 * vxf::ops::fractalNoise(some->transform().indexToWorld(openvdb::Coord(3, 4, 5)), o, 11)));
    CHECK(some->tree().getValue(openvdb::Coord(3, 4, 6)) == 2.0f);
    // Colours: the same noise on every channel unless per channel.
    auto c = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    c->tree().setValueOn(openvdb::Coord(1, 2, 3), openvdb::Vec3f(1.0f));
    o.perChannel = false;
    vxf::ops::noise(*c, o);
    const openvdb::Vec3f v = c->tree().getValue(openvdb::Coord(1, 2, 3));
    CHECK((v[0] == v[1] && v[1] == v[2]));
    o.frequency = 0.0;
    CHECK_THROWS_WITH(vxf::ops::noise(*g, o), Catch::Contains("frequency"));
}
