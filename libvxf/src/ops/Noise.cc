#include <vxf/ops/Noise.h>

#include "Dispatch.h"

#include <openvdb/tree/LeafManager.h>

#include <array>
#include <cmath>
#include <numeric>
#include <random>

namespace vxf::ops {

namespace {

/// Perlin's permutation, shuffled by @a seed, doubled to skip a wrap.
std::array<int, 512> permutationOf(std::uint32_t seed)
{
    std::array<int, 256> p;
    std::iota(p.begin(), p.end(), 0);
    std::mt19937 random(seed);
    // Fisher–Yates by mt19937's own output (its distributions differ between standard libraries).
    for (int i = 255; i > 0; --i) std::swap(p[std::size_t(i)], p[random() % std::uint32_t(i + 1)]);
    std::array<int, 512> doubled;
    for (std::size_t i = 0; i < 512; ++i) doubled[i] = p[i & 255];
    return doubled;
}

double fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }
double lerp(double t, double a, double b) { return a + t * (b - a); }
double grad(int hash, double x, double y, double z)
{
    const int h = hash & 15;
    const double u = h < 8 ? x : y, v = h < 4 ? y : h == 12 || h == 14 ? x : z;
    return ((h & 1) == 0 ? u : -u) + ((h & 2) == 0 ? v : -v);
}

/// Perlin's improved noise (2002) at @a q, in [-1, 1].
double perlin(const std::array<int, 512>& p, openvdb::Vec3d q)
{
    const double fx = std::floor(q[0]), fy = std::floor(q[1]), fz = std::floor(q[2]);
    const int X = int(std::fmod(fx, 256.0) + 256.0) & 255, Y = int(std::fmod(fy, 256.0) + 256.0) & 255,
              Z = int(std::fmod(fz, 256.0) + 256.0) & 255;
    const double x = q[0] - fx, y = q[1] - fy, z = q[2] - fz;
    const double u = fade(x), v = fade(y), w = fade(z);
    const int A = p[X] + Y, AA = p[A] + Z, AB = p[A + 1] + Z, B = p[X + 1] + Y, BA = p[B] + Z, BB = p[B + 1] + Z;
    return lerp(w,
        lerp(v, lerp(u, grad(p[AA], x, y, z), grad(p[BA], x - 1, y, z)), lerp(u, grad(p[AB], x, y - 1, z), grad(p[BB], x - 1, y - 1, z))),
        lerp(v, lerp(u, grad(p[AA + 1], x, y, z - 1), grad(p[BA + 1], x - 1, y, z - 1)),
            lerp(u, grad(p[AB + 1], x, y - 1, z - 1), grad(p[BB + 1], x - 1, y - 1, z - 1))));
}

void checkNoise(const NoiseOptions& o)
{
    if (!(o.frequency > 0.0)) throw UsageError(fmt::format("noise: frequency {} must be > 0", o.frequency));
    if (o.octaves < 1 || o.octaves > 12) throw UsageError(fmt::format("noise: octaves {} must be in [1, 12]", o.octaves));
}

double noiseWith(const std::array<int, 512>& p, const openvdb::Vec3d& x, const NoiseOptions& o)
{
    // Each octave's lattice is moved off the others' (and off the voxels of a grid whose
    // voxel size divides 1/frequency, where gradient noise is 0 on its lattice points).
    const openvdb::Vec3d latticeOffset(0.6180339887, 0.4142135624, 0.7320508076);
    double sum = 0.0, norm = 0.0, amplitude = 1.0, frequency = o.frequency;
    for (int i = 0; i < o.octaves; ++i) {
        sum += amplitude * perlin(p, (x + o.shift) * frequency + latticeOffset * double(i + 1));
        norm += amplitude;
        amplitude *= o.gain;
        frequency *= o.lacunarity;
    }
    return norm > 0.0 ? std::clamp(sum / norm, -1.0, 1.0) : 0.0;
}

double applied(NoiseMode mode, double v, double n)
{
    switch (mode) {
    case NoiseMode::Set: return n;
    case NoiseMode::Add: return v + n;
    case NoiseMode::Multiply: return v * n;
    }
    return v;
}

/// Set every active voxel of @a grid to fn(world centre, value): those @a selection holds (one by
/// one: a tile splits only where it is selected), or all of them (tiles voxelized, in parallel
/// over leaves).
template <typename GridT, typename Fn>
void forActiveVoxels(GridT& grid, const openvdb::BoolGrid* selection, const Fn& fn)
{
    if (selection) {
        if (selection->transform() != grid.transform()) {
            throw UsageError(fmt::format("noise: the selection does not share grid '{}''s transform", grid.getName()));
        }
        auto values = grid.getAccessor();
        for (auto it = selection->cbeginValueOn(); it; ++it) {
            for (auto c = it.getBoundingBox().begin(); c; ++c) {
                if (values.isValueOn(*c)) values.setValue(*c, fn(grid.transform().indexToWorld(*c), values.getValue(*c)));
            }
        }
        return;
    }
    grid.tree().voxelizeActiveTiles();
    openvdb::tree::LeafManager<typename GridT::TreeType> leaves(grid.tree());
    leaves.foreach ([&](typename GridT::TreeType::LeafNodeType& leaf, std::size_t) {
        for (auto it = leaf.beginValueOn(); it; ++it) it.setValue(fn(grid.transform().indexToWorld(it.getCoord()), *it));
    });
}

} // namespace

double fractalNoise(const openvdb::Vec3d& x, const NoiseOptions& options, std::uint32_t seed)
{
    checkNoise(options);
    return noiseWith(permutationOf(seed), x, options);
}

void noise(openvdb::FloatGrid& grid, const NoiseOptions& o, const openvdb::BoolGrid* selection)
{
    checkNoise(o);
    const auto p = permutationOf(o.seed);
    forActiveVoxels(grid, selection,
        [&](const openvdb::Vec3d& x, float v) { return detail::finite(applied(o.mode, v, o.offset + o.amplitude * noiseWith(p, x, o))); });
}

void noise(openvdb::Vec3SGrid& grid, const NoiseOptions& o, const openvdb::BoolGrid* selection)
{
    checkNoise(o);
    const std::array<std::array<int, 512>, 3> p{permutationOf(o.seed), permutationOf(o.seed + 1), permutationOf(o.seed + 2)};
    forActiveVoxels(grid, selection, [&](const openvdb::Vec3d& x, const openvdb::Vec3f& v) {
        openvdb::Vec3f out;
        const double shared = o.perChannel ? 0.0 : noiseWith(p[0], x, o);
        for (int c = 0; c < 3; ++c) {
            const double n = o.perChannel ? noiseWith(p[c], x, o) : shared;
            out[c] = detail::finite(applied(o.mode, v[c], o.offset + o.amplitude * n));
        }
        return out;
    });
}

} // namespace vxf::ops
