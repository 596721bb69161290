// vxf — one scattering pass (source iteration): fluence gathered from a source grid.
#pragma once

#include <vxf/core/Interrupter.h>
#include <vxf/core/StageDefaults.h>
#include <vxf/transport/Medium.h>

#include <cstdint>
#include <string>

namespace vxf {

/// How a pass carries the source's light to every voxel: the thesis's per-voxel gather (a ray
/// march per voxel and direction, below) or discrete-ordinates sweeps (sweepPass, SweepPass.h:
/// one upwind pass over the tree per direction).
enum class ScatterKernel { Gather, Sweep };

/// The kernel called @a name ("gather" or "sweep"); throws vxf::UsageError naming the choices.
ScatterKernel scatterKernelNamed(const std::string& name);

/// The kernel's name for a medium of Henyey-Greenstein @a phaseG when none is named: "sweep"
/// for a forward-scattering phase (its anisotropy only the accelerated sweeps carry, Phase.h),
/// "gather" otherwise.
std::string defaultScatterKernel(double phaseG);

struct ScatterPassOptions
{
    ScatterKernel kernel = ScatterKernel::Gather;
    int directions = defaults::kDirections; ///< spherical Fibonacci directions per voxel (weights 4π/N)
    /// Sweep kernel: the whole direction set is turned by a random rotation seeded by this
    /// (deterministic; 0: unturned), so that passes with other seeds put their ray effects
    /// elsewhere. The gather turns its set per voxel instead (rotatePerVoxel).
    std::uint64_t rotationSeed = 0;
    double step = defaults::kStep; ///< march step in voxels
    /// A march stops when the transmittance of every channel is below this, and adds what lies
    /// beyond as J held at that point over an unbounded medium, T·J/σt (not where its last step
    /// ended at the surface). Without that, every pass lost a share `cutoff` of the light deep
    /// inside, which albedo 0.99 compounds about 40-fold. 1e-3 costs 0.01 point of error against
    /// 1e-4 for 15% less time; above 1e-2, J held constant is too crude (docs/accuracy-notes.md,
    /// "Behind the code: ScatterPass").
    double cutoff = defaults::kScatterCutoff;
    bool rotatePerVoxel = true; ///< rotate the direction set per voxel (deterministic hash): noise, not banding
    /// How the gathers read the source near a surface. Continued (SourceField): sources made
    /// from a pass's fluence. FractionWeighted: σs·φ interpolated and divided by the
    /// interpolated volume fraction (Medium::Sampler::interiorScale), for the lights' source J0,
    /// which varies along the surface within a voxel near the terminator. The same without a
    /// surface (trilinear).
    enum class SourceRead { Continued, FractionWeighted } source = SourceRead::Continued;
};

/// One pass of the kernel options.kernel names: the gather below, or sweepPass (SweepPass.h).
///
/// The gather kernel: φ(x) = Σ_i (4π/N) ∫_0^{d_i} T(x, x+tω_i) J(x+tω_i) dt, rays stopping at
/// the medium's bounds (index-matched boundary), x a voxel's centre or, in the surface's skin
/// (centre within half a voxel of it, either side), its nearest surface point
/// (Medium::Sampler::skinPoint: SourceField reads the skin as J on the surface), where the
/// direction set's pole is turned to the normal so that it splits exactly in half there.
/// Each march step takes σt constant and J quadratic through its values at the step's start,
/// middle and end, and integrates exactly:
/// ΔL = T·∫ J(s) e^{−σt s} ds (emissionWeights), T ·= e^{−σt h}; finite for any σt ≥ 0, never
/// NaN (J constant at the midpoint, as the shared design had it, is several percent low where the
/// light falls off within a step). The scattered light (a Continued source) varies over the
/// diffusion length, not the mean free path: where a step joins one at least half as long, its
/// middle J is the parabola's through the previous step's start and its own ends (one source
/// read a step instead of two); the lights' J0, which falls off over a mean free path, is read
/// at every middle (docs/accuracy-notes.md, "Behind the code: ScatterPass"). Output: a Vec3f grid named
/// "fluence" on @a source's topology (active tiles evaluated at their centre). Parallel over
/// leaves and tiles; every voxel is computed alone, so results do not depend on the thread count.
/// Cost: active voxels × directions × steps per ray (about −ln(cutoff)/(σt·dx·step) in thick media).
openvdb::Vec3SGrid::Ptr scatterPass(
    const Medium& medium, const openvdb::Vec3SGrid& source, const ScatterPassOptions& options = {}, Interrupter* interrupter = nullptr);

} // namespace vxf
