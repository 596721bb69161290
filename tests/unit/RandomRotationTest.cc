// Random rotations from three uniform numbers (vxf/core/RandomRotation.h): proper rotations,
// spread over all orientations.
#include <vxf/core/RandomRotation.h>

#include <vxf/core/Hash.h>

#include <catch2/catch.hpp>

TEST_CASE("a random rotation is orthonormal with determinant one, and turns the pole everywhere", "[core][rotation]")
{
    openvdb::Vec3d meanPole(0.0);
    const int n = 20000;
    for (int i = 0; i < n; ++i) {
        const openvdb::Mat3d r = vxf::randomRotation(
            vxf::unitHash(7, std::uint64_t(i), 0), vxf::unitHash(7, std::uint64_t(i), 1), vxf::unitHash(7, std::uint64_t(i), 2));
        const openvdb::Mat3d identity = r * r.transpose();
        for (int a = 0; a < 3; ++a) {
            for (int b = 0; b < 3; ++b) REQUIRE(identity(a, b) == Approx(a == b ? 1.0 : 0.0).margin(1e-12));
        }
        REQUIRE(r.det() == Approx(1.0));
        meanPole += r * openvdb::Vec3d(0.0, 0.0, 1.0);
    }
    // Uniform over the rotations: the turned pole is uniform on the sphere, its mean near 0.
    meanPole /= double(n);
    CHECK(meanPole.length() < 0.02);
}
