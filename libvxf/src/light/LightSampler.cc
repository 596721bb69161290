#include <vxf/light/LightSampler.h>

#include <vxf/core/Hash.h>
#include <vxf/core/SphericalFibonacci.h>
#include <vxf/io/ImageFile.h>

#include <algorithm>
#include <cmath>

namespace vxf {

namespace {

double falloff(Light::Falloff f, double r)
{
    switch (f) {
    case Light::Falloff::InverseSquare: return 1.0 / (r * r);
    case Light::Falloff::Linear: return 1.0 / r;
    case Light::Falloff::None: return 1.0;
    }
    return 0.0;
}

/// Orthonormal tangents of unit normal @a n.
void frame(const openvdb::Vec3d& n, openvdb::Vec3d& u, openvdb::Vec3d& v)
{
    const openvdb::Vec3d helper = std::abs(n.x()) < 0.9 ? openvdb::Vec3d(1, 0, 0) : openvdb::Vec3d(0, 1, 0);
    u = n.cross(helper).unit();
    v = n.cross(u);
}

/// ∫ L dω of a lat-long map over the Voronoi cells of @a directions (nearest direction per
/// texel; texel solid angle (2π/W)(π/H) sin θ at its centre).
std::vector<openvdb::Vec3d> binMap(const RgbImage& map, const std::vector<openvdb::Vec3d>& directions)
{
    std::vector<openvdb::Vec3d> sums(directions.size(), openvdb::Vec3d(0.0));
    const double du = 2.0 * M_PI / map.width, dv = M_PI / map.height;
    for (int y = 0; y < map.height; ++y) {
        const double theta = (y + 0.5) * dv;
        const double solidAngle = du * dv * std::sin(theta);
        for (int x = 0; x < map.width; ++x) {
            const openvdb::Vec3d w = latLongDirection((x + 0.5) / map.width, (y + 0.5) / map.height);
            std::size_t best = 0;
            double bestDot = -2.0;
            for (std::size_t i = 0; i < directions.size(); ++i) {
                const double d = directions[i].dot(w);
                if (d > bestDot) {
                    bestDot = d;
                    best = i;
                }
            }
            sums[best] += openvdb::Vec3d(map.pixels[std::size_t(y) * std::size_t(map.width) + std::size_t(x)]) * solidAngle;
        }
    }
    return sums;
}

} // namespace

openvdb::Vec3d latLongDirection(double u, double v)
{
    // Blender (direction_to_equirectangular): u = −atan2(y, x)/(2π) + 0.5; here v runs from
    // the zenith (the top row of the file) to the nadir.
    const double phi = -(u - 0.5) * 2.0 * M_PI, theta = v * M_PI;
    const double s = std::sin(theta);
    return openvdb::Vec3d(s * std::cos(phi), s * std::sin(phi), std::cos(theta));
}

LightSampler::LightSampler(const Light& light)
    : mLight(light)
{
    if (light.type != Light::Type::Environment) return;
    mDirections = sphericalFibonacci(light.samples);
    if (light.file.empty()) {
        mRadiance.assign(mDirections.size(), openvdb::Vec3d(4.0 * M_PI / double(mDirections.size())));
    } else {
        mRadiance = binMap(readExr(light.file), mDirections);
    }
}

std::size_t LightSampler::count() const
{
    switch (mLight.type) {
    case Light::Type::Point:
    case Light::Type::Spot:
    case Light::Type::Directional: return 1;
    case Light::Type::Environment: return mDirections.size();
    case Light::Type::Area: {
        const int n = std::max(0, mLight.samples);
        if (mLight.shape == Light::Shape::Sphere) return std::size_t(n);
        const int side = std::max(1, int(std::lround(std::sqrt(double(n)))));
        return std::size_t(side) * std::size_t(side);
    }
    case Light::Type::Volume: return 0;
    }
    return 0;
}

void LightSampler::sample(const openvdb::Vec3d& x, std::uint64_t key, double minDistance, std::vector<LightSample>& out, std::size_t first,
    std::size_t last) const
{
    out.clear();
    last = std::min(last, count());
    if (first >= last) return;
    const Light& light = mLight;
    const openvdb::Vec3d power = light.power();
    // A sample from the point q carrying intensity·f(r).
    const auto fromPoint = [&](const openvdb::Vec3d& q, const openvdb::Vec3d& intensity) {
        const openvdb::Vec3d toLight = q - x;
        const double length = toLight.length();
        const double r = std::max(length, minDistance);
        LightSample s;
        s.direction = length > 0.0 ? toLight / length : openvdb::Vec3d(0.0, 0.0, 1.0);
        s.distance = length;
        s.fluence = intensity * falloff(light.falloff, r);
        out.push_back(s);
    };
    switch (light.type) {
    case Light::Type::Point: fromPoint(light.position, power); return;
    case Light::Type::Spot: {
        // Cone factor: 1 within (half angle − softness), smoothstep to 0 at the half angle.
        const openvdb::Vec3d toX = x - light.position;
        const double length = toX.length();
        const double cosAngle = length > 0.0 ? light.direction.dot(toX) / length : 1.0;
        const double angle = std::acos(std::clamp(cosAngle, -1.0, 1.0)) * 180.0 / M_PI;
        const double outer = 0.5 * light.coneAngleDegrees, inner = outer - light.coneSoftnessDegrees;
        double cone = angle <= inner ? 1.0 : angle >= outer ? 0.0 : (outer - angle) / (outer - inner);
        cone = cone * cone * (3.0 - 2.0 * cone);
        if (cone > 0.0) fromPoint(light.position, power * cone);
        return;
    }
    case Light::Type::Directional: {
        LightSample s;
        s.direction = -light.direction;
        s.fluence = power;
        out.push_back(s);
        return;
    }
    case Light::Type::Environment: {
        // φ = ∫ L T dω ≈ Σ_i T(ω_i) ∫_{cell i} L dω.
        for (std::size_t i = first; i < last; ++i) {
            if (mRadiance[i] == openvdb::Vec3d(0.0)) continue;
            LightSample s;
            s.direction = mDirections[i];
            s.fluence = power * mRadiance[i];
            out.push_back(s);
        }
        return;
    }
    case Light::Type::Area: {
        // Lambertian emitter of radiance L = color·intensity: dφ = L cosθ_l dA f(r).
        const int n = light.samples;
        if (light.shape == Light::Shape::Sphere) {
            const double area = 4.0 * M_PI * light.radius * light.radius;
            for (int i = int(first); i < int(last); ++i) {
                // Stratified in z (equal-area bands) and jittered in angle.
                const double z = 1.0 - 2.0 * (i + unitHash(key, std::uint64_t(i), 1)) / n;
                const double phi = 2.0 * M_PI * unitHash(key, std::uint64_t(i), 2);
                const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
                const openvdb::Vec3d normal(s * std::cos(phi), s * std::sin(phi), z);
                const openvdb::Vec3d q = light.position + light.radius * normal;
                const openvdb::Vec3d toX = x - q;
                const double cosTheta = toX.length() > 0.0 ? normal.dot(toX) / toX.length() : 0.0;
                if (cosTheta > 0.0) fromPoint(q, power * cosTheta * (area / n));
            }
            return;
        }
        openvdb::Vec3d u, v;
        frame(light.direction, u, v);
        const int side = std::max(1, int(std::lround(std::sqrt(double(n)))));
        const int cells = side * side;
        const double area = light.shape == Light::Shape::Disk ? M_PI * light.radius * light.radius : light.width * light.height;
        for (int i = int(first); i < int(last); ++i) {
            const double a = (i % side + unitHash(key, std::uint64_t(i), 3)) / side;
            const double b = (i / side + unitHash(key, std::uint64_t(i), 4)) / side;
            openvdb::Vec3d q;
            if (light.shape == Light::Shape::Disk) {
                const double r = light.radius * std::sqrt(a), phi = 2.0 * M_PI * b; // area-preserving
                q = light.position + r * (std::cos(phi) * u + std::sin(phi) * v);
            } else {
                q = light.position + (a - 0.5) * light.width * u + (b - 0.5) * light.height * v;
            }
            const openvdb::Vec3d toX = x - q;
            const double cosTheta = toX.length() > 0.0 ? light.direction.dot(toX) / toX.length() : 0.0;
            if (cosTheta > 0.0) fromPoint(q, power * cosTheta * (area / cells)); // one-sided emitter
        }
        return;
    }
    case Light::Type::Volume: return;
    }
}

} // namespace vxf
