#include <vxf/pipeline/SceneGeometry.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

using vxf::test::spit;
using vxf::test::TempDir;

namespace {

/// An OFF cube of half side @a h (one digit, so every cube's file has the same size).
std::string cubeOff(int h)
{
    std::string text = "OFF\n8 6 0\n";
    for (int z : {-h, h}) {
        for (int y : {-h, h}) {
            for (int x : {-h, h}) text += std::to_string(x) + " " + std::to_string(y) + " " + std::to_string(z) + "\n";
        }
    }
    return text + "4 0 4 6 2\n4 1 3 7 5\n4 0 1 5 4\n4 2 6 7 3\n4 0 2 3 1\n4 4 5 7 6\n";
}

} // namespace

TEST_CASE("an object's mesh is read once, and again when the file changes", "[pipeline][scene][mesh]")
{
    TempDir dir;
    const std::string path = dir.path("cube.off");
    spit(path, cubeOff(1));
    const vxf::Scene scene = vxf::parseScene(R"({
      "objects": [
        {"name": "a", "mesh": ")" +
            path + R"(", "material": {"sigma_a": [1, 1, 1], "sigma_s": [1, 1, 1]}},
        {"name": "b", "mesh": ")" +
            path + R"(", "transform": {"translate": [5, 0, 0]},
         "material": {"sigma_a": [1, 1, 1], "sigma_s": [1, 1, 1]}}
      ],
      "lights": [], "camera": {"position": [0, -5, 0], "look_at": [0, 0, 0]}
    })",
        dir.path("scene.json"));
    CHECK(vxf::objectMesh(scene.objects[0]).volume() == Approx(8.0));
    // The same file for another object: each gets its own transform.
    const vxf::TriangleMesh moved = vxf::objectMesh(scene.objects[1]);
    CHECK(moved.volume() == Approx(8.0));
    CHECK(moved.bounds().getCenter().x() == Approx(5.0));
    CHECK(vxf::objectMesh(scene.objects[0]).bounds().getCenter().x() == Approx(0.0).margin(1e-12));

    // Rewritten with the same size, at once: the new bytes are read.
    spit(path, cubeOff(2));
    CHECK(vxf::objectMesh(scene.objects[0]).volume() == Approx(64.0));
    CHECK(vxf::objectMesh(scene.objects[1]).volume() == Approx(64.0));
    spit(path, cubeOff(1));
    CHECK(vxf::objectMesh(scene.objects[0]).volume() == Approx(8.0));
}
