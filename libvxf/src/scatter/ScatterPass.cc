#include <vxf/scatter/ScatterPass.h>

#include <vxf/core/Error.h>
#include <vxf/core/Hash.h>
#include <vxf/core/RandomRotation.h>
#include <vxf/core/SphericalFibonacci.h>
#include <vxf/transport/Phase.h>
#include <vxf/transport/Transmittance.h>
#include <vxf/scatter/SourceField.h>
#include <vxf/scatter/SweepPass.h>

#include <openvdb/math/Mat3.h>
#include <openvdb/tree/LeafManager.h>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <optional>

namespace vxf {

namespace {

/// A uniformly random rotation seeded by the voxel.
openvdb::Mat3d voxelRotation(const openvdb::Coord& c)
{
    const std::uint64_t key = coordKey(c);
    return randomRotation(unitHash(key, 0, 5), unitHash(key, 1, 5), unitHash(key, 2, 5));
}

/// A rotation taking the z axis (the pole of sphericalFibonacci's bands) to @a normal, turned
/// about it by a random angle seeded by the voxel: a surface point's directions split at the
/// surface exactly in half (the bands are symmetric about the equator for an even count), where
/// a random orientation let a skin voxel keep more or fewer of its inward directions by chance
/// (±6% per voxel at 16 directions on a flat face). @a random: turned by the voxel's angle.
openvdb::Mat3d surfaceRotation(const openvdb::Coord& c, const openvdb::Vec3d& normal, bool random)
{
    const openvdb::Vec3d helper = std::abs(normal.x()) < 0.9 ? openvdb::Vec3d(1.0, 0.0, 0.0) : openvdb::Vec3d(0.0, 1.0, 0.0);
    const openvdb::Vec3d t1 = normal.cross(helper).unit(), t2 = normal.cross(t1);
    const double psi = random ? 2.0 * M_PI * unitHash(coordKey(c), 3, 5) : 0.0;
    const openvdb::Vec3d a = t1 * std::cos(psi) + t2 * std::sin(psi), b = t2 * std::cos(psi) - t1 * std::sin(psi);
    openvdb::Mat3d r;
    r.setColumns(a, b, normal);
    return r;
}

/// The scattered light's J at a step's middle from the parabola through its values at the
/// previous step's start (@a jBefore, @a a voxels before the step) and this step's ends (@a
/// jStart, @a jEnd, @a b voxels apart): Lagrange weights at b/2, (−b², (2a + b)(a + b),
/// (2a + b)·a) / 4a(a + b); (−1, 6, 3)/8 for equal steps.
openvdb::Vec3d parabolaMiddle(const openvdb::Vec3d& jBefore, const openvdb::Vec3d& jStart, const openvdb::Vec3d& jEnd, double a, double b)
{
    const double scale = 1.0 / (4.0 * a * (a + b));
    return jBefore * (-b * b * scale) + jStart * ((2.0 * a + b) * (a + b) * scale) + jEnd * ((2.0 * a + b) * a * scale);
}

/// The previous step must be at least this long, relative to the step, for parabolaMiddle: its
/// weight on J before grows as b/a (a step clipped short by the surface would amplify J's noise).
constexpr double kJoinedFraction = 0.5;

/// The thesis's gather at one voxel: φ(x) = Σ over the direction set of the radiance marched
/// in from the medium's bounds, J read from the continued field or fraction-weighted from the grid.
struct VoxelGather
{
    const Medium& medium;
    const ScatterPassOptions& options;
    const std::vector<openvdb::Vec3d> directions = sphericalFibonacci(options.directions);
    const double weight = 4.0 * M_PI / double(directions.size());
    const double dx = medium.voxelSize();
    const double h = std::max(options.step, 1e-3);
    const double tauCutoff = -std::log(std::max(options.cutoff, std::numeric_limits<double>::min()));
    const bool empty = medium.activeBounds().empty();
    const openvdb::BBoxd bounds = marchBounds(medium);
    // J quadratic along each step where the medium ends at a surface; without one (coarse
    // lattices, fixtures) its edge is the trilinear density ramp, over which σt, taken at the
    // step's midpoint, varies as much as J: J at the ends then gives a boundary voxel too much
    // of its own light (a 4x coarser bunny lattice leaked 1.3% per pass instead of 3%, and its
    // series no longer matched the fine one's), so J is taken at the midpoint there.
    const bool quadratic = medium.surface() != nullptr;

    openvdb::Vec3f operator()(Medium::Sampler& sampler, const std::optional<SourceField::Sampler>& field,
        const GridLookup<openvdb::Vec3SGrid>& grid, const openvdb::Coord& c) const
    {
        openvdb::Vec3d x = c.asVec3d(), normal;
        openvdb::Mat3d rotation = openvdb::Mat3d::identity();
        if (sampler.skinPoint(c, x, normal)) {
            rotation = surfaceRotation(c, normal, options.rotatePerVoxel);
        } else if (options.rotatePerVoxel) {
            rotation = voxelRotation(c);
        }
        openvdb::Vec3d phi(0.0);
        for (const openvdb::Vec3d& d0 : directions) phi += radianceAlong(sampler, field, grid, x, rotation * d0);
        phi *= weight;
        for (int ch = 0; ch < 3; ++ch) {
            if (!std::isfinite(phi[ch])) phi[ch] = 0.0; // never let NaN/Inf into a grid
        }
        return openvdb::Vec3f(phi);
    }

    /// The radiance arriving at @a x from direction @a d (the march from the medium's bounds).
    openvdb::Vec3d radianceAlong(Medium::Sampler& sampler, const std::optional<SourceField::Sampler>& field,
        const GridLookup<openvdb::Vec3SGrid>& grid, const openvdb::Vec3d& x, const openvdb::Vec3d& d) const
    {
        double tEntry = 0.0, tExit = std::numeric_limits<double>::max();
        if (empty || !clipRay(bounds, x, d, tEntry, tExit)) return openvdb::Vec3d(0.0);
        openvdb::Vec3d radiance(0.0), T(1.0), tau(0.0);
        const int steps = std::max(1, int(std::ceil(tExit / h)));
        const double hStep = tExit / steps;
        InsideSteps inside(sampler, x, d, 0.0, hStep);
        InsideStep step;
        openvdb::Vec3d jStart(0.0), jEnd(0.0); // J at the step's ends
        openvdb::Vec3d jBefore(0.0); // J at the previous step's start
        double lengthBefore = 0.0; // the previous step's length, when this one joins it
        const auto sourceAt = [&](const openvdb::Vec3d& p, double interior) {
            return field ? field->sample(p) : openvdb::Vec3d(grid.sampleTrilinear(p)) * interior;
        };
        for (int i = 0; i < steps; ++i) {
            // Only the part of each step inside the surface holds medium (sharp boundary).
            if (!inside.next(step)) {
                lengthBefore = 0.0;
                continue;
            }
            openvdb::Vec3d jMiddle;
            if (quadratic) {
                const auto interiorAt = [&](const openvdb::Vec3d& p) { return field ? 1.0 : sampler.interiorScale(p, step.distanceBound); };
                if (!step.joined) lengthBefore = 0.0;
                jStart = step.joined ? jEnd : sourceAt(step.start, interiorAt(step.start));
                jEnd = sourceAt(step.end, interiorAt(step.end));
                if (field && lengthBefore >= kJoinedFraction * step.length) {
                    jMiddle = parabolaMiddle(jBefore, jStart, jEnd, lengthBefore, step.length);
                } else {
                    jMiddle = sourceAt(step.midpoint, step.interior);
                }
                jBefore = jStart;
                lengthBefore = step.length;
            } else {
                jStart = jEnd = jMiddle = sourceAt(step.midpoint, step.interior);
            }
            const double hWorld = step.length * dx;
            const openvdb::Vec3d sigmaT = sampler.sigmaT(step.midpoint) * step.interior;
            // ΔL = T·∫ J(s) e^{−σt s} ds (J quadratic along the step); T ·= e^{−σt h}.
            const std::array<EmissionWeights, 3> w = emissionWeights(sigmaT, hWorld);
            for (int ch = 0; ch < 3; ++ch) {
                radiance[ch] += T[ch] * emissionIntegral(w[ch], jStart[ch], jMiddle[ch], jEnd[ch]);
                T[ch] *= w[ch].transmittance;
                tau[ch] += std::max(0.0, sigmaT[ch]) * hWorld;
            }
            if (std::min({tau[0], tau[1], tau[2]}) > tauCutoff) {
                // What lies beyond: J held at the step's end over an unbounded medium, T·J/σt,
                // unless the step ended at the surface or the march's end (nothing beyond).
                if (i + 1 < steps && step.length > hStep * (1.0 - 1e-9)) {
                    for (int ch = 0; ch < 3; ++ch) {
                        if (sigmaT[ch] > 0.0) radiance[ch] += T[ch] * jEnd[ch] / sigmaT[ch];
                    }
                }
                break;
            }
        }
        return radiance;
    }
};

} // namespace

std::string defaultScatterKernel(double phaseG) { return transportScaling(phaseG).restG() != 0.0 ? "sweep" : "gather"; }

ScatterKernel scatterKernelNamed(const std::string& name)
{
    if (name == "gather") return ScatterKernel::Gather;
    if (name == "sweep") return ScatterKernel::Sweep;
    throw UsageError(fmt::format("unknown scatter kernel '{}' (gather or sweep)", name));
}

openvdb::Vec3SGrid::Ptr scatterPass(
    const Medium& medium, const openvdb::Vec3SGrid& source, const ScatterPassOptions& options, Interrupter* interrupter)
{
    if (options.kernel == ScatterKernel::Sweep) return sweepPass(medium, source, options, interrupter);
    InterruptStep step(interrupter, "scattering");
    auto fluence = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    fluence->setName("fluence");
    fluence->setTransform(source.transformPtr()->copy());
    fluence->tree().topologyUnion(source.tree());
    if (options.directions < 1) return fluence;

    const VoxelGather gather{medium, options};

    std::optional<SourceField> sourceField;
    std::shared_ptr<const DenseCopy<openvdb::Vec3SGrid>> sourceDense;
    if (options.source == ScatterPassOptions::SourceRead::Continued)
        sourceField.emplace(medium, source, SourceField::Near::Lattice);
    else
        sourceDense = DenseCopy<openvdb::Vec3SGrid>::create(source, kDenseCopyMargin, kDenseCopyBytes);
    openvdb::tree::LeafManager<openvdb::Vec3STree> leaves(fluence->tree());
    std::vector<openvdb::CoordBBox> tiles;
    for (auto it = fluence->tree().cbeginValueOn(); it; ++it) {
        if (it.isTileValue()) {
            openvdb::CoordBBox box;
            it.getBoundingBox(box);
            tiles.push_back(box);
        }
    }
    const std::size_t leafCount = leaves.leafCount(), total = leafCount + tiles.size();
    std::vector<openvdb::Vec3f> tileValues(tiles.size());
    std::atomic<std::size_t> done{0};
    std::atomic<bool> cancelled{false};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, total, 1), [&](const tbb::blocked_range<std::size_t>& range) {
        Medium::Sampler sampler(medium);
        std::optional<SourceField::Sampler> field;
        if (sourceField) field.emplace(*sourceField);
        const GridLookup<openvdb::Vec3SGrid> grid(source, sourceDense.get());
        for (std::size_t item = range.begin(); item != range.end() && !cancelled; ++item) {
            if (item < leafCount) {
                for (auto it = leaves.leaf(item).beginValueOn(); it; ++it) it.setValue(gather(sampler, field, grid, it.getCoord()));
            } else {
                const openvdb::CoordBBox& box = tiles[item - leafCount];
                tileValues[item - leafCount] = gather(sampler, field, grid, box.min() + openvdb::Coord(box.dim().x() / 2));
            }
            const std::size_t finished = ++done;
            if (interrupter && interrupter->wasInterrupted(int(100 * finished / std::max<std::size_t>(total, 1)))) cancelled = true;
        }
    });
    if (cancelled) throw Interrupted();
    for (std::size_t t = 0; t < tiles.size(); ++t) fluence->tree().fill(tiles[t], tileValues[t], true);
    return fluence;
}

} // namespace vxf
