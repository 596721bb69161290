#include <vxf/scatter/Scatter.h>

#include "SourceIteration.h"
#include "transport/lattice/SweepLattice.h"

#include <vxf/core/GridRoles.h>
#include <vxf/core/MemoryBudget.h>
#include <vxf/transport/Phase.h>

#include <vxf/transport/AdaptiveBand.h>
#include <vxf/scatter/CoarseLevel.h>

#include <vxf/core/Error.h>
#include <vxf/light/InteriorField.h>

#include <openvdb/tools/Composite.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/ValueTransformer.h>
#include <openvdb/tree/LeafManager.h>

#include <fmt/format.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

namespace vxf {

ScatterOptions scatterOptionsFrom(const SceneSettings& s)
{
    ScatterOptions o;
    o.passes = s.passes;
    o.tolerance = s.tolerance;
    o.extrapolateTail = s.extrapolate;
    o.keepPasses = std::find(s.outputs.begin(), s.outputs.end(), "scatter_passes") != s.outputs.end();
    o.pass.directions = s.directions;
    o.pass.step = s.step;
    o.pass.cutoff = s.cutoff;
    o.band = s.scatterBand;
    o.finePasses = s.finePasses;
    o.coarseFactor = s.coarseFactor;
    o.pass.kernel = scatterKernelNamed(s.kernel);
    o.accelerate = s.accelerate;
    return o;
}

openvdb::Vec3d gridEnergy(const openvdb::Vec3SGrid& grid)
{
    openvdb::Vec3d sum(0.0);
    for (auto it = grid.cbeginValueOn(); it; ++it) {
        sum += openvdb::Vec3d(*it) * double(it.getVoxelCount());
    }
    return sum;
}

MemoryEstimate scatterMemory(double voxels) { return stageMemory(kStageFixedBytes, voxels, kScatterBytesPerVoxel); }

MemoryEstimate bandedScatterMemory(double voxels, double swept)
{
    MemoryEstimate e = stageMemory(kStageFixedBytes, swept, kBandedScatterBytesPerSweptVoxel);
    e.bytes += voxels * kBandedScatterBytesPerActiveVoxel;
    e.how = fmt::format("{:.3g} swept voxels × {:.0f} bytes + {:.3g} active voxels × {:.0f} bytes + {:.0f} MiB", swept,
        kBandedScatterBytesPerSweptVoxel, voxels, kBandedScatterBytesPerActiveVoxel, kStageFixedBytes / (1024.0 * 1024.0));
    return e;
}

namespace {

/// The voxels a sweep over @a source's leaves and tiles holds with coarse cells: the leaves'
/// voxels, and of a tile's voxels one a cell where its 8³ blocks are thin enough to be cells
/// (SweepLattice::thinEnoughForCell, at the tile's centre), every one where not.
double sweptWithCoarseCells(const openvdb::Vec3SGrid& source, const Medium& medium)
{
    double swept = double(source.tree().leafCount()) * detail::SweepLattice::kLeafVoxels;
    Medium::Sampler sampler(medium);
    for (auto it = source.tree().cbeginValueOn(); it; ++it) {
        if (it.isVoxelValue()) continue;
        openvdb::CoordBBox box;
        it.getBoundingBox(box);
        const openvdb::Coord centre = box.min() + openvdb::Coord(box.dim().x() / 2 - 4);
        const bool cells = detail::SweepLattice::thinEnoughForCell(sampler, centre);
        swept += double(it.getVoxelCount()) / (cells ? double(detail::SweepLattice::kLeafVoxels) : 1.0);
    }
    return swept;
}

/// Whether scatter() solves the whole sum at once (sweeps or gathers with acceleration), not
/// pass by pass.
bool solvesWhole(const ScatterOptions& options)
{
    return options.accelerate && options.fromPass == 0 && !options.keepPasses && options.finePasses == 0;
}

/// The accelerated solve's iterations as the report's passes.
std::vector<ScatterReport::Pass> passesOf(const SweepSolveReport& solved)
{
    std::vector<ScatterReport::Pass> passes;
    for (const auto& it : solved.iterations) {
        ScatterReport::Pass info;
        info.index = it.index;
        info.energy = it.energy;
        info.ratio = it.ratio;
        info.seconds = it.seconds;
        info.change = it.change;
        info.diffusionIterations = it.diffusionIterations;
        info.correctionSweeps = it.correctionSweeps;
        info.sweepSeconds = it.sweepSeconds;
        passes.push_back(info);
    }
    return passes;
}

/// The lowest channel of @a grid's active values and the highest (tiles and voxels), in parallel
/// over its leaves: no serial pass over a solve's hundred million voxels.
std::pair<float, float> channelRange(const openvdb::Vec3SGrid& grid)
{
    using Range = std::pair<float, float>;
    const auto widen = [](Range r, const openvdb::Vec3f& v) {
        return Range{std::min({r.first, v[0], v[1], v[2]}), std::max({r.second, v[0], v[1], v[2]})};
    };
    const Range none{std::numeric_limits<float>::max(), std::numeric_limits<float>::lowest()};
    Range range = none;
    for (auto it = grid.tree().cbeginValueOn(); it; ++it) {
        if (!it.isVoxelValue()) range = widen(range, *it); // the tiles (few)
    }
    openvdb::tree::LeafManager<const openvdb::Vec3STree> leaves(grid.tree());
    const Range voxels = tbb::parallel_reduce(
        leaves.leafRange(), none,
        [&](const auto& r, Range found) {
            for (auto leaf = r.begin(); leaf; ++leaf) {
                for (auto v = leaf->cbeginValueOn(); v; ++v) found = widen(found, *v);
            }
            return found;
        },
        [](const Range& a, const Range& b) {
            return Range{std::min(a.first, b.first), std::max(a.second, b.second)};
        });
    return {std::min(range.first, voxels.first), std::max(range.second, voxels.second)};
}

/// The scattered light of a source that is nowhere negative is nowhere negative (each term of
/// the series K S … K J ≥ 0): a value of @a sum below zero is an overshoot of an accelerated
/// solve's correction (the diffusion correction or the gathers' sweeps, in voxels many mean free
/// paths thick), set to zero here; what was set is said ("" when nothing was). A source an
/// artist made negative somewhere scatters as the linear operator has it, negative light kept.
std::string clampedBelowZero(openvdb::Vec3SGrid& sum, const openvdb::Vec3SGrid& source)
{
    const auto [lowest, largest] = channelRange(sum);
    if (!(lowest < 0.0f) || channelRange(source).first < 0.0f) return {};
    openvdb::tools::foreach (sum.beginValueOn(), [](const openvdb::Vec3SGrid::ValueOnIter& it) {
        const openvdb::Vec3f v = *it;
        it.setValue(openvdb::Vec3f(std::max(v[0], 0.0f), std::max(v[1], 0.0f), std::max(v[2], 0.0f)));
    });
    return fmt::format("; values below zero (down to {:.3g}, {:.2g} of the largest) set to zero", lowest,
        largest > 0.0f ? -double(lowest) / double(largest) : 0.0);
}

} // namespace

bool carriesFirstMoment(const ScatterOptions& options) { return solvesWhole(options) && options.pass.kernel == ScatterKernel::Sweep; }

Medium scatterMedium(const VoxelSet& set, const Material& material, const ScatterOptions& options)
{
    const bool latticeOnly = carriesFirstMoment(options); // (the same rule: the lattice alone serves the whole solve's sweeps)
    return Medium(set, material, latticeOnly ? Medium::Lookups::Trees : Medium::Lookups::Dense);
}

ScatterReport scatter(VoxelSet& set, const Medium& transport, const ScatterOptions& options, Interrupter* interrupter)
{
    const bool solveWhole = solvesWhole(options);
    const bool sweeps = options.pass.kernel == ScatterKernel::Sweep;
    const bool coarseCells = solveWhole && sweeps && options.band > 0.0 && options.fromPass == 0;
    const double activeVoxels = double(transport.density().activeVoxelCount());
    if (!coarseCells) requireMemory("scatter", scatterMemory(activeVoxels)); // (with coarse cells: once the band has made its tiles)
    ScatterReport report;
    // An anisotropic rest of the phase (g* ≠ 0, Phase.h) only the accelerated sweep solve
    // carries, as a first moment, from a source lit with it (`scatter_source_anisotropy`). Every
    // other way takes the similarity relation's isotropic medium: a source lit so as it is; one
    // lit with the moment in the share 1 − g* that leaves isotropically under the relation (a
    // volume light's emission scaled alike).
    const double restG = transport.material().phaseG;
    const bool litWithMoment = restG != 0.0 && set.find(grids::kSourceAnisotropy);
    const bool carriesMoment = carriesFirstMoment(options) && litWithMoment;
    const Medium medium = carriesMoment ? transport : transport.isotropic();
    const float sourceScale = litWithMoment && !carriesMoment ? float(1.0 - restG) : 1.0f;
    openvdb::Vec3SGrid::Ptr sum, j;
    int k = options.fromPass;
    if (k == 0) {
        // The file's scatter_source stays as it was: a band coarsens a copy as it makes it (none
        // where the light stage's band made it so already), a scale scales a copy.
        j = set.get<openvdb::Vec3SGrid>(grids::kScatterSource);
        bool copied = false;
        if (options.band > 0.0) {
            if (auto coarse = coarsenedBeyondBand(*j, medium.density(), options.band, report.band)) {
                j = coarse;
                copied = true;
            }
        }
        if (sourceScale != 1.0f && !copied) j = j->deepCopy();
        if (sourceScale != 1.0f) {
            openvdb::tools::foreach (
                j->beginValueAll(), [sourceScale](const openvdb::Vec3SGrid::ValueAllIter& it) { it.setValue(*it * sourceScale); });
        }
        if (!(options.band > 0.0)) report.band = coarsenBeyondBand(*j, medium.density(), 0.0); // its counts
        if (coarseCells) requireMemory("scatter", bandedScatterMemory(activeVoxels, sweptWithCoarseCells(*j, medium)));
    } else {
        sum = set.get<openvdb::Vec3SGrid>("scatter_pass_1")->deepCopy();
        for (int p = 2; p <= k; ++p) {
            auto pass = set.get<openvdb::Vec3SGrid>(fmt::format("scatter_pass_{}", p))->deepCopy();
            openvdb::tools::compSum(*sum, *pass);
        }
        j = sourceFromFluence(medium, *set.get<openvdb::Vec3SGrid>(fmt::format("scatter_pass_{}", k)));
        report.band = coarsenBeyondBand(*j, medium.density(), options.band);
    }

    const bool scatters = detail::maxChannel(medium.material().sigmaS) > 0.0 || set.find(grids::kSigmaS);
    if (options.finePasses > 0 && options.coarseFactor != 2 && options.coarseFactor != 4 && options.coarseFactor != 8) {
        throw UsageError(fmt::format("coarse factor must be 2, 4 or 8, got {}", options.coarseFactor));
    }
    // A sum of zeros on the source's voxels, made only where it is used (a whole solve makes its
    // own: holding this one through it took 12 bytes a voxel).
    const auto zeroSum = [&j] {
        openvdb::Vec3SGrid::Ptr zeros = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
        zeros->setTransform(j->transformPtr());
        zeros->tree().topologyUnion(j->tree());
        return zeros;
    };
    SweepMoments moments; // of an anisotropic rest
    if (!scatters) {
        if (k == 0) sum = zeroSum();
        report.stopReason = "the medium does not scatter (sigma_s = 0)";
    } else if (options.passes == 0 && options.fromPass == 0) {
        // No pass: single scattering alone (the image's direct layer), `scatter` zero.
        sum = zeroSum();
        report.stopReason = "passes 0: no multiple scattering (single scattering alone)";
    } else if (solveWhole) {
        // The whole sum at once: sweeps or gathers with diffusion synthetic acceleration.
        SweepSolveOptions solve;
        solve.maxSweeps = options.passes;
        solve.tolerance = options.tolerance > 0.0 ? options.tolerance : 1e-6;
        solve.directions = options.pass.directions;
        solve.kernel = options.pass.kernel;
        solve.gather = options.pass;
        solve.coarseTiles = options.band > 0.0; // the band's tiles swept as cells
        if (options.warmStart && options.warmStart->transform() == j->transform()) solve.initial = options.warmStart.get();
        report.warmStarted = solve.initial != nullptr;
        SweepSolveReport solved;
        if (carriesMoment) {
            moments.source = set.get<openvdb::Vec3SGrid>(grids::kSourceAnisotropy).get();
            if (moments.source->transform() != j->transform()) { // read on the source's voxels
                throw Error(fmt::format("grid '{}' does not share the transform of 'scatter_source'", grids::kSourceAnisotropy));
            }
        }
        sum = sweepSolve(medium, *j, solve, solved, interrupter, &moments);
        report.passes = passesOf(solved);
        report.accelerated = true;
        report.sweptVoxels = solved.voxels;
        report.diffusionUnknowns = solved.diffusionUnknowns;
        report.diffusionCoarsening = solved.diffusionCoarsening;
        report.setupSeconds = solved.setupSeconds;
        report.stopReason = fmt::format("accelerated {} (each {} corrects the whole sum; it is not one scattering order): {}",
            sweeps ? "sweeps" : "gathers", sweeps ? "sweep" : "pass", solved.stopReason);
    } else {
        if (k == 0) sum = zeroSum();
        detail::iterateSources(set, medium, options, report, interrupter, sum, j, k);
    }

    report.stopReason += clampedBelowZero(*sum, *j);
    sum->setName(grids::kScatter);
    set.put(sum);
    if (moments.scattered) {
        set.put(moments.scattered);
    } else {
        set.remove(grids::kScatterAnisotropy); // isotropic now
    }
    putIllumination(set);
    return report;
}

VoxelSetReadOptions scatterInputRead()
{
    VoxelSetReadOptions options;
    options.wanted = [](const std::string& name) { return name != grids::kDirect; };
    // The light the solve and `illumination` carry (a pass's fluence too, when it goes on from one).
    options.finite = [](const std::string& name) {
        return name == grids::kScatterSource || name == grids::kSourceAnisotropy || name == grids::kDirect ||
            name.rfind("scatter_pass_", 0) == 0;
    };
    return options;
}

void putIllumination(VoxelSet& set)
{
    const auto direct = set.find(grids::kDirect);
    const auto scattered = set.find(grids::kScatter);
    if (!direct || !scattered) return;
    auto illumination = set.get<openvdb::Vec3SGrid>(grids::kDirect)->deepCopy();
    auto addend = set.get<openvdb::Vec3SGrid>(grids::kScatter)->deepCopy();
    openvdb::tools::compSum(*illumination, *addend);
    set.put(detail::named(illumination, grids::kIllumination));
}

} // namespace vxf
