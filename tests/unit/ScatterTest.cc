#include <vxf/scatter/Scatter.h>

#include <vxf/core/ProceduralMesh.h>
#include <vxf/light/InteriorField.h>
#include <vxf/voxelize/Voxelize.h>

#include "TestSupport.h"

#include <boost/math/special_functions/expint.hpp>
#include <catch2/catch.hpp>
#include <tbb/global_control.h>

using vxf::test::uniformSphere;

TEST_CASE("in a large homogeneous medium each pass scales by the albedo", "[scatter]")
{
    const vxf::Material m = vxf::test::albedoMaterial(20.0, 0.9); // sigma_t R = 20: the centre does not see the boundary
    vxf::VoxelSet set = uniformSphere(m, 1.0);
    const vxf::Medium medium(set, m);
    vxf::ScatterOptions options;
    options.passes = 4;
    options.tolerance = 0.0;
    options.keepPasses = true;
    const auto report = vxf::scatter(set, medium, options);
    REQUIRE(report.passes.size() == 4);
    const openvdb::Coord centre(0);
    double expected = 0.0, power = 1.0;
    for (int k = 1; k <= 4; ++k) {
        power *= 0.9;
        expected += power;
        const float pass = set.get<openvdb::Vec3SGrid>("scatter_pass_" + std::to_string(k))->tree().getValue(centre).x();
        INFO("pass " << k);
        CHECK(pass == Approx(power).epsilon(0.02));
    }
    CHECK(set.get<openvdb::Vec3SGrid>("scatter")->tree().getValue(centre).x() == Approx(expected).epsilon(0.02));
    CHECK(set.get<openvdb::Vec3SGrid>("illumination")->tree().getValue(centre).x() == Approx(1.0 + expected).epsilon(0.02));
    // No pass adds energy.
    for (std::size_t p = 1; p < report.passes.size(); ++p) CHECK(report.passes[p].ratio <= 0.9 + 1e-6);
}

TEST_CASE("albedo near 1 stays finite and bounded, tolerance stops the passes", "[scatter][stability]")
{
    const vxf::Material m = vxf::test::albedoMaterial(8.0, 0.9999);
    vxf::VoxelSet set = uniformSphere(m, 1.0);
    const vxf::Medium medium(set, m);
    vxf::ScatterOptions options;
    options.passes = 6;
    options.tolerance = 0.2;
    options.accelerate = false; // plain source iteration (accelerated: SweepSolveTest)
    options.pass.directions = 24;
    const auto report = vxf::scatter(set, medium, options);
    // Each pass keeps most of the light (ratio near 1), so the rest of the series, φ_K·r/(1−r),
    // stays far above 20% of the sum: the tolerance must not stop it (it used to, when it
    // only asked whether the last pass added little).
    CHECK(report.passes.size() == 6);
    // The limit says what it left out: most of the light, at this albedo.
    CHECK(report.stopReason.rfind("reached 6 passes; the rest of the series would add about ", 0) == 0);
    CHECK(report.stopReason.find("set fine_passes") != std::string::npos);
    for (std::size_t p = 1; p < report.passes.size(); ++p) CHECK(report.passes[p].ratio <= 1.0);
    bool bounded = true;
    for (auto it = set.get<openvdb::Vec3SGrid>("scatter")->cbeginValueOn(); it; ++it) {
        bounded = bounded && std::isfinite((*it)[0]) && (*it)[0] >= 0.0f && (*it)[0] <= 6.0f;
    }
    CHECK(bounded);

    // Albedo 0.5: the series is short, and the tolerance stops it.
    const vxf::Material low = vxf::test::albedoMaterial(8.0, 0.5);
    vxf::VoxelSet lowSet = uniformSphere(low, 1.0);
    options.passes = 30;
    options.tolerance = 0.01;
    const auto lowReport = vxf::scatter(lowSet, vxf::Medium(lowSet, low), options);
    CHECK(lowReport.passes.size() < 12);
    CHECK(lowReport.stopReason.find("below the tolerance") != std::string::npos);
}

TEST_CASE("no scattering when sigma_s is zero", "[scatter]")
{
    const vxf::Material m = vxf::test::albedoMaterial(5.0, 0.0);
    vxf::VoxelSet set = uniformSphere(m, 1.0);
    const auto report = vxf::scatter(set, vxf::Medium(set, m));
    CHECK(report.passes.empty());
    CHECK(report.stopReason == "the medium does not scatter (sigma_s = 0)");
    CHECK(vxf::gridEnergy(*set.get<openvdb::Vec3SGrid>("scatter")) == openvdb::Vec3d(0.0));
}

TEST_CASE("continuing from a kept pass equals running straight through, for any thread count", "[scatter]")
{
    const vxf::Material m = vxf::test::albedoMaterial(6.0, 0.8);
    vxf::ScatterOptions three;
    three.passes = 3;
    three.tolerance = 0.0;
    three.keepPasses = true;
    three.pass.directions = 16;
    vxf::VoxelSet straight = uniformSphere(m, 1.0);
    vxf::scatter(straight, vxf::Medium(straight, m), three);

    vxf::VoxelSet resumed = uniformSphere(m, 1.0);
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        vxf::ScatterOptions two = three;
        two.passes = 2;
        vxf::scatter(resumed, vxf::Medium(resumed, m), two);
        vxf::ScatterOptions one = three;
        one.passes = 1;
        one.fromPass = 2;
        vxf::scatter(resumed, vxf::Medium(resumed, m), one);
    }
    std::string why;
    CHECK(vxf::test::identicalGrids(*straight.find("scatter_pass_3"), *resumed.find("scatter_pass_3"), &why));
    INFO(why);
    const auto a = straight.get<openvdb::Vec3SGrid>("scatter")->tree().getValue(openvdb::Coord(3, 1, 2));
    const auto b = resumed.get<openvdb::Vec3SGrid>("scatter")->tree().getValue(openvdb::Coord(3, 1, 2));
    CHECK(a.x() == Approx(b.x()).epsilon(1e-6));

    vxf::ScatterOptions missing;
    missing.fromPass = 5;
    CHECK_THROWS_WITH(vxf::scatter(resumed, vxf::Medium(resumed, m), missing), "no grid named 'scatter_pass_4' in the voxel set");
}

TEST_CASE("extrapolating the geometric tail reaches the converged sum in few passes", "[scatter]")
{
    const vxf::Material m = vxf::test::albedoMaterial(20.0, 0.9);
    vxf::VoxelSet set = uniformSphere(m, 1.0);
    vxf::ScatterOptions options;
    options.passes = 4;
    options.tolerance = 0.0;
    options.extrapolateTail = true;
    options.accelerate = false; // the tail of plain source iteration
    options.pass.directions = 32;
    const auto report = vxf::scatter(set, vxf::Medium(set, m), options);
    CHECK(report.tailFactor > 5.0); // the global ratio is below 0.9: the boundary leaks
    // Σ_k 0.9^k = 9 at the centre, far from the boundary; four passes alone give 3.1. The tail,
    // capped by the global ratio (< 0.9: the boundary leaks), brings it most of the way, never beyond.
    const float centre = set.get<openvdb::Vec3SGrid>("scatter")->tree().getValue(openvdb::Coord(0)).x();
    CHECK(centre > 7.0f);
    CHECK(centre < 9.0f * 1.02f);
}

TEST_CASE("a settled pass ratio ends the series early, with its rest added", "[scatter]")
{
    // Albedo 0.99, σt R = 10 at dx 1/8: each pass keeps ~95% of the light, so the rest of the
    // series stays above 1e-3 of the sum for ~150 passes. Once the pass ratio has settled the
    // rest is φ_K·r/(1−r) to within the tolerance; the series stops there and adds it.
    const vxf::Material m = vxf::test::albedoMaterial(10.0, 0.99);
    const auto run = [&](int passes, double tolerance) {
        vxf::VoxelSet set = uniformSphere(m, 1.0, 8);
        vxf::ScatterOptions options;
        options.passes = passes;
        options.tolerance = tolerance;
        options.accelerate = false; // plain source iteration, whose rest is a geometric series
        options.pass.directions = 16;
        const auto report = vxf::scatter(set, vxf::Medium(set, m), options);
        return std::make_pair(report, vxf::gridEnergy(*set.get<openvdb::Vec3SGrid>("scatter"))[0]);
    };
    const auto [full, converged] = run(300, 0.0); // 0.955^300: 1e-6 left
    INFO("full: " << full.passes.size() << " passes, ratio " << full.passes.back().ratio << ", energy " << converged);
    REQUIRE(full.passes.back().ratio < 0.99);
    const auto [early, energy] = run(300, 1e-3);
    INFO(early.stopReason);
    CHECK(early.stopReason.find("known to within") != std::string::npos);
    CHECK(early.stopReason.find("; added") != std::string::npos);
    CHECK(early.tailFactor > 5.0); // it stopped with much of the series still to come...
    CHECK(early.passes.size() < 100);
    CHECK(energy == Approx(converged).epsilon(2e-3)); // ...and the rest it added is right
    // The same passes without the rest: far from the sum.
    const auto [cut, cutEnergy] = run(int(early.passes.size()), 0.0);
    CHECK(cutEnergy < converged * 0.9);
}

TEST_CASE("a march cut off at the transmittance cutoff adds the light beyond it", "[scatter]")
{
    // Uniform source J deep in a homogeneous medium (σt R = 10): one pass gives φ = 4πJ/σt =
    // albedo·φ0 at the centre. A march stopped at transmittance c misses a share c of it
    // unless it adds what lies beyond (J held over an unbounded medium: exact here).
    const vxf::Material m = vxf::test::albedoMaterial(10.0, 0.5);
    for (const double cutoff : {0.05, 1e-3}) {
        vxf::VoxelSet set = uniformSphere(m, 1.0);
        vxf::ScatterOptions options;
        options.passes = 1;
        options.tolerance = 0.0;
        options.accelerate = false; // one pass: the first order alone
        options.pass.directions = 32;
        options.pass.cutoff = cutoff;
        vxf::scatter(set, vxf::Medium(set, m), options);
        INFO("cutoff " << cutoff);
        CHECK(set.get<openvdb::Vec3SGrid>("scatter")->tree().getValue(openvdb::Coord(0)).x() == Approx(0.5).epsilon(2e-3));
    }
}

namespace {

/// The second pass in a half-space of uniform source (φ0 = 1, albedo @a albedo) at optical
/// depth @a tau: (A/2)·∫ E1(|τ − t|)·φ1(t) dt over t ≥ 0, φ1(t) = A·(1 − E2(t)/2); by midpoints
/// in u = √|τ − t| (the kernel's logarithm at t = τ made smooth).
double secondPassOnHalfSpace(double albedo, double tau)
{
    const auto phi1 = [&](double t) { return albedo * (1.0 - 0.5 * boost::math::expint(2, std::max(t, 1e-300))); };
    const auto kernel = [](double s) { return boost::math::expint(1, s); };
    const int n = 4000;
    double sum = 0.0;
    const double uBeyond = std::sqrt(40.0), du = uBeyond / n; // t > τ: up to 40 mean free paths
    for (int i = 0; i < n; ++i) {
        const double u = (i + 0.5) * du;
        sum += 2.0 * u * kernel(u * u) * phi1(tau + u * u) * du;
    }
    if (tau > 0.0) {
        const double uBefore = std::sqrt(tau), dv = uBefore / n; // 0 < t < τ
        for (int i = 0; i < n; ++i) {
            const double u = (i + 0.5) * dv;
            sum += 2.0 * u * kernel(u * u) * phi1(tau - u * u) * dv;
        }
    }
    return 0.5 * albedo * sum;
}

} // namespace

TEST_CASE("two passes from a uniform source near a flat face: the closed form and a 1-D quadrature at every depth, the face anywhere in "
          "its voxel",
    "[scatter]")
{
    // A half-space of uniform source J0 = σs·φ0/4π: at depth z the directions leaving through
    // the face see the medium for z/μ, so one pass gives φ1(z) = A·φ0·(1 − E2(σt z)/2), half
    // of A·φ0 on the face itself. Near the face φ1 rises with infinite slope (E2' = −E1), a
    // voxel or two per mean free path sees it all; the second pass reads it from SourceField's
    // lattice, whose skin and outside voxels its layers fill (J on the surface, a depth and a
    // rise 1 − E2 beneath). The skin voxel (centre within half a voxel of the face, either
    // side) holds the value on the face (Medium::Sampler::skinPoint), its directions split
    // exactly in half there. With the face at four offsets in its voxel; a box at least 8 mean
    // free paths deep around the probed line. The skin's second pass comes out −0.9%, +1.4%,
    // −0.1%, −2.8% off at the four offsets (within 0.25% when the passes read the layers
    // themselves, which cost the thick bunny accuracy: SourceField::Near), the voxel 0.85
    // deep −0.7%, every voxel deeper within 0.5%. (The linear continuation before the layers
    // left it 6.6% low on the face where it passes through the centres.)
    const double dx = 1.0 / 32.0, sigmaT = 16.0, albedo = 0.8; // 2 voxels per mean free path
    const vxf::Material m = vxf::test::albedoMaterial(sigmaT, albedo);
    for (const double offset : {0.1, 0.35, 0.6, 0.85}) {
        const double face = 0.5 + offset * dx; // voxel centres lie on dx·ℤ
        vxf::VoxelizeOptions voxelize;
        voxelize.voxelSize = dx;
        vxf::VoxelSet set = vxf::voxelize(vxf::makeBox(openvdb::Vec3d(-0.25, -0.5, -0.5), openvdb::Vec3d(face, 0.5, 0.5)), voxelize);
        vxf::test::putConstantFluence(set, "direct", 1.0);
        set.put(vxf::sourceFromFluence(vxf::Medium(set, m), *set.get<openvdb::Vec3SGrid>("direct")));
        vxf::ScatterOptions options;
        options.passes = 2;
        options.tolerance = 0.0;
        options.keepPasses = true;
        options.pass.directions = 64;
        vxf::scatter(set, vxf::Medium(set, m), options);
        const auto phi1 = set.get<openvdb::Vec3SGrid>("scatter_pass_1")->getConstAccessor();
        const auto phi2 = set.get<openvdb::Vec3SGrid>("scatter_pass_2")->getConstAccessor();
        int skins = 0;
        for (int i = 10; double(i) * dx < face + 0.5 * dx; ++i) {
            const double centreDepth = face - double(i) * dx;
            const double depth = centreDepth < 0.5 * dx ? 0.0 : centreDepth; // the skin's value is on the face
            skins += depth == 0.0;
            INFO("face offset " << offset << " voxel, centre " << i << ": depth " << depth / dx << " voxels");
            const double first = albedo * (1.0 - 0.5 * boost::math::expint(2, std::max(sigmaT * depth, 1e-300)));
            CHECK(phi1.getValue(openvdb::Coord(i, 0, 0)).x() == Approx(first).epsilon(0.003));
            CHECK(phi2.getValue(openvdb::Coord(i, 0, 0)).x() ==
                Approx(secondPassOnHalfSpace(albedo, sigmaT * depth))
                    .epsilon(depth == 0.0 ? 0.03
                            : depth < dx  ? 0.01
                                          : 0.005));
        }
        CHECK(skins == 1);
    }
}

TEST_CASE("with a Henyey-Greenstein phase each pass scales by the reduced albedo, at albedo 1 none loses light", "[scatter][phase]")
{
    // The transport's medium (Phase.h): σs' = (1 − g)σs, σt' = σt − gσs, so each pass deep in a
    // large medium scales by a' = σs'/σt', and at albedo 1 by exactly 1 for any g: the forward
    // part of the phase keeps light on its way, none is lost. Both kernels, plain passes.
    const auto kernel = GENERATE(vxf::ScatterKernel::Gather, vxf::ScatterKernel::Sweep);
    for (const auto& [albedo, g] : {std::pair{1.0, 0.7}, std::pair{0.9, 0.5}, std::pair{0.9, -0.5}}) {
        vxf::Material m = vxf::test::albedoMaterial(40.0, albedo); // σt' R ≥ 12 at g = 0.7
        m.phaseG = g;
        vxf::VoxelSet set = uniformSphere(m, 1.0);
        const vxf::Medium medium(set, m);
        vxf::ScatterOptions options;
        options.passes = 3;
        options.tolerance = 0.0;
        options.keepPasses = true;
        options.pass.kernel = kernel;
        vxf::scatter(set, medium, options);
        const double reducedS = (1.0 - g) * albedo * 40.0, reduced = reducedS / (40.0 - g * albedo * 40.0);
        double power = 1.0;
        for (int k = 1; k <= 3; ++k) {
            power *= reduced;
            INFO("albedo " << albedo << ", g " << g << ", pass " << k);
            CHECK(set.get<openvdb::Vec3SGrid>("scatter_pass_" + std::to_string(k))->tree().getValue(openvdb::Coord(0)).x() ==
                Approx(power).epsilon(0.02));
        }
    }
}

TEST_CASE("passes 0 runs none: scatter zero, illumination the direct light, for every kernel", "[scatter]")
{
    const vxf::Material m = vxf::test::albedoMaterial(8.0, 0.9);
    for (const auto kernel : {vxf::ScatterKernel::Sweep, vxf::ScatterKernel::Gather}) {
        for (const bool accelerate : {true, false}) {
            vxf::VoxelSet set = uniformSphere(m, 1.0);
            const vxf::Medium medium(set, m);
            vxf::ScatterOptions options;
            options.passes = 0;
            options.pass.kernel = kernel;
            options.accelerate = accelerate;
            const auto report = vxf::scatter(set, medium, options);
            CHECK(report.passes.empty());
            CHECK(report.stopReason == "passes 0: no multiple scattering (single scattering alone)");
            const auto scattered = set.get<openvdb::Vec3SGrid>("scatter");
            CHECK(scattered->activeVoxelCount() == set.get<openvdb::Vec3SGrid>("scatter_source")->activeVoxelCount());
            for (auto it = scattered->cbeginValueOn(); it; ++it) REQUIRE(*it == openvdb::Vec3f(0.0f));
            CHECK(vxf::test::identicalGrids(*set.get<openvdb::Vec3SGrid>("illumination"), *set.get<openvdb::Vec3SGrid>("direct")));
        }
    }
}

TEST_CASE("the accelerated sweeps read the medium through its trees, to the same sums", "[scatter]")
{
    // scatterMedium leaves out the dense copies where the sweeps solve the whole sum (their
    // lattice reads each voxel once); the gathers' marches keep them. The sums are the same
    // bits either way, with an isotropic and a forward-scattering phase.
    for (const double g : {0.0, 0.6}) {
        vxf::Material m = vxf::test::albedoMaterial(12.0, 0.95);
        m.phaseG = g;
        vxf::ScatterOptions options;
        options.passes = 8;
        options.pass.kernel = vxf::ScatterKernel::Sweep;
        options.pass.directions = 8;
        vxf::VoxelSet lit = uniformSphere(m, 1.0);
        if (g != 0.0) { // the first moment's path: the source's mean direction (none)
            auto a0 = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
            a0->setName("scatter_source_anisotropy");
            a0->setTransform(lit.transformPtr());
            a0->tree().topologyUnion(lit.get<openvdb::Vec3SGrid>("scatter_source")->tree());
            lit.put(a0);
        }
        CHECK(vxf::scatterMedium(lit, m, options).uniformBricks() == nullptr);
        vxf::ScatterOptions gathers = options;
        gathers.pass.kernel = vxf::ScatterKernel::Gather;
        CHECK(vxf::scatterMedium(lit, m, gathers).uniformBricks() != nullptr);

        vxf::VoxelSet viaTrees = lit, viaCopies = lit;
        vxf::scatter(viaTrees, vxf::scatterMedium(viaTrees, m, options), options);
        vxf::scatter(viaCopies, vxf::Medium(viaCopies, m), options);
        std::string why;
        INFO("g " << g);
        CHECK(vxf::test::identicalGrids(*viaTrees.find("scatter"), *viaCopies.find("scatter"), &why));
        INFO(why);
        CHECK(vxf::gridEnergy(*viaTrees.get<openvdb::Vec3SGrid>("scatter"))[0] > 0.0);
        CHECK(bool(viaTrees.find("scatter_anisotropy")) == (g != 0.0));
    }
}
