#include <vxf/light/DirectLight.h>

#include <vxf/core/GridRoles.h>
#include <vxf/core/GridStats.h>
#include <vxf/core/MemoryBudget.h>
#include <vxf/light/VolumeEmission.h>
#include <vxf/transport/Phase.h>

#include "LightSweeps.h"

#include <vxf/core/Hash.h>

#include <openvdb/tools/Morphology.h>
#include <openvdb/tree/LeafManager.h>

#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
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

/// A grid of the light stage on the density's topology, one voxel beyond it (26-neighbourhood):
/// trilinear lookups of φ near the surface then blend real values, not the background 0 (which
/// would dim the outermost half voxel).
openvdb::Vec3SGrid::Ptr stageGrid(const openvdb::FloatGrid& density, const char* name, bool coarseTiles)
{
    auto grid = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    grid->setTransform(density.transformPtr()->copy());
    grid->tree().topologyUnion(density.tree());
    grid->setName(name);
    if (!coarseTiles) grid->tree().voxelizeActiveTiles();
    openvdb::tools::dilateActiveValues(
        grid->tree(), 1, openvdb::tools::NN_FACE_EDGE_VERTEX, coarseTiles ? openvdb::tools::PRESERVE_TILES : openvdb::tools::IGNORE_TILES);
    return grid;
}

/// Σ over @a leaves' active voxels of @a fluence (per lattice voxel), and over @a tiles of the
/// value at the tile's centre times its voxels (as the light stage's grids hold them), in a
/// fixed order: the same for every thread count.
openvdb::Vec3d energyOf(const std::vector<openvdb::Vec3f>& fluence, const detail::SweepLattice& lattice,
    const openvdb::tree::LeafManager<openvdb::Vec3STree>& leaves, const std::vector<openvdb::CoordBBox>& tiles)
{
    std::vector<openvdb::Vec3d> sums(leaves.leafCount() + tiles.size(), openvdb::Vec3d(0.0));
    const auto at = [&](const openvdb::Coord& ijk) {
        const std::int64_t i = lattice.indexOf(ijk);
        return i < 0 ? openvdb::Vec3d(0.0) : openvdb::Vec3d(fluence[std::size_t(i)]);
    };
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, sums.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t item = r.begin(); item != r.end(); ++item) {
            if (item < leaves.leafCount()) {
                for (auto it = leaves.leaf(item).cbeginValueOn(); it; ++it) sums[item] += at(it.getCoord());
            } else {
                const openvdb::CoordBBox& box = tiles[item - leaves.leafCount()];
                sums[item] += at(box.min() + openvdb::Coord(box.dim().x() / 2)) * double(box.volume());
            }
        }
    });
    openvdb::Vec3d total(0.0);
    for (const openvdb::Vec3d& s : sums) total += s;
    return total;
}

/// The lights a sweep carries, swept over one lattice on @a direct's topology: their fluence at
/// every voxel centre (at the rim, from its medium point along the directions that graze the
/// surface there), each light added into the sums as it is swept (no array of its own: 12 bytes
/// a voxel and light, 24 with a phase), its energy for the report what it added.
struct SweptLights
{
    std::optional<detail::SweepLattice> lattice; ///< none: no light is swept
    std::vector<bool> swept; ///< per light
    std::vector<openvdb::Vec3d> energy; ///< per light, the energyOf the fluence it added
    std::vector<openvdb::Vec3f> fluence, flux; ///< per lattice voxel, the sums (flux: anisotropic)
};
SweptLights sweepLights(const std::vector<LightSampler>& active, const Medium& medium, const openvdb::Vec3SGrid& direct,
    const DirectLightOptions& options, bool anisotropic, const openvdb::tree::LeafManager<openvdb::Vec3STree>& leaves,
    const std::vector<openvdb::CoordBBox>& tiles, Interrupter* interrupter)
{
    SweptLights out;
    out.swept.assign(active.size(), false);
    out.energy.assign(active.size(), openvdb::Vec3d(0.0));
    if (!options.sweep) return out;
    Rim rim;
    for (std::size_t l = 0; l < active.size(); ++l) {
        const bool fromPoint = sweepableFromPoint(active[l].light());
        if (!sweepable(active[l].light()) && !fromPoint) continue;
        if (!out.lattice) {
            out.lattice.emplace(medium, direct, detail::SweepLattice::Coefficients::SweepOnly);
            rim = rimOf(*out.lattice, medium);
        }
        // Each light adds into the sums; its energy is what it added (energyOf is a sum, and
        // the earlier lights' part is known).
        const openvdb::Vec3d before = out.fluence.empty() ? openvdb::Vec3d(0.0) : energyOf(out.fluence, *out.lattice, leaves, tiles);
        std::vector<openvdb::Vec3f>* flux = anisotropic ? &out.flux : nullptr;
        if (fromPoint)
            sweepPointLight(active[l], *out.lattice, medium, rim, options, out.fluence, flux);
        else
            sweepLight(active[l], *out.lattice, medium, rim, options, out.fluence, flux);
        out.swept[l] = true;
        out.energy[l] = energyOf(out.fluence, *out.lattice, leaves, tiles) - before;
        checkInterrupt(interrupter);
    }
    return out;
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
    const std::vector<openvdb::Vec3f>& sweptFluence; ///< per lattice voxel, the swept lights' sum
    const std::vector<openvdb::Vec3f>& sweptFlux; ///< per lattice voxel, their first moment's sum (anisotropic)
    const bool anisotropic;

    /// At voxel @a ijk (index point @a pointIjk), adding each marched light's fluence × @a weight
    /// to @a sums (the swept ones' are summed as they are swept: SweptLights::energy).
    void operator()(Medium::Sampler& sampler, std::vector<VolumeEmission::Sampler>& emitters, const openvdb::Coord& ijk,
        const openvdb::Vec3d& pointIjk, std::vector<openvdb::Vec3d>& sums, openvdb::Vec3f& outDirect, openvdb::Vec3f& outSource,
        openvdb::Vec3f& outAnisotropy, double weight) const
    {
        openvdb::Vec3d phi(0.0), flux(0.0);
        // Swept lights from their sweep; the others marched (lightFluence).
        const std::int64_t index = lattice ? lattice->indexOf(ijk) : -1;
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

DirectLightReport computeDirectLight(
    VoxelSet& set, const Medium& medium, const std::vector<Light>& lights, const DirectLightOptions& options, Interrupter* interrupter)
{
    InterruptStep step(interrupter, "lighting");
    requireMemory("light", stageMemory(kStageFixedBytes, double(medium.density().activeVoxelCount()), kLightBytesPerVoxel));
    DirectLightReport report;
    warnIfNoDensity(medium, report);
    std::vector<LightSampler> active;
    std::vector<int> activeIndex; // per report entry: its index in `active`, or -1
    std::vector<VolumeEmission> emission; // volume lights
    sortLights(lights, report, active, activeIndex, emission);

    const openvdb::FloatGrid& density = medium.density();
    auto direct = stageGrid(density, grids::kDirect, options.coarseTiles);
    // An anisotropic rest of the phase (Medium: delta-M's g*): the source's mean direction of travel.
    const bool anisotropic = medium.material().phaseG != 0.0;

    // Work items: leaf voxels (per leaf) and active tiles (value at the tile centre).
    openvdb::tree::LeafManager<openvdb::Vec3STree> leaves(direct->tree());
    std::vector<openvdb::CoordBBox> tiles;
    for (auto it = direct->tree().cbeginValueOn(); it; ++it) {
        if (it.isTileValue()) {
            openvdb::CoordBBox box;
            it.getBoundingBox(box);
            tiles.push_back(box);
        }
    }
    const std::size_t leafCount = leaves.leafCount();
    const std::size_t total = leafCount + tiles.size();
    std::vector<std::vector<openvdb::Vec3d>> perLight(total);
    std::vector<openvdb::Vec3f> tileDirect(tiles.size()), tileSource(tiles.size()), tileAnisotropy(tiles.size());
    std::atomic<std::size_t> done{0};
    std::atomic<bool> cancelled{false};

    const SweptLights swept = sweepLights(active, medium, *direct, options, anisotropic, leaves, tiles, interrupter);
    // The other grids of the stage, on direct's topology (made after the sweeps, whose arrays
    // and optical depths were the peak).
    auto source = stageGrid(density, grids::kScatterSource, options.coarseTiles);
    openvdb::Vec3SGrid::Ptr anisotropy;
    if (anisotropic) {
        anisotropy = source->deepCopy(); // its values are all 0 yet
        anisotropy->setName(grids::kSourceAnisotropy);
    }
    openvdb::tree::LeafManager<openvdb::Vec3STree> sourceLeaves(source->tree());
    std::optional<openvdb::tree::LeafManager<openvdb::Vec3STree>> anisotropyLeaves;
    if (anisotropy) anisotropyLeaves.emplace(anisotropy->tree());

    const PointLighting evaluate{medium, options, active, swept.lattice, swept.swept, swept.fluence, swept.flux, anisotropic};

    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, total, 1), [&](const tbb::blocked_range<std::size_t>& range) {
        Medium::Sampler sampler = lightStageSampler(medium, options);
        std::vector<VolumeEmission::Sampler> emitters(emission.begin(), emission.end());
        for (std::size_t item = range.begin(); item != range.end(); ++item) {
            if (cancelled) return;
            auto& sums = perLight[item];
            sums.assign(active.size(), openvdb::Vec3d(0.0));
            if (item < leafCount) {
                auto& leaf = leaves.leaf(item);
                auto& sourceLeaf = sourceLeaves.leaf(item);
                auto* anisotropyLeaf = anisotropyLeaves ? &anisotropyLeaves->leaf(item) : nullptr;
                for (auto it = leaf.beginValueOn(); it; ++it) {
                    openvdb::Vec3f d, s, a;
                    evaluate(sampler, emitters, it.getCoord(), it.getCoord().asVec3d(), sums, d, s, a, 1.0);
                    it.setValue(d);
                    sourceLeaf.setValueOnly(it.pos(), s);
                    if (anisotropyLeaf) anisotropyLeaf->setValueOnly(it.pos(), a);
                }
            } else {
                const std::size_t t = item - leafCount;
                const openvdb::CoordBBox& box = tiles[t];
                const openvdb::Coord centre = box.min() + openvdb::Coord(box.dim().x() / 2);
                evaluate(sampler, emitters, centre, centre.asVec3d(), sums, tileDirect[t], tileSource[t], tileAnisotropy[t],
                    double(box.volume()));
            }
            const std::size_t finished = ++done;
            if (interrupter && interrupter->wasInterrupted(int(100 * finished / std::max<std::size_t>(total, 1)))) {
                cancelled = true;
            }
        }
    });
    if (cancelled) throw Interrupted();
    for (std::size_t t = 0; t < tiles.size(); ++t) {
        direct->tree().fill(tiles[t], tileDirect[t], true);
        source->tree().fill(tiles[t], tileSource[t], true);
        if (anisotropy) anisotropy->tree().fill(tiles[t], tileAnisotropy[t], true);
    }

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
