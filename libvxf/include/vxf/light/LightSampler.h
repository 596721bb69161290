// vxf — how the light of one scene light arrives at a point: a set of directional samples.
#pragma once

#include <vxf/core/Scene.h>

#include <cstdint>
#include <limits>
#include <vector>

namespace vxf {

/// Light arriving at a point from one sample of a light, before any attenuation.
struct LightSample
{
    openvdb::Vec3d direction; ///< unit, world space: from the point toward the light
    double distance = std::numeric_limits<double>::infinity(); ///< to the emitting point (∞: from outside the scene)
    openvdb::Vec3d fluence{0.0}; ///< its share of the unattenuated fluence (= irradiance at normal incidence)
};

/// The samples of one light, per DESIGN.md's direct stage:
/// - point: I·f(r) from the light's position; spot: the same × the cone factor (1 inside
///   half angle − softness, smoothstep to 0 at the half angle);
/// - directional: E from −direction;
/// - area (rectangle, disk, sphere): Lambertian emitter of radiance L, samples
///   L·cosθ_l·(A/N)·f(r) stratified over its surface and jittered by @a key;
/// - environment: (4π/N)·L over N spherical Fibonacci directions for a constant colour;
///   with a lat-long map, each direction carries ∫ L dω over the texels nearest to it (the
///   map's energy is kept exactly, whatever N);
/// - volume: none (a volume light is a source, see computeDirectLight).
/// f(r) is the falloff (1/r², 1/r or 1), r never below @a minDistance (no division by zero).
/// Construction reads an environment map (throws vxf::InputError naming the file);
/// afterwards read-only, safe from any thread.
class LightSampler
{
public:
    explicit LightSampler(const Light& light);

    const Light& light() const { return mLight; }

    /// How many samples the light gives a point (before those that carry nothing are left
    /// out): 1 for point, spot and directional lights, N for area and environment lights.
    std::size_t count() const;

    /// Replace @a out with the samples of light arriving at world point @a x, of the sample
    /// numbers [@a first, @a last) only (e.g. one of them, chosen at random and weighted by
    /// count()); samples that carry nothing (behind an area light, black texels) are left out.
    void sample(const openvdb::Vec3d& x, std::uint64_t key, double minDistance, std::vector<LightSample>& out, std::size_t first = 0,
        std::size_t last = std::numeric_limits<std::size_t>::max()) const;

private:
    Light mLight;
    std::vector<openvdb::Vec3d> mDirections, mRadiance; ///< environment: directions and ∫ L dω per direction
};

/// The direction (unit, +Z up) of lat-long map coordinates u, v ∈ [0, 1] (v = 0: the top row,
/// looking up; u = 0.5: looking along +X; u grows toward −Y) — Blender's convention.
openvdb::Vec3d latLongDirection(double u, double v);

} // namespace vxf
