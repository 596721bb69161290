#include <vxf/scatter/CoarseLevel.h>
#include <vxf/scatter/Scatter.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

namespace {

/// A homogeneous ball of radius 1, @a cells voxels per unit (density 1), lit uniformly:
/// φ0 = 1, so `scatter_source` = σs/(4π).
vxf::VoxelSet uniformlyLitBall(const vxf::Material& m, int cells) { return vxf::test::uniformSphere(m, 1.0, cells); }

} // namespace

TEST_CASE("a coarse voxel covers a block of fine voxels, centre on centre", "[coarse]")
{
    const auto fine = openvdb::math::Transform::createLinearTransform(0.1);
    for (int f : {2, 4, 8}) {
        const auto coarse = vxf::coarseTransform(*fine, f);
        CHECK(coarse->voxelSize()[0] == Approx(0.1 * f));
        // Coarse voxel (1, -1, 0) covers fine f..2f−1, −f..−1, 0..f−1: its centre is theirs.
        const openvdb::Vec3d centre = coarse->indexToWorld(openvdb::Vec3d(1, -1, 0));
        const openvdb::Vec3d expected = fine->indexToWorld(openvdb::Vec3d(1.5 * f - 0.5, -0.5 * f - 0.5, 0.5 * f - 0.5));
        CHECK((centre - expected).length() < 1e-12);
    }
}

TEST_CASE("block averages keep the total, voxels and tiles alike", "[coarse]")
{
    auto fine = openvdb::FloatGrid::create(0.0f);
    fine->setTransform(openvdb::math::Transform::createLinearTransform(0.5));
    fine->tree().fill(openvdb::CoordBBox(openvdb::Coord(-16), openvdb::Coord(-9)), 1.0f, true); // one active tile
    fine->tree().setValueOn(openvdb::Coord(3, 5, -7), 0.25f);
    fine->tree().setValueOn(openvdb::Coord(-1, 0, 2), 0.75f);
    double total = 0.0;
    for (auto it = fine->cbeginValueOn(); it; ++it) total += double(*it) * double(it.getVoxelCount());
    for (int f : {2, 4, 8}) {
        const auto coarse = vxf::blockAverage(*fine, f, vxf::coarseTransform(fine->transform(), f));
        double sum = 0.0;
        for (auto it = coarse->cbeginValueOn(); it; ++it) sum += double(*it) * double(it.getVoxelCount()) * f * f * f;
        INFO("factor " << f);
        CHECK(sum == Approx(total).epsilon(1e-6));
        // The tile fills whole blocks: 1 there; the lone voxel (−1, 0, 2) is 0.75 of one f³ block.
        CHECK(coarse->tree().getValue(openvdb::Coord(-16 / f)) == Approx(1.0));
        CHECK(coarse->tree().getValue(openvdb::Coord(-1, 0, 2 / f)) == Approx(0.75 / (f * f * f)));
    }
}

TEST_CASE("prolongation interpolates a linear field exactly", "[coarse]")
{
    const auto fineXform = openvdb::math::Transform::createLinearTransform(0.25);
    const auto coarseXform = vxf::coarseTransform(*fineXform, 4);
    const auto field = [](const openvdb::Vec3d& w) { return float(1.0 + 2.0 * w.x() - 0.5 * w.y() + 3.0 * w.z()); };
    auto coarse = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    coarse->setTransform(coarseXform);
    for (int i = -4; i <= 4; ++i)
        for (int j = -4; j <= 4; ++j)
            for (int k = -4; k <= 4; ++k) {
                coarse->tree().setValueOn(
                    openvdb::Coord(i, j, k), openvdb::Vec3f(field(coarseXform->indexToWorld(openvdb::Coord(i, j, k)))));
            }
    auto fine = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    fine->setTransform(fineXform);
    for (int i = -8; i <= 8; i += 3)
        for (int j = -8; j <= 8; j += 5)
            for (int k = -8; k <= 8; k += 2) fine->tree().setValueOn(openvdb::Coord(i, j, k), openvdb::Vec3f(-1.0f));
    const auto out = vxf::prolong(*coarse, *fine);
    CHECK(out->activeVoxelCount() == fine->activeVoxelCount());
    for (auto it = out->cbeginValueOn(); it; ++it) {
        const float expected = field(fineXform->indexToWorld(it.getCoord()));
        INFO(it.getCoord());
        CHECK((*it).y() == Approx(expected).margin(1e-4));
    }
}

TEST_CASE("coarse passes converge the series of a high albedo to its closed form", "[coarse][scatter]")
{
    // A homogeneous ball of radius 1 at dx 1/16, σt = 20, albedo 0.9, lit uniformly (φ0 = 1):
    // at the centre, far from the boundary, Σ_k a^k = a/(1−a) = 9.
    const vxf::Material m = vxf::test::albedoMaterial(20.0, 0.9);
    vxf::VoxelSet set = uniformlyLitBall(m, 16);
    vxf::ScatterOptions options;
    options.passes = 300;
    options.tolerance = 1e-4;
    options.pass.directions = 32;
    options.finePasses = 2;
    options.coarseFactor = 2;
    const auto report = vxf::scatter(set, vxf::Medium(set, m), options);
    CHECK(report.passes.size() > 20); // the pass ratio settles within 1e-4 of the sum after ~40 passes
    CHECK_FALSE(report.passes[1].coarse);
    CHECK(report.passes[2].coarse);
    const float centre = set.get<openvdb::Vec3SGrid>("scatter")->tree().getValue(openvdb::Coord(0)).x();
    CHECK(centre == Approx(9.0).epsilon(0.03));

    options.coarseFactor = 3;
    CHECK_THROWS_WITH(vxf::scatter(set, vxf::Medium(set, m), options), "coarse factor must be 2, 4 or 8, got 3");
}

TEST_CASE("the coarse cycles' correction brings coarse passes to the plain iteration's sum", "[coarse][scatter]")
{
    // A small thick ball (radius 1, dx 1/8, σt = 10, albedo 0.99), lit uniformly: light leaks
    // out through the surface, and a 4x coarser lattice (5³ voxels) leaks a different amount;
    // the series' 1/(1−r) magnifies that. Compared in the outer shell, where the light that
    // leaves the medium comes from. Albedo 0.999 at σt = 30 too: there the uncorrected coarse
    // passes give 33% too much light, and the first correction step overshoots (−38%, +12%, …).
    const auto [sigmaT, albedo] = GENERATE(std::make_pair(10.0, 0.99), std::make_pair(30.0, 0.999));
    const vxf::Material m = vxf::test::albedoMaterial(sigmaT, albedo);
    const double dx = 1.0 / 8.0;
    const auto run = [&](int finePasses, bool correction) {
        vxf::VoxelSet set = uniformlyLitBall(m, 8);
        vxf::ScatterOptions options;
        options.passes = 5000;
        options.tolerance = 1e-5;
        options.pass.directions = 32;
        options.finePasses = finePasses;
        options.coarseFactor = 4;
        options.coarseCorrection = correction;
        const auto report = vxf::scatter(set, vxf::Medium(set, m), options);
        if (correction) {
            // Each cycle's share of the sum, signed, and no limit reached.
            CHECK_THAT(report.stopReason, Catch::Contains("corrected by") && Catch::Contains("% of the sum;"));
            CHECK_THAT(report.stopReason, !Catch::Contains("limit"));
            // Conjugate steps settle in 3-4 cycles here (plain steps took 6 at albedo 0.99:
            // +4.9%, +4.4%, +2.3%, +1.4%, +0.88%, …).
            CHECK(report.correctionCycles <= 4);
        }
        double shell = 0.0;
        for (auto it = set.get<openvdb::Vec3SGrid>("scatter")->cbeginValueOn(); it; ++it) {
            if (it.getCoord().asVec3d().length() * dx > 0.75) shell += (*it).x();
        }
        return shell;
    };
    const double plain = run(0, false);
    const double uncorrected = run(2, false) / plain - 1.0;
    const double corrected = run(2, true) / plain - 1.0;
    INFO("albedo " << albedo << ": uncorrected " << uncorrected << ", corrected " << corrected);
    // The cycles go on until what is left is below 0.3% of the sum.
    CHECK(std::abs(corrected) < 0.004);
    CHECK(std::abs(uncorrected) > 6.0 * std::abs(corrected));
}
