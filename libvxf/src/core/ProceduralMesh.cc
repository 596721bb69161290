#include <vxf/core/ProceduralMesh.h>

#include <vxf/core/Error.h>

#include <cmath>

namespace vxf {

openvdb::BBoxd TriangleMesh::bounds() const
{
    openvdb::BBoxd box; // default-constructed: empty (min > max)
    for (const auto& p : points) box.expand(p);
    return box;
}

double TriangleMesh::volume() const
{
    // V = 1/6 Σ p0 · (p1 × p2), relative to the first point for accuracy far from the origin.
    if (points.empty()) return 0.0;
    const openvdb::Vec3d origin = points.front();
    double sixV = 0.0;
    for (const auto& t : triangles) {
        const openvdb::Vec3d a = points[t[0]] - origin, b = points[t[1]] - origin, c = points[t[2]] - origin;
        sixV += a.dot(b.cross(c));
    }
    return sixV / 6.0;
}

TriangleMesh makeRevolution(const std::vector<openvdb::Vec2d>& profile, int segments)
{
    if (profile.size() < 3 || segments < 3) throw Error("makeRevolution: profile too short");
    if (profile.front()[0] != 0.0 || profile.back()[0] != 0.0) {
        throw Error("makeRevolution: the profile must start and end on the axis");
    }
    TriangleMesh mesh;
    const auto ringCount = profile.size() - 2; // profile points off the axis
    const openvdb::Index bottom = 0;
    mesh.points.emplace_back(0.0, 0.0, profile.front()[1]);
    for (std::size_t r = 1; r + 1 < profile.size(); ++r) {
        for (int s = 0; s < segments; ++s) {
            const double phi = 2.0 * M_PI * double(s) / double(segments);
            mesh.points.emplace_back(profile[r][0] * std::cos(phi), profile[r][0] * std::sin(phi), profile[r][1]);
        }
    }
    const auto top = openvdb::Index(mesh.points.size());
    mesh.points.emplace_back(0.0, 0.0, profile.back()[1]);

    const auto ring = [&](std::size_t r, int s) { return openvdb::Index(1 + r * segments + std::size_t((s + segments) % segments)); };
    // Outward orientation: the profile runs bottom → top with the solid on the axis side.
    for (int s = 0; s < segments; ++s) {
        mesh.triangles.emplace_back(bottom, ring(0, s + 1), ring(0, s));
        for (std::size_t r = 0; r + 1 < ringCount; ++r) {
            mesh.triangles.emplace_back(ring(r, s), ring(r, s + 1), ring(r + 1, s + 1));
            mesh.triangles.emplace_back(ring(r, s), ring(r + 1, s + 1), ring(r + 1, s));
        }
        mesh.triangles.emplace_back(top, ring(ringCount - 1, s), ring(ringCount - 1, s + 1));
    }
    return mesh;
}

TriangleMesh makeSphere(const openvdb::Vec3d& center, double radius, int rings, int segments)
{
    std::vector<openvdb::Vec2d> profile;
    for (int i = 0; i <= rings; ++i) {
        const double theta = M_PI * double(i) / double(rings); // 0 at the south pole
        profile.emplace_back(i == 0 || i == rings ? 0.0 : radius * std::sin(theta), -radius * std::cos(theta));
    }
    TriangleMesh mesh = makeRevolution(profile, segments);
    for (auto& p : mesh.points) p += center;
    return mesh;
}

TriangleMesh makeBox(const openvdb::Vec3d& lo, const openvdb::Vec3d& hi)
{
    TriangleMesh mesh;
    for (int i = 0; i < 8; ++i) {
        mesh.points.emplace_back(i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]);
    }
    // Two outward triangles per face (vertex bit 0 = x, 1 = y, 2 = z).
    const unsigned quads[6][4] = {
        {0, 4, 6, 2}, {1, 3, 7, 5}, // -x, +x
        {0, 1, 5, 4}, {2, 6, 7, 3}, // -y, +y
        {0, 2, 3, 1}, {4, 5, 7, 6}, // -z, +z
    };
    for (const auto& q : quads) {
        mesh.triangles.emplace_back(q[0], q[1], q[2]);
        mesh.triangles.emplace_back(q[0], q[2], q[3]);
    }
    return mesh;
}

TriangleMesh makeCandle(int segments)
{
    const double radius = 1.0, height = 3.0, rim = 0.08, pool = 0.12;
    std::vector<openvdb::Vec2d> profile;
    profile.emplace_back(0.0, 0.0);
    profile.emplace_back(radius - rim, 0.0);
    for (int i = 1; i <= 4; ++i) { // rounded bottom edge
        const double a = 0.5 * M_PI * i / 4.0;
        profile.emplace_back(radius - rim + rim * std::sin(a), rim - rim * std::cos(a));
    }
    for (int i = 1; i <= 8; ++i) profile.emplace_back(radius, rim + (height - 2 * rim) * i / 8.0);
    for (int i = 1; i <= 6; ++i) { // rounded rim, lip slightly higher than the pool
        const double a = M_PI * i / 6.0;
        profile.emplace_back(radius - rim + rim * std::cos(a), height - rim + rim * std::sin(a));
    }
    const double inner = radius - 2.0 * rim;
    for (int i = 1; i <= 10; ++i) { // melt pool: a shallow bowl down to the wick
        const double u = double(i) / 10.0;
        const double r = inner * (1.0 - u);
        profile.emplace_back(r, height - rim - pool * std::sin(0.5 * M_PI * u));
    }
    profile.back()[0] = 0.0;
    return makeRevolution(profile, segments);
}

TriangleMesh makeFlame(int segments)
{
    // r(u) = k·√u·(1 − u)^1.2 for height u: round at the base, widest (0.22) at u = 0.29,
    // drawn out to a point at the tip.
    const int rings = 24;
    const double k = 0.22 / (std::sqrt(0.5 / 1.7) * std::pow(1.2 / 1.7, 1.2));
    std::vector<openvdb::Vec2d> profile;
    for (int i = 0; i <= rings; ++i) {
        const double u = double(i) / rings;
        const double s = u * u * (3.0 - 2.0 * u); // rings closer at both ends, where r turns fastest
        profile.emplace_back(k * std::sqrt(s) * std::pow(1.0 - s, 1.2), s);
    }
    return makeRevolution(profile, segments); // r is exactly 0 at u = 0 and 1: on the axis
}

const std::vector<std::string>& builtinMeshNames()
{
    static const std::vector<std::string> names = {"builtin:candle", "builtin:flame", "builtin:sphere", "builtin:box"};
    return names;
}

std::optional<TriangleMesh> builtinMesh(const std::string& name)
{
    if (name == "builtin:candle") return makeCandle();
    if (name == "builtin:flame") return makeFlame();
    if (name == "builtin:sphere") return makeSphere(openvdb::Vec3d(0.0), 1.0);
    if (name == "builtin:box") return makeBox(openvdb::Vec3d(-1.0), openvdb::Vec3d(1.0));
    return std::nullopt;
}

} // namespace vxf
