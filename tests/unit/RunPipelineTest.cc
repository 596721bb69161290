#include <vxf/pipeline/RunPipeline.h>

#include <vxf/io/ImageFile.h>
#include <vxf/io/VoxelSetFile.h>
#include <vxf/pipeline/SceneFile.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <tuple>

namespace {

using nlohmann::json;

/// A rigid motion x → R·x + t, R turning about x, then y, then z by @a degrees (the scene's
/// transform: rotate, then translate).
struct Motion
{
    openvdb::Vec3d degrees{0.0}, t{0.0};

    openvdb::Mat4d matrix() const
    {
        openvdb::Mat4d m = openvdb::Mat4d::identity();
        m.postRotate(openvdb::math::X_AXIS, degrees[0] * M_PI / 180.0);
        m.postRotate(openvdb::math::Y_AXIS, degrees[1] * M_PI / 180.0);
        m.postRotate(openvdb::math::Z_AXIS, degrees[2] * M_PI / 180.0);
        m.postTranslate(t);
        return m;
    }
    static openvdb::Vec3d vec(const json& v) { return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()}; }
    static json array(const openvdb::Vec3d& v) { return {v.x(), v.y(), v.z()}; }
    json point(const json& p) const { return array(matrix().transform(vec(p))); }
    json vector(const json& v) const { return array(matrix().transform3x3(vec(v))); }
};

/// @a scene with every object, light and the camera moved together by @a m.
json moved(json scene, const Motion& m)
{
    for (json& o : scene["objects"]) o["transform"] = {{"rotate", Motion::array(m.degrees)}, {"translate", Motion::array(m.t)}};
    for (json& l : scene["lights"]) {
        if (l.contains("position")) l["position"] = m.point(l["position"]);
        if (l.contains("direction")) l["direction"] = m.vector(l["direction"]);
    }
    scene["camera"]["position"] = m.point(scene["camera"]["position"]);
    scene["camera"]["look_at"] = m.point(scene["camera"]["look_at"]);
    scene["camera"]["up"] = m.vector(scene["camera"].value("up", json{0, 0, 1}));
    return scene;
}

/// The mean of an image's channels.
double meanOf(const vxf::RgbImage& image)
{
    double sum = 0.0;
    for (const openvdb::Vec3f& p : image.pixels) sum += double(p[0] + p[1] + p[2]) / 3.0;
    return sum / double(image.pixels.size());
}

/// A smooth puff of density on voxels centred at i·dx (dx 1/16), active above 0.02, and a flame
/// that reaches beyond it: a volume object with its own emission.
void writePuff(const std::string& path)
{
    const double dx = 1.0 / 16.0;
    auto transform = openvdb::math::Transform::createLinearTransform(dx);
    auto density = openvdb::FloatGrid::create(0.0f), flame = openvdb::FloatGrid::create(0.0f);
    for (auto* g : {density.get(), flame.get()}) g->setTransform(transform);
    density->setName("density");
    density->setGridClass(openvdb::GRID_FOG_VOLUME);
    flame->setName("flame");
    for (int i = -10; i <= 10; ++i) {
        for (int j = -10; j <= 10; ++j) {
            for (int k = -10; k <= 10; ++k) {
                const double r2 = (i * i + j * j + k * k) * dx * dx;
                const float d = float(std::exp(-r2 / (2.0 * 0.25 * 0.25)));
                if (d > 0.02f) density->tree().setValue(openvdb::Coord(i, j, k), d);
                if (r2 < 0.75 * 0.75) flame->tree().setValue(openvdb::Coord(i, j, k), float(1.0 - r2 / (0.75 * 0.75)));
            }
        }
    }
    vxf::VoxelSet set(transform);
    set.put(density);
    set.put(flame);
    vxf::writeVoxelSet(path, set);
}

/// Every light type in turn, placed around the origin (the area light a disk: turned about its
/// axis it stays itself; the sky constant). A spot's edge soft and a sky's directions many
/// enough that the voxels' and directions' own sampling of them, which a move shifts, stays
/// within the tolerance (a 5-degree edge at dim 32: 1.4%; a 16-direction sky turned: 0.8%).
std::vector<std::pair<std::string, json>> everyLight()
{
    return {{"point", {{"type", "point"}, {"position", {0.8, -0.9, 1.1}}, {"intensity", 3}}},
        {"spot",
            {{"type", "spot"}, {"position", {0.8, -0.9, 1.1}}, {"direction", {-0.8, 0.9, -1.1}}, {"cone_angle", 60}, {"cone_softness", 25},
                {"intensity", 3}}},
        {"directional", {{"type", "directional"}, {"direction", {-0.3, 0.5, -0.8}}, {"intensity", 2}}},
        {"area",
            {{"type", "area"}, {"shape", "disk"}, {"radius", 0.3}, {"position", {0.6, -0.7, 1.0}}, {"direction", {-0.6, 0.7, -1.0}},
                {"intensity", 3}, {"samples", 8}}},
        {"environment", {{"type", "environment"}, {"intensity", 0.5}, {"samples", 64}}}};
}

} // namespace

TEST_CASE("moving the objects, lights and camera together leaves the image as it was: every light type, both kernels, "
          "mesh media and volume objects",
    "[pipeline][transform]")
{
    vxf::test::TempDir dir;
    writePuff(dir.path("puff.vdb"));
    // Translated off the lattice (a tenth of a voxel and odd fractions of one), nothing but the
    // voxels' sampling of a smooth light moves. Turned a quarter about z and translated by whole
    // voxels (dx 1/16 for the puff, which then resamples exactly; the mesh's lattice follows its
    // bounds), the image keeps the quadrature error of direction sets fixed in the world (the
    // sweeps' 16, the sky's 64): a spot's light swept, 1.0%; the sky on the puff, 0.6% (0.55% at
    // 64 sweep directions). Turned any way, a volume object is resampled onto new voxels, whose
    // thin rim then meets the flame (as a 150x blow-up of the sweeps did).
    const std::vector<std::tuple<std::string, Motion, double>> motions = {{"translated", {{0, 0, 0}, {0.1, 0.37, -0.23}}, 0.005},
        {"turned a quarter and translated", {{0, 0, 90}, {0.25, -0.125, 0.5}}, 0.015},
        {"turned and translated", {{10, 20, 30}, {0.1, 0.2, 0.3}}, 0.03}};
    for (const std::string medium : {"mesh", "volume"}) {
        for (const std::string kernel : {"sweep", "gather"}) {
            auto lights = everyLight();
            if (medium == "volume") lights.push_back({"object's emission", json::object()});
            for (std::size_t index = 0; index < lights.size(); ++index) {
                const auto& [lightName, light] = lights[index];
                json object = medium == "mesh"
                    ? json{{"name", "ball"}, {"mesh", "builtin:sphere"}, {"material", {{"albedo", 0.9}, {"mean_free_path", 0.2}}}}
                    : json{{"name", "puff"}, {"volume", "puff.vdb"},
                          {"material", {{"albedo", 0.9}, {"mean_free_path", 0.1}, {"phase", {{"g", 0.3}}}}}};
                if (light.empty()) object["emission"] = {{"grid", "flame"}, {"intensity", 2}};
                const json scene = {{"objects", {object}}, {"lights", light.empty() ? json::array() : json::array({light})},
                    {"camera", {{"position", {0.4, -3.0, 0.6}}, {"look_at", {0, 0, 0}}, {"fov", 40}}}, {"voxelize", {{"dim", 32}}},
                    {"scatter", {{"kernel", kernel}, {"directions", 16}, {"passes", 8}}},
                    {"render", {{"width", 40}, {"height", 30}, {"samples", 1}}}};
                const auto render = [&](const json& s, const std::string& name) {
                    const std::string path = dir.path(name + ".json");
                    vxf::test::spit(path, s.dump());
                    const vxf::PipelineReport report = vxf::runPipeline(vxf::loadScene(path), dir.path("out-" + name));
                    return meanOf(vxf::readExr(report.image));
                };
                const std::string tag = medium + "-" + kernel + "-" + std::to_string(index);
                const double still = render(scene, tag);
                REQUIRE(still > 0.0);
                for (std::size_t m = 0; m < motions.size(); ++m) {
                    const auto& [motionName, motion, tolerance] = motions[m];
                    INFO(medium << " medium, " << kernel << " kernel, " << lightName << " light, " << motionName);
                    const double there = render(moved(scene, motion), tag + "-moved-" + std::to_string(m));
                    CHECK(there == Approx(still).epsilon(tolerance));
                }
            }
        }
    }
}
