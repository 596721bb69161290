// Blackbody light from a temperature grid, as Cycles' Principled Volume gives it (vxf/light/Blackbody.h).
#include <vxf/light/Blackbody.h>

#include <vxf/io/VoxelSetFile.h>
#include <vxf/light/VolumeEmission.h>
#include <vxf/pipeline/SceneFile.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

namespace {

double luminance(const openvdb::Vec3d& c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

} // namespace

TEST_CASE("a blackbody's colour is Cycles' within 2.5%, of luminance 1", "[blackbody]")
{
    // Cycles' Principled Volume (Blender 4.5.15) through a thin slab at these temperatures,
    // its RGB divided by its luminance (docs/accuracy-notes.md, "Blackbody").
    const struct
    {
        double kelvin;
        openvdb::Vec3d cycles;
    } measured[] = {{2000, {2.529, 0.645, 0.020}}, {3000, {1.784, 0.841, 0.269}}, {4000, {1.422, 0.922, 0.527}},
        {6500, {1.047, 0.984, 1.024}}, {10000, {0.875, 0.995, 1.415}}};
    for (const auto& m : measured) {
        const openvdb::Vec3d c = vxf::blackbodyColour(m.kelvin);
        INFO(m.kelvin << " K: " << c);
        CHECK(luminance(c) == Approx(1.0).epsilon(1e-3));
        // (Cycles fits its own table: 2.3% apart at 2000 K, 1.7% at 3000 K, within 1.1% from 4000 K up)
        for (int i = 0; i < 3; ++i) CHECK(c[i] == Approx(m.cycles[i]).margin(0.005).epsilon(m.kelvin < 3000 ? 0.025 : 0.02));
    }
    // Red below, blue above; never negative (out of gamut is clamped).
    CHECK(vxf::blackbodyColour(1000)[0] > vxf::blackbodyColour(1000)[2]);
    CHECK(vxf::blackbodyColour(20000)[2] > vxf::blackbodyColour(20000)[0]);
    CHECK(vxf::blackbodyColour(500)[2] >= 0.0);
}

TEST_CASE("blackbody emission grows as T^4 in Cycles' units, zero at and below 0 K", "[blackbody]")
{
    CHECK(luminance(vxf::blackbodyEmission(6500)) == Approx(vxf::kCyclesBlackbody * std::pow(6500.0, 4)).epsilon(2e-3));
    const double ratio = luminance(vxf::blackbodyEmission(4000)) / luminance(vxf::blackbodyEmission(2000));
    CHECK(ratio == Approx(16.0).epsilon(2e-3));
    CHECK(vxf::blackbodyEmission(0.0) == openvdb::Vec3d(0.0));
    CHECK(vxf::blackbodyEmission(-300.0) == openvdb::Vec3d(0.0));
}

TEST_CASE("a volume object's emission from a temperature grid, as Blender's Principled Volume scales it", "[blackbody][scene][volume]")
{
    vxf::test::TempDir dir;
    // Mantaflow's normalised temperature: 1.5 everywhere in a block; Blender's Temperature 2000 K.
    vxf::VoxelSet set(openvdb::math::Transform::createLinearTransform(0.1));
    for (const auto& [name, value] : {
             std::pair<const char*, float>{"density", 1.0f},
             {"temperature", 1.5f},
         }) {
        auto grid = openvdb::FloatGrid::create(0.0f);
        grid->setName(name);
        grid->setTransform(set.transformPtr());
        grid->tree().fill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(7)), value, true);
        set.put(grid);
    }
    auto vector = openvdb::Vec3SGrid::create();
    vector->setName("velocity");
    vector->setTransform(set.transformPtr());
    set.put(vector);
    vxf::writeVoxelSet(dir.path("fire.vdb"), set);
    const auto scene = [&](const std::string& emission) {
        return vxf::parseScene(R"({"objects": [{"volume": "fire.vdb", "voxel_placement": "centre", "emission": )" + emission +
                R"(, "material": {"albedo": 0.5, "mean_free_path": 1}}], "lights": [], "camera": {"position": [0, -5, 0], "look_at": [0, 0, 0]}})",
            dir.path("s.json"));
    };
    const vxf::Scene s = scene(R"({"grid": "temperature", "blackbody": {"temperature": 2000, "intensity": 0.5}, "intensity": 2})");
    REQUIRE(s.lights.size() == 1);
    CHECK(s.lights[0].blackbodyKelvin == 2000.0);
    const vxf::VolumeEmission emission(s.lights[0]);
    vxf::VolumeEmission::Sampler sampler(emission);
    const openvdb::Vec3d inside = sampler.at({0.35, 0.35, 0.35});
    const openvdb::Vec3d expected = vxf::blackbodyEmission(3000.0); // 1.5 × 2000 K, × 0.5 × 2
    for (int i = 0; i < 3; ++i) CHECK(inside[i] == Approx(expected[i]).epsilon(1e-4));
    CHECK(sampler.at({3.0, 3.0, 3.0}) == openvdb::Vec3d(0.0)); // outside: 0 K, no light
    // A blackbody needs a float grid.
    const vxf::Scene wrong = scene(R"({"grid": "velocity", "blackbody": {"temperature": 1000}})");
    CHECK_THROWS_WITH(vxf::VolumeEmission(wrong.lights[0]), Catch::Contains("must be a float temperature"));
}
