#include <vxf/light/DirectLight.h>

#include <vxf/core/GridRoles.h>
#include <vxf/core/GridLookup.h>
#include <vxf/core/GridStats.h>
#include <vxf/core/MemoryBudget.h>
#include <vxf/light/VolumeEmission.h>
#include <vxf/transport/AdaptiveBand.h>
#include <vxf/transport/Phase.h>

#include "LightSweeps.h"

#include <vxf/core/Hash.h>

#include <openvdb/tools/Morphology.h>
#include <openvdb/tree/LeafManager.h>

#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <array>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <optional>

namespace vxf {

openvdb::Vec3d sampleTransmittance(const LightSample& sample, Medium::Sampler& sampler, const Medium& medium, const openvdb::Vec3d& xWorld,
    const MarchOptions& options, const RayScene* occluders)
{
    if (!detail::unoccluded(occluders, medium, xWorld, sample)) return openvdb::Vec3d(0.0);
    const openvdb::math::Transform& xform = medium.transform();
    const openvdb::Vec3d xIjk = xform.worldToIndex(xWorld);
    if (std::isfinite(sample.distance)) {
        return transmittance(sampler, medium, xIjk, xform.worldToIndex(xWorld + sample.direction * sample.distance), options);
    }
    return transmittanceToBoundary(sampler, medium, xIjk, xform.worldToIndex(xWorld + sample.direction) - xIjk, options);
}

openvdb::Vec3d lightFluence(const LightSampler& light, Medium::Sampler& sampler, const Medium& medium, const openvdb::Coord& voxel,
    const MarchOptions& options, const RayScene* occluders, openvdb::Vec3d* flux)
{
    static thread_local std::vector<LightSample> samples;
    // A rim voxel's light is its medium's, inside the surface: at its centre outside, the light
    // of a shadowed side comes in unattenuated past the limb (see DirectLight.h).
    const openvdb::Vec3d xWorld = medium.transform().indexToWorld(sampler.mediumPoint(voxel));
    // Never divide by zero: distances below half a voxel count as half a voxel.
    light.sample(xWorld, coordKey(voxel), 0.5 * medium.voxelSize(), samples);
    openvdb::Vec3d phi(0.0);
    for (const LightSample& s : samples) {
        const openvdb::Vec3d f = s.fluence * sampleTransmittance(s, sampler, medium, xWorld, options, occluders);
        phi += f;
        if (flux) *flux -= greyOf(f) * s.direction; // travelling away from the light
    }
    return phi;
}

namespace {

using namespace detail;
/// A warning in @a report when the medium's density has no positive value: a volume object
/// reading the wrong grid, or a grid its writer left empty, renders black.
void warnIfNoDensity(const Medium& medium, DirectLightReport& report)
{
    const auto& density = medium.density();
    const ValueRange range = valueRange(density);
    const double highest = range.channels > 0 ? range.max[0] : 0.0;
    if (!(highest > 0.0)) {
        report.warnings.push_back(fmt::format("the medium's density ('{}', {} active voxels) has no positive value{}: nothing "
                                              "absorbs, scatters or glows, and the image shows surfaces only",
            density.getName(), density.activeVoxelCount(),
            density.activeVoxelCount() > 0 ? fmt::format(" (largest {:.4g})", highest) : std::string()));
    }
}

/// The lights that shine (@a active), the volume lights (@a emission), and a report entry per
/// light; @a activeIndex per entry: its index in @a active, or -1.
void sortLights(const std::vector<Light>& lights, DirectLightReport& report, std::vector<LightSampler>& active,
    std::vector<int>& activeIndex, std::vector<VolumeEmission>& emission)
{
    for (const Light& light : lights) {
        DirectLightReport::PerLight entry;
        entry.name = light.name;
        if (light.power() == openvdb::Vec3d(0.0)) {
            entry.skipped = true;
            entry.why = "zero colour or intensity";
        } else if (light.type == Light::Type::Volume) {
            emission.emplace_back(light);
            entry.why = "volume light: its emission adds to scatter_source";
        } else {
            activeIndex.push_back(int(active.size()));
            active.emplace_back(light);
            report.lights.push_back(entry);
            continue;
        }
        activeIndex.push_back(-1);
        report.lights.push_back(entry);
    }
}

/// The light stage's grids' topology: the density's, one voxel beyond it (26-neighbourhood):
/// trilinear lookups of φ near the surface then blend real values, not the background 0 (which
/// would dim the outermost half voxel). Dilated before its tiles are voxelized (without
/// @a coarseTiles): the same voxels, but the dilation visits the surface's leaves, not the
/// interior's (the bunny at dim 1024: 54k leaves, not 430k).
openvdb::MaskTree stageTopology(const openvdb::FloatGrid& density, bool coarseTiles)
{
    openvdb::MaskTree topology(density.tree(), false, openvdb::TopologyCopy());
    openvdb::tools::dilateActiveValues(topology, 1, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::PRESERVE_TILES);
    if (!coarseTiles) topology.voxelizeActiveTiles();
    return topology;
}

using StageLeaf = openvdb::Vec3STree::LeafNodeType;
using StageLeaves = openvdb::tree::LeafManager<const openvdb::MaskTree>;

/// A grid of the light stage named @a name: @a leaves (taken) and @a tiles filled with @a tileValues.
openvdb::Vec3SGrid::Ptr stageGrid(const openvdb::FloatGrid& density, const char* name, std::vector<std::unique_ptr<StageLeaf>>& leaves,
    const std::vector<openvdb::CoordBBox>& tiles, const std::vector<openvdb::Vec3f>& tileValues)
{
    auto grid = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    grid->setTransform(density.transformPtr()->copy());
    grid->setName(name);
    for (auto& leaf : leaves) grid->tree().addLeaf(leaf.release());
    for (std::size_t t = 0; t < tiles.size(); ++t) grid->tree().fill(tiles[t], tileValues[t], true);
    return grid;
}

/// The voxel at the centre of tile @a box (where the light stage evaluates it).
openvdb::Coord centreOf(const openvdb::CoordBBox& box) { return box.min() + openvdb::Coord(box.dim().x() / 2); }

/// Σ over @a leaves' active voxels of @a fluence (per lattice voxel), and over @a tiles of the
/// value at the tile's centre times its voxels (as the light stage's grids hold them), in a
/// fixed order: the same for every thread count.
openvdb::Vec3d energyOf(const detail::LeafBlocks<openvdb::Vec3f>& fluence, const detail::SweepLattice& lattice, const StageLeaves& leaves,
    const std::vector<openvdb::CoordBBox>& tiles)
{
    std::vector<openvdb::Vec3d> sums(leaves.leafCount() + tiles.size(), openvdb::Vec3d(0.0));
    const auto at = [&](const openvdb::Coord& ijk) {
        const std::int64_t i = lattice.indexOf(ijk);
        return i < 0 ? openvdb::Vec3d(0.0) : openvdb::Vec3d(fluence[std::size_t(i)]);
    };
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, sums.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t item = r.begin(); item != r.end(); ++item) {
            if (item < leaves.leafCount()) {
                // The lattice's leaf at the stage leaf's origin (both 8³ aligned), looked up once.
                const std::int64_t first = lattice.indexOf(leaves.leaf(item).origin());
                if (first < 0) continue;
                for (auto it = leaves.leaf(item).cbeginValueOn(); it; ++it)
                    sums[item] += openvdb::Vec3d(fluence[std::size_t(first) + it.pos()]);
            } else {
                const openvdb::CoordBBox& box = tiles[item - leaves.leafCount()];
                sums[item] += at(centreOf(box)) * double(box.volume());
            }
        }
    });
    openvdb::Vec3d total(0.0);
    for (const openvdb::Vec3d& s : sums) total += s;
    return total;
}

/// The lights a sweep carries, swept over one lattice on the stage's @a topology: their fluence at
/// every voxel centre (at the rim, from its medium point along the directions that graze the
/// surface there), each light added into the sums as it is swept (no array of its own: 12 bytes
/// a voxel and light, 24 with a phase), its energy for the report what it added.
struct SweptLights
{
    std::optional<detail::SweepLattice> lattice; ///< none: no light is swept
    std::vector<bool> swept; ///< per light
    std::vector<openvdb::Vec3d> energy; ///< per light, the energyOf the fluence it added
    detail::LeafBlocks<openvdb::Vec3f> fluence, flux; ///< per lattice voxel, the sums (flux: anisotropic)
};
SweptLights sweepLights(const std::vector<LightSampler>& active, const Medium& medium, const openvdb::MaskTree& topology,
    const DirectLightOptions& options, bool anisotropic, const StageLeaves& leaves, const std::vector<openvdb::CoordBBox>& tiles,
    Interrupter* interrupter)
{
    SweptLights out;
    out.swept.assign(active.size(), false);
    out.energy.assign(active.size(), openvdb::Vec3d(0.0));
    if (!options.sweep) return out;
    Rim rim;
    std::optional<LatticeSpans> spans;
    openvdb::Vec3d before(0.0); // the sums' energyOf so far
    for (std::size_t l = 0; l < active.size(); ++l) {
        const bool fromPoint = sweepableFromPoint(active[l].light());
        if (!sweepable(active[l].light()) && !fromPoint) continue;
        if (!out.lattice) {
            out.lattice.emplace(medium, topology, detail::SweepLattice::Coefficients::SweepOnly);
            rim = rimOf(*out.lattice, medium);
            if (!options.boundary) spans.emplace(*out.lattice); // (with meshes, the marches ask them)
        }
        // Each light adds into the sums; its energy is what it added (energyOf is a sum: the
        // sums' energy after the light less the earlier lights').
        detail::LeafBlocks<openvdb::Vec3f>* flux = anisotropic ? &out.flux : nullptr;
        if (fromPoint)
            sweepPointLight(active[l], *out.lattice, medium, rim, spans ? &*spans : nullptr, options, out.fluence, flux);
        else
            sweepLight(active[l], *out.lattice, medium, rim, spans ? &*spans : nullptr, options, out.fluence, flux);
        out.swept[l] = true;
        const openvdb::Vec3d after = energyOf(out.fluence, *out.lattice, leaves, tiles);
        out.energy[l] = after - before;
        before = after;
        checkInterrupt(interrupter);
    }
    return out;
}

/// Per work item (@a leaves, then @a tiles), the lattice leaf of @a swept whose sums it reads
/// (−1: none); the sums' blocks no item reads are freed at once.
std::vector<std::int64_t> latticeLeavesRead(
    SweptLights& swept, const StageLeaves& leaves, const std::vector<openvdb::CoordBBox>& tiles, bool anisotropic)
{
    std::vector<std::int64_t> latticeLeaf(leaves.leafCount() + tiles.size(), -1);
    if (!swept.lattice || swept.fluence.empty()) return latticeLeaf;
    std::vector<char> read(swept.lattice->leafCount(), 0);
    for (std::size_t item = 0; item < latticeLeaf.size(); ++item) {
        const std::size_t leafCount = leaves.leafCount();
        const openvdb::Coord at = item < leafCount ? leaves.leaf(item).origin() : centreOf(tiles[item - leafCount]);
        const std::int64_t i = swept.lattice->indexOf(at);
        if (i < 0) continue;
        latticeLeaf[item] = i / detail::SweepLattice::kLeafVoxels;
        read[std::size_t(latticeLeaf[item])] = 1;
    }
    for (std::size_t n = 0; n < read.size(); ++n) {
        if (read[n]) continue;
        swept.fluence.release(n);
        if (anisotropic) swept.flux.release(n);
    }
    return latticeLeaf;
}

/// The light stage at one point: φ0 from every light (swept where a sweep holds the voxel,
/// marched otherwise), J0 and the source's mean direction of travel.
struct PointLighting
{
    const Medium& medium;
    const DirectLightOptions& options;
    const std::vector<LightSampler>& active;
    const std::optional<detail::SweepLattice>& lattice;
    const std::vector<bool>& swept; ///< per light: its fluence is in sweptFluence
    const detail::LeafBlocks<openvdb::Vec3f>& sweptFluence; ///< per lattice voxel, the swept lights' sum
    const detail::LeafBlocks<openvdb::Vec3f>& sweptFlux; ///< per lattice voxel, their first moment's sum (anisotropic)
    const bool anisotropic;

    /// The lattice's per-voxel index of @a ijk, which lies in lattice leaf @a latticeLeaf (−1:
    /// none, or no sums; latticeLeavesRead), or −1: no lookup.
    static std::int64_t indexIn(std::int64_t latticeLeaf, const openvdb::Coord& ijk)
    {
        if (latticeLeaf < 0) return -1;
        return latticeLeaf * detail::SweepLattice::kLeafVoxels + detail::SweepLattice::localIndex(ijk[0] & 7, ijk[1] & 7, ijk[2] & 7);
    }

    /// At voxel @a ijk (index point @a pointIjk; the lattice's per-voxel @a index there, −1:
    /// none), adding each marched light's fluence × @a weight to @a sums (the swept ones' are
    /// summed as they are swept: SweptLights::energy).
    void operator()(Medium::Sampler& sampler, std::vector<VolumeEmission::Sampler>& emitters, const openvdb::Coord& ijk, std::int64_t index,
        const openvdb::Vec3d& pointIjk, std::vector<openvdb::Vec3d>& sums, openvdb::Vec3f& outDirect, openvdb::Vec3f& outSource,
        openvdb::Vec3f& outAnisotropy, double weight) const
    {
        openvdb::Vec3d phi(0.0), flux(0.0);
        // Swept lights from their sweep; the others marched (lightFluence).
        if (index >= 0 && !sweptFluence.empty()) {
            phi += openvdb::Vec3d(sweptFluence[std::size_t(index)]);
            if (anisotropic) flux += openvdb::Vec3d(sweptFlux[std::size_t(index)]);
        }
        for (std::size_t l = 0; l < active.size(); ++l) {
            if (index >= 0 && swept[l]) continue;
            const openvdb::Vec3d f =
                lightFluence(active[l], sampler, medium, ijk, options.march, options.occluders, anisotropic ? &flux : nullptr);
            phi += f;
            sums[l] += f * weight;
        }
        // J0 = σs φ0 / 4π (+ emission of volume lights, radiance per unit length).
        const openvdb::Vec3d scattered = sampler.sigmaS(pointIjk) * phi / (4.0 * M_PI);
        openvdb::Vec3d j = scattered;
        const openvdb::Vec3d world = medium.transform().indexToWorld(pointIjk);
        for (VolumeEmission::Sampler& e : emitters) j += e.at(world);
        for (int c = 0; c < 3; ++c) {
            if (!std::isfinite(phi[c])) phi[c] = 0.0; // cannot happen by construction; never let NaN in
            if (!std::isfinite(j[c])) j[c] = 0.0;
        }
        outDirect = openvdb::Vec3f(phi);
        outSource = openvdb::Vec3f(j);
        if (anisotropic) {
            // The scattered light's first moment F·σs/4π, the emission's none: a = F/φ of the
            // light scattered, in the share of J0 it makes (grey).
            const double scatteredGrey = greyOf(scattered), phiGrey = greyOf(phi), jGrey = greyOf(j);
            outAnisotropy = phiGrey > 0.0 && jGrey > 0.0 ? openvdb::Vec3f(clampedToUnit(flux / phiGrey) * (scatteredGrey / jGrey))
                                                         : openvdb::Vec3f(0.0f);
        }
    }
};

} // namespace

MemoryEstimate lightMemory(double voxels)
{
    const double denseCopies = std::min(2.0 * double(kDenseCopyBytes), voxels * kLightDenseBytesPerVoxel);
    return stageMemory(kStageFixedBytes + denseCopies, voxels, kLightBytesPerVoxel);
}

DirectLightReport computeDirectLight(
    VoxelSet& set, const Medium& medium, const std::vector<Light>& lights, const DirectLightOptions& options, Interrupter* interrupter)
{
    InterruptStep step(interrupter, "lighting");
    requireMemory("light", lightMemory(double(medium.density().activeVoxelCount())));
    DirectLightReport report;
    warnIfNoDensity(medium, report);
    std::vector<LightSampler> active;
    std::vector<int> activeIndex; // per report entry: its index in `active`, or -1
    std::vector<VolumeEmission> emission; // volume lights
    sortLights(lights, report, active, activeIndex, emission);

    const openvdb::FloatGrid& density = medium.density();
    const openvdb::MaskTree topology = stageTopology(density, options.coarseTiles);
    // An anisotropic rest of the phase (Medium: delta-M's g*): the source's mean direction of travel.
    const bool anisotropic = medium.material().phaseG != 0.0;

    // Work items: leaf voxels (per leaf) and active tiles (value at the tile centre).
    const StageLeaves leaves(topology);
    std::vector<openvdb::CoordBBox> tiles;
    for (auto it = topology.cbeginValueOn(); it; ++it) {
        if (it.isTileValue()) {
            openvdb::CoordBBox box;
            it.getBoundingBox(box);
            tiles.push_back(box);
        }
    }
    const std::size_t leafCount = leaves.leafCount();
    const std::size_t total = leafCount + tiles.size();
    const auto tileCentre = [&](std::size_t t) { return centreOf(tiles[t]); };
    std::vector<std::vector<openvdb::Vec3d>> perLight(total);
    std::vector<openvdb::Vec3f> tileDirect(tiles.size()), tileSource(tiles.size()), tileAnisotropy(tiles.size());
    std::atomic<std::size_t> done{0};
    std::atomic<bool> cancelled{false};

    SweptLights swept = sweepLights(active, medium, topology, options, anisotropic, leaves, tiles, interrupter);
    // The grids' leaves are made as each is lit, and the swept sums' blocks freed as they are read
    // (the sweeps' arrays and the grids are never held whole at once).
    const std::vector<std::int64_t> latticeLeaf = latticeLeavesRead(swept, leaves, tiles, anisotropic);
    std::vector<std::unique_ptr<StageLeaf>> directLeaves(leafCount), sourceLeaves(leafCount), anisotropyLeaves(anisotropic ? leafCount : 0);
    // Beyond the band, a leaf is made, then kept as its mean (direct, source, anisotropy).
    const BandInterior deep(density, options.band);
    std::vector<std::optional<std::array<openvdb::Vec3f, 3>>> deepMeans(options.band > 0.0 ? leafCount : 0);

    const PointLighting evaluate{medium, options, active, swept.lattice, swept.swept, swept.fluence, swept.flux, anisotropic};

    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, total, 1), [&](const tbb::blocked_range<std::size_t>& range) {
        Medium::Sampler sampler = lightStageSampler(medium, options);
        std::vector<VolumeEmission::Sampler> emitters(emission.begin(), emission.end());
        for (std::size_t item = range.begin(); item != range.end(); ++item) {
            if (cancelled) return;
            auto& sums = perLight[item];
            sums.assign(active.size(), openvdb::Vec3d(0.0));
            if (item < leafCount) {
                const auto& mask = leaves.leaf(item);
                const auto made = [&](std::unique_ptr<StageLeaf>& leaf) {
                    leaf = std::make_unique<StageLeaf>(mask.origin(), openvdb::Vec3f(0.0f), false);
                    leaf->setValueMask(mask.getValueMask());
                    return leaf.get();
                };
                StageLeaf* directLeaf = made(directLeaves[item]);
                StageLeaf* sourceLeaf = made(sourceLeaves[item]);
                StageLeaf* anisotropyLeaf = anisotropic ? made(anisotropyLeaves[item]) : nullptr;
                for (auto it = mask.cbeginValueOn(); it; ++it) {
                    openvdb::Vec3f d, s, a;
                    const openvdb::Coord ijk = it.getCoord();
                    evaluate(sampler, emitters, ijk, evaluate.indexIn(latticeLeaf[item], ijk), ijk.asVec3d(), sums, d, s, a, 1.0);
                    directLeaf->setValueOnly(it.pos(), d);
                    sourceLeaf->setValueOnly(it.pos(), s);
                    if (anisotropyLeaf) anisotropyLeaf->setValueOnly(it.pos(), a);
                }
                if (!deepMeans.empty() && deep.holdsLeaf(mask.origin())) {
                    deepMeans[item] = {
                        leafMean(*directLeaf), leafMean(*sourceLeaf), anisotropyLeaf ? leafMean(*anisotropyLeaf) : openvdb::Vec3f(0.0f)};
                    directLeaves[item].reset();
                    sourceLeaves[item].reset();
                    if (anisotropyLeaf) anisotropyLeaves[item].reset();
                }
            } else {
                const std::size_t t = item - leafCount;
                const openvdb::Coord centre = tileCentre(t);
                evaluate(sampler, emitters, centre, evaluate.indexIn(latticeLeaf[item], centre), centre.asVec3d(), sums, tileDirect[t],
                    tileSource[t], tileAnisotropy[t], double(tiles[t].volume()));
            }
            if (latticeLeaf[item] >= 0) {
                swept.fluence.release(std::size_t(latticeLeaf[item]));
                if (anisotropic) swept.flux.release(std::size_t(latticeLeaf[item]));
            }
            const std::size_t finished = ++done;
            if (interrupter && interrupter->wasInterrupted(int(100 * finished / std::max<std::size_t>(total, 1)))) {
                cancelled = true;
            }
        }
    });
    if (cancelled) throw Interrupted();
    for (std::size_t n = 0; n < deepMeans.size(); ++n) {
        if (!deepMeans[n]) continue;
        tiles.push_back(openvdb::CoordBBox::createCube(leaves.leaf(n).origin(), StageLeaf::DIM));
        tileDirect.push_back((*deepMeans[n])[0]);
        tileSource.push_back((*deepMeans[n])[1]);
        tileAnisotropy.push_back((*deepMeans[n])[2]);
    }
    auto direct = stageGrid(density, grids::kDirect, directLeaves, tiles, tileDirect);
    auto source = stageGrid(density, grids::kScatterSource, sourceLeaves, tiles, tileSource);
    openvdb::Vec3SGrid::Ptr anisotropy;
    if (anisotropic) anisotropy = stageGrid(density, grids::kSourceAnisotropy, anisotropyLeaves, tiles, tileAnisotropy);

    // Per-light energy sums in a fixed order (deterministic for any thread count).
    for (std::size_t e = 0; e < report.lights.size(); ++e) {
        if (activeIndex[e] < 0) continue;
        for (const auto& sums : perLight) report.lights[e].fluenceSum += sums[std::size_t(activeIndex[e])];
        report.lights[e].fluenceSum += swept.energy[std::size_t(activeIndex[e])];
    }
    set.put(direct);
    set.put(source);
    if (anisotropy) {
        set.put(anisotropy);
    } else {
        set.remove(grids::kSourceAnisotropy); // a set lit before with another phase
    }
    return report;
}

} // namespace vxf
