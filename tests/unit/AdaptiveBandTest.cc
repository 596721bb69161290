#include <vxf/transport/AdaptiveBand.h>
#include <vxf/scatter/Scatter.h>

#include <vxf/core/MemoryBudget.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>
#include <tbb/global_control.h>

namespace {

/// A cube of density 1 over voxels [-half, half-1]³ (active tiles where the tree allows) with
/// voxel size @a dx, and a source grid on its topology holding a value that varies per voxel.
std::pair<openvdb::FloatGrid::Ptr, openvdb::Vec3SGrid::Ptr> cube(int half, double dx)
{
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setTransform(openvdb::math::Transform::createLinearTransform(dx));
    density->tree().fill(openvdb::CoordBBox(openvdb::Coord(-half), openvdb::Coord(half - 1)), 1.0f, true);
    auto source = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    source->setTransform(density->transformPtr());
    source->tree().topologyUnion(density->tree());
    source->tree().voxelizeActiveTiles();
    for (auto it = source->tree().beginValueOn(); it; ++it) {
        const openvdb::Coord c = it.getCoord();
        it.setValue(openvdb::Vec3f(1.0f + 0.01f * float(c.x()), 2.0f, 0.5f + 0.001f * float(c.y() * c.z())));
    }
    return {density, source};
}

/// The scattered light of a uniformSphere of @a m (voxel size 1/@a cells) with its surface, by
/// the accelerated sweeps over @a directions with @a band, and the report.
std::pair<openvdb::Vec3SGrid::Ptr, vxf::ScatterReport> sweptSphere(const vxf::Material& m, int cells, double band, int directions)
{
    vxf::VoxelSet set = vxf::test::uniformSphere(m, 1.0, cells);
    vxf::test::putSphereSurface(set, 1.0, cells);
    const vxf::Medium medium(set, m);
    vxf::ScatterOptions options;
    options.passes = 40;
    options.tolerance = 1e-3;
    options.band = band;
    options.pass.kernel = vxf::ScatterKernel::Sweep;
    options.pass.directions = directions;
    const auto report = vxf::scatter(set, medium, options);
    return {set.get<openvdb::Vec3SGrid>("scatter"), report};
}

} // namespace

TEST_CASE("the band keeps full resolution near the surface and tiles the deep interior, preserving energy", "[band]")
{
    auto [density, source] = cube(24, 0.1); // 48³ voxels
    const openvdb::Vec3d before = vxf::gridEnergy(*source);
    const openvdb::Index64 voxels = source->activeVoxelCount();

    SECTION("band 0 changes nothing")
    {
        const auto report = vxf::coarsenBeyondBand(*source, *density, 0.0);
        CHECK(report.leafTiles == 0);
        CHECK(report.fineVoxels == voxels);
    }
    SECTION("band of 8 voxels: leaves in [-16, 15]³ become tiles")
    {
        // A voxel is 8 deep (L∞) when its 17³ neighbourhood is inside: i in [-16, 15] per axis;
        // the leaves aligned within that are 4 per axis.
        const auto report = vxf::coarsenBeyondBand(*source, *density, 0.8);
        CHECK(report.leafTiles == 64);
        CHECK(report.internalTiles == 0);
        CHECK(report.coarseVoxels == 64 * 512);
        CHECK(report.fineVoxels == voxels - 64 * 512);
        CHECK(source->activeVoxelCount() == voxels);
        const openvdb::Vec3d after = vxf::gridEnergy(*source);
        for (int c = 0; c < 3; ++c) CHECK(after[c] == Approx(before[c]).epsilon(1e-6));
        // Voxels within the band keep their own values.
        CHECK(source->tree().getValue(openvdb::Coord(-17, 0, 0)) == openvdb::Vec3f(1.0f - 0.17f, 2.0f, 0.5f));
        CHECK(source->tree().probeConstLeaf(openvdb::Coord(-17, 0, 0)) != nullptr);
        CHECK(source->tree().probeConstLeaf(openvdb::Coord(0, 0, 0)) == nullptr);
        // Idempotent; no copy is made of what is coarse already.
        vxf::AdaptiveBandReport copied;
        CHECK(vxf::coarsenedBeyondBand(*source, *density, 0.8, copied) == nullptr);
        CHECK(copied.fineVoxels == report.fineVoxels);
        const auto again = vxf::coarsenBeyondBand(*source, *density, 0.8);
        CHECK(again.leafTiles == 0);
        CHECK(again.fineVoxels == report.fineVoxels);
    }
    SECTION("a coarsened copy: the same grid, the original untouched")
    {
        vxf::AdaptiveBandReport copied;
        const auto copy = vxf::coarsenedBeyondBand(*source, *density, 0.8, copied);
        CHECK(source->tree().leafCount() == 216); // 6³ leaves, none made a tile
        CHECK(vxf::gridEnergy(*source) == before);
        const auto report = vxf::coarsenBeyondBand(*source, *density, 0.8);
        CHECK(copied.leafTiles == report.leafTiles);
        CHECK(copied.fineVoxels == report.fineVoxels);
        CHECK(copied.coarseVoxels == report.coarseVoxels);
        CHECK(copy->tree().leafCount() == source->tree().leafCount());
        CHECK(copy->transform() == source->transform());
        CHECK(copy->tree().activeTileCount() == source->tree().activeTileCount());
        std::string why;
        const bool same = vxf::test::identicalGrids(*copy, *source, &why);
        INFO(why);
        CHECK(same);
    }
    SECTION("a band thinner than half a leaf still keeps 4 voxels")
    {
        // max(band, 4): depth 4 means i in [-20, 19], leaves [-16, 15]: 64 again.
        CHECK(vxf::coarsenBeyondBand(*source, *density, 0.1).leafTiles == 64);
    }
    SECTION("a band as deep as half the medium leaves everything at full resolution")
    {
        // 24 voxels deep in a 48-voxel cube: no voxel is deeper. A band of 1e12 (a world-unit
        // band given in voxels, or worse) is the same, and is not eroded voxel by voxel.
        for (const double band : {2.4, 1e12}) {
            const auto report = vxf::coarsenBeyondBand(*source, *density, band);
            CHECK(report.leafTiles == 0);
            CHECK(report.fineVoxels == voxels);
            CHECK_FALSE(vxf::BandInterior(*density, band).holdsLeaf(openvdb::Coord(0)));
        }
        CHECK(vxf::BandInterior(*density, 1.2).holdsLeaf(openvdb::Coord(0))); // 12 deep: voxels [-12, 11]
    }
}

TEST_CASE("blocks 64 voxels deep become 128³ tiles", "[band]")
{
    auto density = openvdb::FloatGrid::create(0.0f);
    density->tree().fill(openvdb::CoordBBox(openvdb::Coord(-192), openvdb::Coord(191)), 1.0f, true); // 384³, as tiles
    auto source = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    source->tree().topologyUnion(density->tree());
    const openvdb::Coord probe(5, 6, 7);
    source->tree().setValueOn(probe, openvdb::Vec3f(512.0f)); // one voxel of a 128³ block differs
    const openvdb::Vec3d before = vxf::gridEnergy(*source);
    vxf::AdaptiveBandReport copied;
    const auto copy = vxf::coarsenedBeyondBand(*source, *density, 1.0, copied);
    const auto report = vxf::coarsenBeyondBand(*source, *density, 1.0); // 1 voxel: depth max(1, 64)
    CHECK(copied.internalTiles == report.internalTiles);
    CHECK(copied.coarseVoxels == report.coarseVoxels);
    CHECK(vxf::test::identicalGrids(*copy, *source));
    CHECK(copy->tree().getValueDepth(probe) == 1);
    // Blocks [-128, -1] and [0, 127] per axis lie 64 deep: 8 of them; 7 already are tiles
    // (the fill made them), the one holding the probe becomes one.
    CHECK(report.internalTiles == 1);
    const openvdb::Vec3d after = vxf::gridEnergy(*source);
    for (int c = 0; c < 3; ++c) CHECK(after[c] == Approx(before[c]).epsilon(1e-6));
    CHECK(source->tree().getValueDepth(probe) == 1); // a level-2 tile sits at depth 1 below the root
    CHECK(source->tree().getValue(probe)[0] == Approx(512.0 / (128.0 * 128.0 * 128.0)));
}

TEST_CASE("scattering with a band matches full resolution near the surface", "[band][scatter]")
{
    // A homogeneous cube, lit uniformly: J0 = σs φ0/4π everywhere inside.
    const vxf::Material m = vxf::test::albedoMaterial(10.0, 0.8); // mean free path 0.1 = 1 voxel
    // (Not a structured binding: clang 14 lets no lambda capture one.)
    const auto grids = cube(16, 0.1);
    const auto density = grids.first;
    const auto source = grids.second;
    for (auto it = source->tree().beginValueOn(); it; ++it) it.setValue(openvdb::Vec3f(float(m.sigmaS[0] / (4.0 * M_PI))));
    const auto run = [&](double band) {
        vxf::VoxelSet set(density->transformPtr());
        auto d = density->deepCopy();
        d->setName("density");
        auto j = source->deepCopy();
        j->setName("scatter_source");
        set.put(d);
        set.put(j);
        const vxf::Medium medium(set, m);
        vxf::ScatterOptions options;
        options.passes = 3;
        options.tolerance = 0.0;
        options.band = band;
        options.pass.directions = 16;
        const auto report = vxf::scatter(set, medium, options);
        return std::make_pair(set.get<openvdb::Vec3SGrid>("scatter"), report);
    };
    const auto [full, fullReport] = run(0.0);
    const auto [banded, bandReport] = run(0.4); // 4 voxels = 4 mean free paths
    CHECK(bandReport.band.leafTiles == 8); // [-8, 7]³
    CHECK(fullReport.band.leafTiles == 0);
    CHECK(bandReport.band.fineVoxels < fullReport.band.fineVoxels);
    // Within the band (the part a camera sees) the two agree; energy agrees overall.
    for (const openvdb::Coord c : {openvdb::Coord(-16, 0, 0), openvdb::Coord(15, 5, -3), openvdb::Coord(0, -13, 10)}) {
        INFO(c);
        CHECK(banded->tree().getValue(c)[0] == Approx(full->tree().getValue(c)[0]).epsilon(0.02));
    }
    CHECK(vxf::gridEnergy(*banded)[0] == Approx(vxf::gridEnergy(*full)[0]).epsilon(0.02));
}

TEST_CASE(
    "the accelerated sweeps take the band's tiles as coarse cells: the surface's light as at full resolution", "[band][scatter][sweep]")
{
    // A sphere of albedo 0.99 and 6 mean free paths' radius (8 voxels each) with its surface,
    // lit uniformly; beyond a band of one mean free path the sweeps take 8³ blocks as one cell.
    const vxf::Material m = vxf::test::albedoMaterial(6.0, 0.99);
    const auto [full, fullReport] = sweptSphere(m, 48, 0.0, 16);
    const auto [banded, bandReport] = sweptSphere(m, 48, 8.0 / 48.0, 16);
    INFO(bandReport.stopReason);
    CHECK(bandReport.accelerated);
    CHECK(bandReport.passes.size() <= fullReport.passes.size() + 2);
    CHECK(bandReport.band.leafTiles > 200);
    // Each coarse cell one value a sweep (the band's leaves, 8 to 16 voxels deep, most of this
    // small sphere's voxels).
    CHECK(double(bandReport.sweptVoxels) < 0.85 * double(fullReport.sweptVoxels));
    // Within the band, the light the camera sees, the two agree; energy within 3%.
    const auto acc = banded->getConstAccessor();
    for (const openvdb::Coord c :
        {openvdb::Coord(-44, 0, 0), openvdb::Coord(30, 30, 5), openvdb::Coord(0, -20, 40), openvdb::Coord(-38, 0, 0)}) {
        INFO(c);
        CHECK(acc.getValue(c)[0] == Approx(full->tree().getValue(c)[0]).epsilon(0.005));
    }
    CHECK(vxf::gridEnergy(*banded)[0] == Approx(vxf::gridEnergy(*full)[0]).epsilon(0.03));
    // A tile of the result holds its coarse cell's value, the centre's the furthest off (deepest
    // in the cells, near albedo 1: docs/accuracy-notes.md (ah), what the band costs).
    CHECK(banded->tree().probeConstLeaf(openvdb::Coord(0)) == nullptr);
    CHECK(acc.getValue(openvdb::Coord(0))[0] == Approx(full->tree().getValue(openvdb::Coord(0))[0]).epsilon(0.15));
}

TEST_CASE("coarse cells sweep the same whatever the thread count", "[band][sweep][threads]")
{
    const vxf::Material m = vxf::test::albedoMaterial(4.0, 0.99); // cells of a mean free path
    const auto run = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
        return sweptSphere(m, 32, 4.0 / 32.0, 8).first;
    };
    const auto one = run(1), two = run(2);
    std::string why;
    CHECK(vxf::test::identicalGrids(*one, *two, &why));
    INFO(why);
}

TEST_CASE("a banded scatter is budgeted by what its sweeps hold, and refused by it", "[band][memory]")
{
    // The thick bunny at dim 512 with a band of one mean free path: 28.1M active voxels, 14.0M
    // swept, 2011 MiB measured (docs/accuracy-notes.md (ah)); without the band 2728 MiB.
    const double mib = 1024.0 * 1024.0;
    const vxf::MemoryEstimate banded = vxf::bandedScatterMemory(28106951.0, 13985683.0);
    CHECK(banded.bytes > 2011.0 * mib);
    CHECK(banded.bytes < 1.2 * 2011.0 * mib);
    CHECK(banded.bytes < vxf::scatterMemory(28106951.0).bytes);
    CHECK(banded.how.find("swept voxels") != std::string::npos);
    // A sphere whose band leaves most voxels to coarse cells, under a budget below its
    // estimate: refused before the solve, naming the band's estimate.
    const vxf::Material m = vxf::test::albedoMaterial(12.0, 0.99);
    vxf::VoxelSet set = vxf::test::uniformSphere(m, 1.0, 48);
    const vxf::Medium medium(set, m);
    vxf::ScatterOptions options;
    options.pass.kernel = vxf::ScatterKernel::Sweep;
    options.band = 8.0 / 48.0;
    vxf::setMemoryBudget(std::uint64_t(64) << 20);
    CHECK_THROWS_WITH(vxf::scatter(set, medium, options), Catch::StartsWith("scatter needs about") && Catch::Contains("swept voxels"));
    vxf::setMemoryBudget(0); // the default again, for the tests after this one
}
