// Light samples (vxf/light/LightSampler.h): the unattenuated fluence each light type brings to a
// point, against its closed form.
#include <vxf/light/LightSampler.h>

#include <catch2/catch.hpp>

#include <cmath>

namespace {
openvdb::Vec3d total(const vxf::LightSampler& sampler, const openvdb::Vec3d& x)
{
    std::vector<vxf::LightSample> samples;
    sampler.sample(x, 42, 0.0, samples);
    openvdb::Vec3d sum(0.0);
    for (const auto& s : samples) sum += s.fluence;
    return sum;
}
} // namespace

TEST_CASE("a point light gives power / r^2 toward it, clamped at the minimum distance", "[light][sampler]")
{
    vxf::Light point;
    point.type = vxf::Light::Type::Point;
    point.position = openvdb::Vec3d(0.0, 0.0, 3.0);
    point.color = openvdb::Vec3d(1.0, 0.5, 0.25);
    point.intensity = 8.0;
    const vxf::LightSampler sampler(point);
    std::vector<vxf::LightSample> samples;
    sampler.sample(openvdb::Vec3d(0.0, 0.0, 1.0), 0, 0.0, samples);
    REQUIRE(samples.size() == 1);
    CHECK(samples[0].direction.z() == Approx(1.0));
    CHECK(samples[0].distance == Approx(2.0));
    CHECK(samples[0].fluence[0] == Approx(8.0 / 4.0));
    CHECK(samples[0].fluence[2] == Approx(8.0 * 0.25 / 4.0));
    sampler.sample(openvdb::Vec3d(0.0, 0.0, 2.9), 0, 0.5, samples); // 0.1 away, clamped to 0.5
    CHECK(samples[0].fluence[0] == Approx(8.0 / 0.25));
}

TEST_CASE("a directional light is irradiance from where it comes, a spot's cone cuts it off", "[light][sampler]")
{
    vxf::Light sun;
    sun.type = vxf::Light::Type::Directional;
    sun.direction = openvdb::Vec3d(0.0, 0.6, -0.8);
    sun.intensity = 3.0;
    std::vector<vxf::LightSample> samples;
    vxf::LightSampler(sun).sample(openvdb::Vec3d(5.0), 0, 0.0, samples);
    REQUIRE(samples.size() == 1);
    CHECK(samples[0].direction.y() == Approx(-0.6));
    CHECK(samples[0].direction.z() == Approx(0.8));
    CHECK(std::isinf(samples[0].distance));
    CHECK(samples[0].fluence[1] == Approx(3.0));

    vxf::Light spot;
    spot.type = vxf::Light::Type::Spot;
    spot.direction = openvdb::Vec3d(0.0, 0.0, -1.0);
    spot.coneAngleDegrees = 40.0;
    const vxf::LightSampler spotSampler(spot);
    CHECK(total(spotSampler, openvdb::Vec3d(0.0, 0.0, -2.0))[0] == Approx(0.25)); // on the axis: a point light
    CHECK(total(spotSampler, openvdb::Vec3d(2.0, 0.0, -2.0))[0] == 0.0); // 45 degrees off the axis: outside
}

TEST_CASE("a disk light far away is L A cos / r^2, and a constant sky gives 4 pi L", "[light][sampler]")
{
    vxf::Light disk;
    disk.type = vxf::Light::Type::Area;
    disk.shape = vxf::Light::Shape::Disk;
    disk.radius = 0.1;
    disk.samples = 64;
    disk.intensity = 2.0; // radiance
    disk.direction = openvdb::Vec3d(0.0, 0.0, -1.0);
    const double r = 10.0;
    CHECK(total(vxf::LightSampler(disk), openvdb::Vec3d(0.0, 0.0, -r))[0] == Approx(2.0 * M_PI * 0.01 / (r * r)).epsilon(1e-3));
    CHECK(total(vxf::LightSampler(disk), openvdb::Vec3d(0.0, 0.0, r))[0] == 0.0); // one-sided

    vxf::Light sky;
    sky.type = vxf::Light::Type::Environment;
    sky.color = openvdb::Vec3d(0.5, 1.0, 2.0);
    sky.samples = 64;
    const vxf::LightSampler skySampler(sky);
    CHECK(skySampler.count() == 64);
    const openvdb::Vec3d phi = total(skySampler, openvdb::Vec3d(0.0));
    CHECK(phi[0] == Approx(4.0 * M_PI * 0.5));
    CHECK(phi[2] == Approx(4.0 * M_PI * 2.0));
}
