// `vxf bake`: vxf's light as the grids of an emission–absorption volume, checked by rendering the
// bake back in vxf (any renderer's emission–absorption shader sees the same) and against closed forms.
#include "TestSupport.h"

#include <vxf/io/VoxelSetFile.h>

#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>

using vxf::test::binary;
using vxf::test::run;
using vxf::test::slurp;
using vxf::test::spit;
using vxf::test::TempDir;

namespace {

/// The mean of an EXR's R, G and B over its pixels.
double meanOf(const std::string& path)
{
    Imf::InputFile file(path.c_str());
    const Imath::Box2i window = file.header().dataWindow();
    const int width = window.max.x - window.min.x + 1, height = window.max.y - window.min.y + 1;
    std::vector<float> pixels(std::size_t(width) * std::size_t(height) * 3);
    Imf::FrameBuffer buffer;
    for (int c = 0; c < 3; ++c) {
        buffer.insert(
            std::string(1, "RGB"[c]), Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(pixels.data() + c), 12, 12 * std::size_t(width)));
    }
    file.setFrameBuffer(buffer);
    file.readPixels(window.min.y, window.max.y);
    double sum = 0.0;
    for (float v : pixels) sum += v;
    return sum / double(pixels.size());
}

/// A fog sphere of density 1 (made as vdb_tool -ls2fog would) in @a path.
void writeFog(const std::string& path)
{
    vxf::VoxelSet set(openvdb::math::Transform::createLinearTransform(0.05));
    auto fog = openvdb::FloatGrid::create(0.0f);
    fog->setName("density");
    fog->setTransform(set.transformPtr());
    for (int i = -12; i <= 12; ++i)
        for (int j = -12; j <= 12; ++j)
            for (int k = -12; k <= 12; ++k) {
                if (i * i + j * j + k * k <= 144) fog->tree().setValue(openvdb::Coord(i, j, k), 1.0f);
            }
    set.put(fog);
    vxf::writeVoxelSet(path, set);
}

/// The stage cache's entry in @a cache whose name starts with @a stage ("" for none).
std::string cacheEntry(const std::string& cache, const std::string& stage)
{
    for (const auto& e : std::filesystem::directory_iterator(cache)) {
        if (e.path().filename().string().rfind(stage, 0) == 0 && e.path().extension() == ".vdb") return e.path().string();
    }
    return "";
}

} // namespace

TEST_CASE("vxf bake writes density and emission whose emission-absorption render is vxf's image", "[cli][bake]")
{
    TempDir dir;
    writeFog(dir.path("fog.vdb"));
    const std::string scene = R"({"objects": [{"volume": "fog.vdb", "material": {"albedo": 0.8, "mean_free_path": 0.2}}],
      "lights": [{"type": "directional", "direction": [-0.5, 0.6, -0.6], "intensity": 2}, {"type": "environment", "color": 0.1, "samples": 16}],
      "camera": {"position": [0, -3, 0.4], "look_at": [0, 0, 0], "up": [0, 0, 1], "fov": 30},
      "scatter": {"kernel": "sweep", "directions": 16},
      "render": {"width": 48, "height": 36, "samples": 4, "direct": "grid"}, "outputs": ["image"]})";
    spit(dir.path("s.json"), scene);
    const std::string vxf = binary("vxf");
    REQUIRE(run(fmt::format("{} run {} --out {}", vxf, dir.path("s.json"), dir.path("out"))).status == 0);
    const auto baked = run(fmt::format("{} bake {} -o {} --out {}", vxf, dir.path("s.json"), dir.path("bake.vdb"), dir.path("out")));
    INFO(baked.out << baked.err);
    REQUIRE(baked.status == 0);
    const nlohmann::json manifest = nlohmann::json::parse(slurp(dir.path("bake.json")));
    CHECK(manifest["vdb"] == "bake.vdb");
    CHECK(manifest["scattering"] == "all");
    CHECK(manifest["medium"]["sigma_s"][0].get<double>() == Approx(4.0)); // albedo 0.8 / mean free path 0.2
    CHECK(manifest["half_voxel"][0].get<double>() == Approx(0.025));

    // Emission = σs (direct + scatter) / 4π at a voxel, from the stage cache's grids.
    const vxf::VoxelSet set = vxf::readVoxelSet(dir.path("bake.vdb"));
    const std::string scatterEntry = cacheEntry(dir.path("out/cache"), "scatter-");
    REQUIRE_FALSE(scatterEntry.empty());
    const vxf::VoxelSet solved = vxf::readVoxelSet(scatterEntry);
    const openvdb::Coord voxel(3, -2, 5);
    const openvdb::Vec3f phi = solved.get<openvdb::Vec3SGrid>("direct")->tree().getValue(voxel) +
        solved.get<openvdb::Vec3SGrid>("scatter")->tree().getValue(voxel);
    const openvdb::Vec3f emission = set.get<openvdb::Vec3SGrid>("emission")->tree().getValue(voxel);
    CHECK(emission[0] == Approx(4.0 * phi[0] / (4.0 * M_PI)).epsilon(1e-5));
    CHECK(set.get<openvdb::FloatGrid>("density")->tree().getValue(voxel) == 1.0f);

    // Rendered back as an emission-absorption medium (σa = σt, no lights): the image vxf rendered.
    spit(dir.path("ea.json"), R"({"objects": [{"volume": "bake.vdb", "emission": {"grid": "emission"},
      "material": {"sigma_a": 5, "sigma_s": 0}}], "lights": [],
      "camera": {"position": [0, -3, 0.4], "look_at": [0, 0, 0], "up": [0, 0, 1], "fov": 30},
      "render": {"width": 48, "height": 36, "samples": 4}, "outputs": ["image"]})");
    REQUIRE(run(fmt::format("{} run {} --out {}", vxf, dir.path("ea.json"), dir.path("out"))).status == 0);
    const double original = meanOf(dir.path("out/s.exr")), again = meanOf(dir.path("out/ea.exr"));
    INFO(original << " vs " << again);
    CHECK(again == Approx(original).epsilon(0.01));

    // The multiple scattering alone.
    REQUIRE(
        run(fmt::format("{} bake {} -o {} --out {} --scattering multiple", vxf, dir.path("s.json"), dir.path("ms.vdb"), dir.path("out")))
            .status == 0);
    const openvdb::Vec3f multiple = vxf::readVoxelSet(dir.path("ms.vdb")).get<openvdb::Vec3SGrid>("emission")->tree().getValue(voxel);
    CHECK(multiple[0] == Approx(4.0 * solved.get<openvdb::Vec3SGrid>("scatter")->tree().getValue(voxel)[0] / (4.0 * M_PI)).epsilon(1e-5));
    CHECK(run(fmt::format("{} bake {} -o {} --scattering some", vxf, dir.path("s.json"), dir.path("x.vdb"))).status == 2);
    // s.json baked to s.vdb would write its manifest, s.json, over the scene: refused, the scene kept.
    const auto over = run(fmt::format("{} bake {} -o {} --out {}", vxf, dir.path("s.json"), dir.path("s.vdb"), dir.path("out")));
    CHECK(over.status == 2);
    CHECK_THAT(over.err, Catch::Contains("would replace the scene") && Catch::Contains("s-baked.vdb"));
    CHECK(slurp(dir.path("s.json")) == scene);
}

TEST_CASE("vxf bake of a mesh medium holds the surface on finer voxels", "[cli][bake]")
{
    // A sphere of radius 1 at 32 voxels across, light a mean free path deep (the glow near the
    // surface, where a grid's one-voxel edge ramp shows most), rendered back by vxf from the bake as
    // an emission-absorption volume: what Cycles sees of it (bench/interchange/bake).
    TempDir dir;
    const std::string camera = R"("camera": {"position": [0, -4.5, 1.2], "look_at": [0, 0, 0], "up": [0, 0, 1], "fov": 32},
      "render": {"width": 48, "height": 40, "samples": 4, "direct": "grid"}, "outputs": ["image"])";
    spit(dir.path("s.json"),
        R"({"objects": [{"mesh": "builtin:sphere", "material": {"albedo": 0.95, "mean_free_path": 0.08}}],
      "lights": [{"type": "point", "position": [1.5, -2, 2], "intensity": 4}, {"type": "environment", "color": 0.05, "samples": 16}],
      "voxelize": {"dim": 32}, "scatter": {"kernel": "sweep", "directions": 16}, )" +
            camera + "}");
    const std::string vxf = binary("vxf");
    REQUIRE(run(fmt::format("{} run {} --out {}", vxf, dir.path("s.json"), dir.path("out"))).status == 0);
    const double original = meanOf(dir.path("out/s.exr"));
    const auto renderedBack = [&](const std::string& name, const std::string& flags) {
        const auto baked =
            run(fmt::format("{} bake {} -o {} --out {} {}", vxf, dir.path("s.json"), dir.path(name + ".vdb"), dir.path("out"), flags));
        INFO(baked.out << baked.err);
        REQUIRE(baked.status == 0);
        const nlohmann::json manifest = nlohmann::json::parse(slurp(dir.path(name + ".json")));
        const double sigmaT = manifest["medium"]["sigma_a"][0].get<double>() + manifest["medium"]["sigma_s"][0].get<double>();
        spit(dir.path(name + "-ea.json"),
            fmt::format(R"({{"objects": [{{"volume": "{}.vdb", "emission": {{"grid": "emission"}},
          "material": {{"sigma_a": {}, "sigma_s": 0}}}}], "lights": [], {}}})",
                name, sigmaT, camera));
        REQUIRE(run(fmt::format("{} run {} --out {}", vxf, dir.path(name + "-ea.json"), dir.path("out"))).status == 0);
        return std::make_pair(manifest, meanOf(dir.path("out/" + name + "-ea.exr")));
    };

    // By default a mesh medium is baked at two voxels a side to each of the medium's, centred in its cube.
    const auto [manifest, fine] = renderedBack("fine", "");
    CHECK(manifest["supersample"] == 2);
    const vxf::VoxelSet set = vxf::readVoxelSet(dir.path("fine.vdb"));
    const auto density = set.get<openvdb::FloatGrid>("density");
    const std::string scatterEntry = cacheEntry(dir.path("out/cache"), "scatter-");
    REQUIRE_FALSE(scatterEntry.empty());
    const vxf::VoxelSet medium = vxf::readVoxelSet(scatterEntry);
    const double dx = medium.transformPtr()->voxelSize()[0];
    CHECK(density->voxelSize()[0] == Approx(dx / 2));
    const openvdb::Vec3d first = density->transform().indexToWorld(openvdb::Vec3d(0.0)),
                         cornerOfCube = medium.transformPtr()->indexToWorld(openvdb::Vec3d(-0.5));
    CHECK((first - cornerOfCube - openvdb::Vec3d(dx / 4)).length() < 1e-9);
    CHECK(manifest["half_voxel"][0].get<double>() == Approx(dx / 4));
    // Its mass is the sphere's volume, and the emission lies where the density does.
    double mass = 0.0;
    for (auto it = density->cbeginValueOn(); it; ++it) mass += double(*it) * std::pow(dx / 2, 3);
    CHECK(mass == Approx(4.0 / 3.0 * M_PI).epsilon(0.01));
    const auto emission = set.get<openvdb::Vec3SGrid>("emission");
    const auto densityAt = density->getConstAccessor();
    std::size_t glowingOutside = 0;
    for (auto it = emission->cbeginValueOn(); it; ++it) glowingOutside += (*it)[0] > 0.0f && densityAt.getValue(it.getCoord()) == 0.0f;
    CHECK(glowingOutside == 0);
    INFO(original << " vs " << fine);
    CHECK(fine == Approx(original).epsilon(0.03));
    // The medium's own voxels: the edge ramp a voxel wide brightens the rim.
    const auto [coarseManifest, coarse] = renderedBack("coarse", "--supersample 1");
    CHECK(coarseManifest["supersample"] == 1);
    CHECK(std::abs(coarse - original) > std::abs(fine - original));
    CHECK(run(fmt::format("{} bake {} -o {} --supersample 5", vxf, dir.path("s.json"), dir.path("x.vdb"))).status == 2);
}
