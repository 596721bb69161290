#include <vxf/core/SphericalFibonacci.h>

#include <catch2/catch.hpp>

TEST_CASE("spherical Fibonacci directions are unit and evenly spread", "[core][directions]")
{
    const auto dirs = vxf::sphericalFibonacci(256);
    REQUIRE(dirs.size() == 256);
    openvdb::Vec3d sum(0.0);
    double zz = 0.0;
    for (const auto& d : dirs) {
        CHECK(d.length() == Approx(1.0));
        sum += d;
        zz += d.z() * d.z();
    }
    CHECK(sum.length() / 256.0 < 0.01); // no net direction
    CHECK(zz / 256.0 == Approx(1.0 / 3.0).epsilon(0.01)); // <z^2> of the uniform sphere
    CHECK(vxf::sphericalFibonacci(0).empty());
}
