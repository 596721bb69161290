#include <vxf/ops/Normalize.h>

#include <vxf/core/Error.h>

#include <catch2/catch.hpp>

#include <random>

TEST_CASE("normalize maps to [0, 1] and denormalize restores every value bit for bit", "[ops]")
{
    std::mt19937 random(7);
    std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
    for (const double range : {1.0, 37.5, 1e-20, 3e30}) {
        auto g = openvdb::Vec3SGrid::create();
        std::vector<std::pair<openvdb::Coord, openvdb::Vec3f>> values;
        for (int i = 0; i < 2000; ++i) {
            const openvdb::Coord c(i % 13, i / 13 % 17, i / 221);
            const openvdb::Vec3f v(float(uniform(random) * range), float(uniform(random) * range * 0.5), 0.0f);
            g->tree().setValueOn(c, v);
            values.emplace_back(c, v);
        }
        vxf::ops::normalize(*g);
        float hi = 0.0f, lo = 1.0f;
        for (auto it = g->cbeginValueOn(); it; ++it) {
            for (int c = 0; c < 3; ++c) {
                hi = std::max(hi, (*it)[c]);
                lo = std::min(lo, (*it)[c]);
            }
        }
        INFO("range " << range);
        CHECK(hi > 0.5f);
        CHECK(hi <= 1.0f);
        CHECK(lo >= 0.0f);
        vxf::ops::denormalize(*g);
        int exact = 0;
        for (const auto& [c, v] : values) exact += g->tree().getValue(c) == v ? 1 : 0;
        CHECK(exact == int(values.size()));
        CHECK_FALSE(g->getMetadata<openvdb::DoubleMetadata>(vxf::ops::kNormalizeScaleKey));
    }
}

TEST_CASE("normalize without the exact scale puts the maximum on 1", "[ops]")
{
    auto g = openvdb::FloatGrid::create(0.0f);
    g->tree().setValueOn(openvdb::Coord(0), 0.3f);
    g->tree().setValueOn(openvdb::Coord(1), 3.7f);
    vxf::ops::NormalizeOptions o;
    o.exact = false;
    vxf::ops::normalize(*g, o);
    CHECK(g->tree().getValue(openvdb::Coord(1)) == 1.0f);
    vxf::ops::denormalize(*g);
    CHECK(g->tree().getValue(openvdb::Coord(0)) == Approx(0.3f).epsilon(1e-7));
}

TEST_CASE("normalize: negatives give an offset or are clamped, all-zero grids stay finite", "[ops][stability]")
{
    auto g = openvdb::FloatGrid::create(0.0f);
    g->tree().setValueOn(openvdb::Coord(0), -2.0f);
    g->tree().setValueOn(openvdb::Coord(1), 6.0f);
    vxf::ops::normalize(*g); // offset −2, range 8 (a power of two already)
    CHECK(g->tree().getValue(openvdb::Coord(0)) == 0.0f);
    CHECK(g->tree().getValue(openvdb::Coord(1)) == 1.0f);
    vxf::ops::denormalize(*g);
    CHECK(g->tree().getValue(openvdb::Coord(0)) == -2.0f);

    vxf::ops::NormalizeOptions clamp;
    clamp.clampNegatives = true;
    vxf::ops::normalize(*g, clamp);
    CHECK(g->tree().getValue(openvdb::Coord(0)) == 0.0f);
    CHECK(g->metaValue<double>(vxf::ops::kNormalizeOffsetKey) == 0.0);

    auto zero = openvdb::FloatGrid::create(0.0f);
    zero->tree().setValueOn(openvdb::Coord(3), 0.0f);
    vxf::ops::normalize(*zero);
    CHECK(zero->tree().getValue(openvdb::Coord(3)) == 0.0f);
    CHECK(zero->metaValue<double>(vxf::ops::kNormalizeScaleKey) == 1.0);
    CHECK_THROWS_WITH(vxf::ops::denormalize(*openvdb::FloatGrid::create()), Catch::Contains("normalize it first"));
}
