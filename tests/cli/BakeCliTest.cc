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
    std::string scatterEntry;
    for (const auto& e : std::filesystem::directory_iterator(dir.path("out/cache"))) {
        if (e.path().filename().string().rfind("scatter-", 0) == 0 && e.path().extension() == ".vdb") scatterEntry = e.path().string();
    }
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
