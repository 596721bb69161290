// Interpolation over the corners a caller accepts (vxf/core/MaskedTrilinear.h): exact for a linear
// field, geometric means exact for an exponential one, renormalised over the corners kept.
#include <vxf/core/MaskedTrilinear.h>

#include <catch2/catch.hpp>

#include <cmath>
#include <functional>

namespace {
/// A field given by a function of the corner.
struct Field
{
    std::function<openvdb::Vec3d(const openvdb::Coord&)> f;
    openvdb::Vec3d getValue(const openvdb::Coord& c) const { return f(c); }
};
const auto all = [](const openvdb::Coord&) { return true; };
} // namespace

TEST_CASE("the weights of a trilinear cell sum to one and reproduce the point", "[core][trilinear]")
{
    const openvdb::Vec3d p(2.3, -1.7, 0.45);
    const vxf::TrilinearCell cell(p);
    double total = 0.0;
    openvdb::Vec3d centroid(0.0);
    for (int i = 0; i < 8; ++i) {
        total += cell.weight[i];
        centroid += cell.corner(i).asVec3d() * cell.weight[i];
    }
    CHECK(total == Approx(1.0));
    CHECK(centroid.x() == Approx(p.x()));
    CHECK(centroid.y() == Approx(p.y()));
    CHECK(centroid.z() == Approx(p.z()));
}

TEST_CASE("masked trilinear: linear fields exactly, exponential ones geometrically, too few corners refused", "[core][trilinear]")
{
    const openvdb::Vec3d p(0.25, 0.6, 0.9);
    const Field linear{[](const openvdb::Coord& c) { return openvdb::Vec3d(1.0 + 2.0 * c.x() - c.y() + 0.5 * c.z()); }};
    openvdb::Vec3d out(0.0);
    REQUIRE(vxf::maskedTrilinear(linear, p, all, out));
    CHECK(out[0] == Approx(1.0 + 2.0 * p.x() - p.y() + 0.5 * p.z()));

    const Field exponential{[](const openvdb::Coord& c) { return openvdb::Vec3d(std::exp(-1.3 * c.x() - 0.4 * c.z())); }};
    REQUIRE(vxf::maskedTrilinear(exponential, p, all, out, /*geometric=*/true));
    CHECK(out[1] == Approx(std::exp(-1.3 * p.x() - 0.4 * p.z())));
    REQUIRE(vxf::maskedTrilinear(exponential, p, all, out, /*geometric=*/false));
    CHECK(out[1] > std::exp(-1.3 * p.x() - 0.4 * p.z())); // linear overshoots a convex fall-off

    // A constant field stays constant over any corners kept; too little weight is refused.
    const Field constant{[](const openvdb::Coord&) { return openvdb::Vec3d(7.0); }};
    const auto upper = [](const openvdb::Coord& c) { return c.z() == 1; }; // weight 0.9 at z = 0.9
    REQUIRE(vxf::maskedTrilinear(constant, p, upper, out));
    CHECK(out[2] == Approx(7.0));
    const auto lower = [](const openvdb::Coord& c) { return c.z() == 0; }; // weight 0.1
    out = openvdb::Vec3d(-1.0);
    CHECK_FALSE(vxf::maskedTrilinear(constant, p, lower, out));
    CHECK(out[0] == -1.0); // left as it was
    CHECK(vxf::maskedTrilinear(constant, p, lower, out, false, 0.05));
}
