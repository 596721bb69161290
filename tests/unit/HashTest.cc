// The deterministic hashes behind per-voxel rotations and camera jitter (vxf/core/Hash.h): seeded by
// position, the same on every run and thread, and spread evenly.
#include <vxf/core/Hash.h>

#include <catch2/catch.hpp>

#include <set>

TEST_CASE("coordinate keys are distinct across a block and the same on every call", "[core][hash]")
{
    std::set<std::uint64_t> keys;
    for (int x = -8; x < 8; ++x) {
        for (int y = -8; y < 8; ++y) {
            for (int z = -8; z < 8; ++z) keys.insert(vxf::coordKey(openvdb::Coord(x, y, z)));
        }
    }
    CHECK(keys.size() == 16u * 16u * 16u);
    CHECK(vxf::coordKey(openvdb::Coord(3, -4, 5)) == vxf::coordKey(openvdb::Coord(3, -4, 5)));
    CHECK(vxf::coordKey(openvdb::Coord(3, -4, 5)) != vxf::coordKey(openvdb::Coord(5, -4, 3))); // not symmetric in the axes
    CHECK(vxf::CoordHash()(openvdb::Coord(1, 2, 3)) == std::size_t(vxf::coordKey(openvdb::Coord(1, 2, 3))));
}

TEST_CASE("unit hashes lie between 0 and 1, are uniform, and change with index and salt", "[core][hash]")
{
    const int n = 200000;
    double sum = 0.0, sumSquares = 0.0;
    int below[10] = {};
    for (int i = 0; i < n; ++i) {
        const double u = vxf::unitHash(12345, std::uint64_t(i));
        REQUIRE(u >= 0.0);
        REQUIRE(u < 1.0);
        sum += u;
        sumSquares += u * u;
        ++below[int(u * 10.0)];
    }
    CHECK(sum / n == Approx(0.5).margin(0.003));
    CHECK(sumSquares / n == Approx(1.0 / 3.0).margin(0.003)); // E[u²] of the uniform distribution
    for (int bin : below) CHECK(bin == Approx(n / 10).epsilon(0.03));
    CHECK(vxf::unitHash(1, 2, 0) != vxf::unitHash(1, 2, 1));
    CHECK(vxf::unitHash(1, 2) == vxf::unitHash(1, 2));
}
