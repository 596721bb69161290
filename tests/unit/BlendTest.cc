#include <vxf/ops/Blend.h>

#include <vxf/core/Error.h>

#include <catch2/catch.hpp>

namespace {
openvdb::FloatGrid::Ptr grid(std::initializer_list<std::pair<openvdb::Coord, float>> values)
{
    auto g = openvdb::FloatGrid::create(0.0f);
    for (const auto& [c, v] : values) g->tree().setValueOn(c, v);
    return g;
}
} // namespace

TEST_CASE("blend: every mode per voxel, the union of active voxels, B untouched", "[ops]")
{
    const openvdb::Coord both(0), onlyA(1, 0, 0), onlyB(2, 0, 0);
    const auto run = [&](vxf::ops::BlendMode mode, double weight = 0.5, bool clamp = false, bool normalize = false) {
        auto a = grid({{both, 2.0f}, {onlyA, -1.0f}});
        auto b = grid({{both, 4.0f}, {onlyB, 3.0f}});
        vxf::ops::BlendOptions o;
        o.mode = mode;
        o.weight = weight;
        o.clampNegatives = clamp;
        o.normalizeB = normalize;
        vxf::ops::blend(*a, *b, o);
        CHECK(b->tree().getValue(both) == 4.0f);
        CHECK(a->tree().isValueOn(onlyB));
        CHECK(a->activeVoxelCount() == 3);
        return std::array<float, 3>{a->tree().getValue(both), a->tree().getValue(onlyA), a->tree().getValue(onlyB)};
    };
    using M = vxf::ops::BlendMode;
    CHECK(run(M::Add) == std::array<float, 3>{6.0f, -1.0f, 3.0f});
    CHECK(run(M::Subtract) == std::array<float, 3>{-2.0f, -1.0f, -3.0f});
    CHECK(run(M::Multiply) == std::array<float, 3>{8.0f, -0.0f, 0.0f});
    CHECK(run(M::Darker) == std::array<float, 3>{2.0f, -1.0f, 0.0f});
    CHECK(run(M::Lighter) == std::array<float, 3>{4.0f, 0.0f, 3.0f});
    CHECK(run(M::Mix, 0.25) == std::array<float, 3>{2.5f, -0.75f, 0.75f});
    CHECK(run(M::Add, 0.5, true) == std::array<float, 3>{6.0f, 0.0f, 3.0f});
    CHECK(run(M::Add, 0.5, false, true) == std::array<float, 3>{3.0f, -1.0f, 0.75f}); // B / 4

    auto a = grid({{both, 1.0f}});
    auto other = grid({{both, 1.0f}});
    other->setTransform(openvdb::math::Transform::createLinearTransform(2.0));
    CHECK_THROWS_WITH(vxf::ops::blend(*a, *other, {}), Catch::Contains("different transforms"));
    auto resampled = vxf::ops::resampleLike(*other, *a);
    CHECK(resampled->transform() == a->transform());
    CHECK_THROWS_AS(vxf::ops::blend(*a, *openvdb::Vec3SGrid::create(), {}), vxf::UsageError);
}

TEST_CASE("blend: a large tile of A over smaller tiles and voxels of B is split where B varies", "[ops]")
{
    auto a = openvdb::FloatGrid::create(0.0f);
    a->tree().addTile(2, openvdb::Coord(0), 1.0f, true); // one 128³ tile of 1
    auto b = openvdb::FloatGrid::create(0.0f);
    b->tree().addTile(1, openvdb::Coord(8, 0, 0), 2.0f, true); // an 8³ tile of 2 inside it
    b->tree().addTile(1, openvdb::Coord(200, 0, 0), 5.0f, true); // and one outside it
    vxf::ops::blend(*a, *b, {});
    CHECK(a->tree().getValue(openvdb::Coord(9, 1, 1)) == 3.0f);
    CHECK(a->tree().getValue(openvdb::Coord(60, 60, 60)) == 1.0f);
    CHECK(a->tree().getValue(openvdb::Coord(201, 0, 0)) == 5.0f);
    CHECK(a->activeVoxelCount() == 128 * 128 * 128 + 512);
}
