// vxf — a noise fill: fractal gradient noise over a grid's active voxels (breaking up a flat
// colour or density, as Houdini's Volume VOP noise and Blender's Noise Texture do).
#pragma once

#include <openvdb/openvdb.h>

#include <cstdint>

namespace vxf::ops {

enum class NoiseMode {
    Set, ///< v = offset + amplitude·n
    Add, ///< v + offset + amplitude·n
    Multiply ///< v·(offset + amplitude·n)
};

struct NoiseOptions
{
    double frequency = 4.0; ///< cycles per world unit of the first octave (> 0)
    int octaves = 4; ///< 1 to 12, each twice the frequency (lacunarity) at `gain` the amplitude
    double lacunarity = 2.0, gain = 0.5;
    double amplitude = 1.0, offset = 0.0;
    std::uint32_t seed = 0;
    openvdb::Vec3d shift{0.0}; ///< where the pattern starts (world): moves it without changing it
    NoiseMode mode = NoiseMode::Add;
    /// Vec3 grids: three independent noises, one per channel (seeds seed, seed+1, seed+2); else
    /// the same noise on every channel.
    bool perChannel = false;
};

/// Fractal noise n(x) = Σ_o gain^o·perlin(frequency·lacunarity^o·(x + shift) + (o + 1)·c), c a
/// fixed irrational offset (no octave's lattice zeros on a voxel), normalised by Σ gain^o so that |n| ≤ 1 (Perlin's improved gradient
/// noise, 2002: a fixed permutation of 256 shuffled by the seed, quintic fade), at world point @a x.
double fractalNoise(const openvdb::Vec3d& x, const NoiseOptions& options, std::uint32_t seed);

/// Apply the noise to every active voxel (tiles voxel by voxel) at its centre, or to those
/// @a selection holds (null: all), as options.mode says; values stay finite. Deterministic:
/// the same options give the same bits on any thread count. Throws vxf::UsageError for a
/// frequency ≤ 0 or octaves outside [1, 12].
void noise(openvdb::FloatGrid& grid, const NoiseOptions& options, const openvdb::BoolGrid* selection = nullptr);
void noise(openvdb::Vec3SGrid& grid, const NoiseOptions& options, const openvdb::BoolGrid* selection = nullptr);

} // namespace vxf::ops
