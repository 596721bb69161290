// The scene's types (vxf/core/Scene.h): what the lights and materials derive from their fields.
#include <vxf/core/Scene.h>

#include <catch2/catch.hpp>

TEST_CASE("a light's power is colour times intensity, a material's albedo and sigma_t per channel", "[core][scene]")
{
    vxf::Light light;
    light.color = openvdb::Vec3d(1.0, 0.5, 0.0);
    light.intensity = 4.0;
    CHECK(light.power() == openvdb::Vec3d(4.0, 2.0, 0.0));

    vxf::Material m;
    m.sigmaA = openvdb::Vec3d(1.0, 0.0, 0.0);
    m.sigmaS = openvdb::Vec3d(3.0, 2.0, 0.0);
    CHECK(m.sigmaT() == openvdb::Vec3d(4.0, 2.0, 0.0));
    CHECK(m.albedo()[0] == Approx(0.75));
    CHECK(m.albedo()[1] == Approx(1.0));
    CHECK(m.albedo()[2] == 0.0); // σt 0: albedo 0, not NaN
    CHECK(m.scatters());
    m.sigmaS = openvdb::Vec3d(0.0);
    CHECK_FALSE(m.scatters());

    vxf::SurfaceShading shading;
    CHECK_FALSE(shading.reflects());
    shading.specular = openvdb::Vec3d(0.04);
    CHECK(shading.reflects());

    // A scene's default settings are the stages' (vxf/core/StageDefaults.h).
    const vxf::SceneSettings s;
    CHECK(s.passes == vxf::defaults::kPasses);
    CHECK(s.width == vxf::defaults::kWidth);
    CHECK(s.outputs == std::vector<std::string>{"image"});
}
