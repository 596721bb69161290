// Where another tool's voxels lie: OpenVDB's and Houdini's centres or Blender's and Cycles' cells
// (vxf/io/VoxelPlacement.h), and a volume object and its emission placed so (SceneMedium, VolumeEmission).
#include <vxf/io/VoxelPlacement.h>

#include <vxf/io/VoxelSetFile.h>
#include <vxf/light/VolumeEmission.h>
#include <vxf/pipeline/SceneFile.h>
#include <vxf/pipeline/SceneMedium.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <filesystem>

using vxf::VoxelPlacement;

namespace {

VoxelPlacement autoPlacement(const std::string& path, const std::string& creator = "")
{
    openvdb::MetaMap meta;
    if (!creator.empty()) meta.insertMeta("creator", openvdb::StringMetadata(creator));
    return vxf::resolvePlacement(VoxelPlacement::Auto, path, meta).placement;
}

/// A block of density 1 (and a `flame` of 2) over voxels 0..3 of size 0.1, in @a path.
void writeBlock(const std::string& path)
{
    vxf::VoxelSet set(openvdb::math::Transform::createLinearTransform(0.1));
    for (const auto& [name, value] : {std::pair<const char*, float>{"density", 1.0f}, {"flame", 2.0f}}) {
        auto grid = openvdb::FloatGrid::create(0.0f);
        grid->setName(name);
        grid->setTransform(set.transformPtr());
        grid->tree().fill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(3)), value, true);
        set.put(grid);
    }
    vxf::writeVoxelSet(path, set);
}

} // namespace

TEST_CASE("auto placement follows the file's writer: Blender's cells, everyone else's centres", "[placement]")
{
    vxf::test::TempDir dir;
    CHECK(autoPlacement("/cache/data/fluid_data_0012.vdb") == VoxelPlacement::Cell); // Mantaflow, as Blender names it
    CHECK(autoPlacement("/cache/noise/fluid_noise_0001.vdb") == VoxelPlacement::Cell);
    CHECK(autoPlacement("smoke.0001.vdb") == VoxelPlacement::Centre);
    CHECK(autoPlacement("fluid_data_0012.vdb", "Houdini/SOP_OpenVDB_Write") == VoxelPlacement::Centre); // the metadata wins
    CHECK(autoPlacement("any.vdb", "Blender 4.5") == VoxelPlacement::Cell);
    // A geometry-nodes bake: blobs/00001_00000_file_1.vdb beside meta/ (what bpy 4.5.15 writes).
    std::filesystem::create_directories(dir.root() / "bake" / "meta");
    std::filesystem::create_directories(dir.root() / "bake" / "blobs");
    CHECK(autoPlacement(dir.path("bake/blobs/00001_00000_file_1.vdb")) == VoxelPlacement::Cell);
    std::filesystem::create_directories(dir.root() / "other" / "blobs");
    CHECK(autoPlacement(dir.path("other/blobs/00001_00000_file_1.vdb")) == VoxelPlacement::Centre); // no meta/: not a bake
    // vxf's own files, and an explicit choice.
    openvdb::MetaMap vxfMeta;
    vxfMeta.insertMeta("vxf:version", openvdb::StringMetadata("0.1"));
    CHECK(vxf::resolvePlacement(VoxelPlacement::Auto, "fluid_data_0001.vdb", vxfMeta).placement == VoxelPlacement::Centre);
    CHECK(vxf::resolvePlacement(VoxelPlacement::Centre, "fluid_data_0001.vdb", {}).placement == VoxelPlacement::Centre);
    CHECK(vxf::resolvePlacement(VoxelPlacement::Cell, "x.vdb", {}).why == "voxel_placement \"cell\"");
}

TEST_CASE("cell placement moves the voxels half a voxel along the grid's own axes", "[placement]")
{
    const auto linear = openvdb::math::Transform::createLinearTransform(0.1);
    CHECK(vxf::placedTransform(*linear, VoxelPlacement::Centre)->indexToWorld(openvdb::Coord(0)) == openvdb::Vec3d(0.0));
    const openvdb::Vec3d cell = vxf::placedTransform(*linear, VoxelPlacement::Cell)->indexToWorld(openvdb::Coord(2, 0, 0));
    CHECK(cell.x() == Approx(0.25));
    CHECK(cell.y() == Approx(0.05));
    // A grid turned a quarter about z: the half voxel turns with it.
    auto turned = openvdb::math::Transform::createLinearTransform(0.1);
    turned->postRotate(M_PI / 2, openvdb::math::Z_AXIS);
    const openvdb::Vec3d turnedCell = vxf::placedTransform(*turned, VoxelPlacement::Cell)->indexToWorld(openvdb::Coord(0));
    CHECK(turnedCell.x() == Approx(-0.05));
    CHECK(turnedCell.y() == Approx(0.05));
}

TEST_CASE("a volume object and its emission lie where voxel_placement puts them", "[placement][scene][volume]")
{
    vxf::test::TempDir dir;
    writeBlock(dir.path("block.vdb"));
    const auto scene = [&](const std::string& placement) {
        return vxf::parseScene(R"({"objects": [{"volume": "block.vdb", "voxel_placement": ")" + placement +
                R"(", "emission": {"grid": "flame"}, "material": {"albedo": 0.5, "mean_free_path": 1}}], "lights": [],
                "camera": {"position": [0, -5, 0], "look_at": [0, 0, 0]}})",
            dir.path("s.json"));
    };
    for (const std::string placement : {"centre", "cell"}) {
        const vxf::Scene s = scene(placement);
        const double shift = placement == "cell" ? 0.05 : 0.0;
        const vxf::VoxelSet set = vxf::voxelizeMedia(s, vxf::VoxelizeOptions{});
        const openvdb::Vec3d first = set.transform().indexToWorld(openvdb::Coord(0));
        CHECK(first.x() == Approx(shift).margin(1e-12));
        // The emission, read by its light, lies on the same voxels: 2 inside the block's cells, 0 past them.
        REQUIRE(s.lights.size() == 1);
        CHECK(s.lights[0].placement == s.objects[0].placement);
        const vxf::VolumeEmission emission(s.lights[0]);
        vxf::VolumeEmission::Sampler sampler(emission);
        CHECK(sampler.at({0.3 + shift, 0.15, 0.15})[0] == Approx(2.0));
        CHECK(sampler.at({0.36 + shift, 0.15, 0.15})[0] == Approx(2.0 * 0.4).margin(1e-6)); // 0.6 of the way past the last centre
    }
    CHECK_THROWS_WITH(vxf::parseScene(R"({"objects": [{"mesh": "builtin:sphere", "voxel_placement": "cell",
        "material": {"albedo": 0.5, "mean_free_path": 1}}], "lights": [], "camera": {"position": [0, -5, 0], "look_at": [0, 0, 0]}})",
                          "s.json"),
        Catch::Contains("/objects/0/voxel_placement: places a volume object's voxels; this object has a mesh"));
}

TEST_CASE("a file Blender wrote lies where Blender puts it: a baked unit cube centred on the origin", "[placement][volume][interop]")
{
    // tests/data/blender-bake: bpy 4.5.15's geometry-nodes bake of Mesh to Volume of a unit cube
    // (scripts/make-blender-bake), voxels -2..1 of 0.217: no writer metadata, known by its folders.
    const std::string file = vxf::test::source("tests/data/blender-bake/blobs/00001_00000_file_1.vdb");
    const auto centroid = [&](const std::string& placement) {
        const vxf::Scene scene = vxf::parseScene(R"({"objects": [{"volume": ")" + file + R"(", "voxel_placement": ")" + placement +
                R"(", "material": {"albedo": 0.5, "mean_free_path": 1}}], "lights": [], "camera": {"position": [0, -5, 0], "look_at": [0, 0, 0]}})",
            "s.json");
        const vxf::VoxelSet set = vxf::voxelizeMedia(scene, vxf::VoxelizeOptions{});
        const auto density = set.get<openvdb::FloatGrid>("density");
        openvdb::Vec3d sum(0.0);
        double weight = 0.0;
        for (auto it = density->cbeginValueOn(); it; ++it) {
            sum += density->transform().indexToWorld(it.getCoord()) * double(*it);
            weight += double(*it);
        }
        return sum / weight;
    };
    const openvdb::Vec3d blender = centroid("auto"), openvdbCentres = centroid("centre");
    for (int i = 0; i < 3; ++i) {
        CHECK(blender[i] == Approx(0.0).margin(1e-6)); // the cube's centre, as Cycles renders it
        CHECK(openvdbCentres[i] == Approx(-0.5 * 0.2165).margin(1e-3)); // half a voxel off under OpenVDB's convention
    }
    openvdb::MetaMap none;
    CHECK(vxf::resolvePlacement(VoxelPlacement::Auto, file, none).why.find("geometry-nodes bake") != std::string::npos);
}
