#include <vxf/transport/Medium.h>
#include <vxf/transport/Phase.h>
#include <vxf/scatter/SweepPass.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <cmath>

TEST_CASE("Henyey-Greenstein: unit mean over the sphere, mean cosine g, 1 everywhere at g = 0", "[phase]")
{
    for (const double g : {-0.95, -0.5, 0.0, 0.3, 0.8, 0.95}) {
        INFO("g " << g);
        // ∫ p dω = ½ ∫_{−1}^{1} 4πp(μ) dμ, midpoints in μ, fine enough for g = 0.95's peak.
        const int n = 400000;
        double mean = 0.0, cosine = 0.0;
        for (int i = 0; i < n; ++i) {
            const double mu = -1.0 + (i + 0.5) * 2.0 / n;
            const double p = vxf::henyeyGreenstein4Pi(g, mu);
            mean += 0.5 * p * 2.0 / n;
            cosine += 0.5 * p * mu * 2.0 / n;
        }
        CHECK(mean == Approx(1.0).epsilon(1e-4));
        CHECK(cosine == Approx(g).margin(1e-4));
        // Closed form at straight on and straight back: (1 ± g)/(1 ∓ g)².
        CHECK(vxf::henyeyGreenstein4Pi(g, 1.0) == Approx((1.0 + g) / ((1.0 - g) * (1.0 - g))));
        CHECK(vxf::henyeyGreenstein4Pi(g, -1.0) == Approx((1.0 - g) / ((1.0 + g) * (1.0 + g))));
    }
    CHECK(vxf::henyeyGreenstein4Pi(0.0, 0.3) == 1.0);
}

TEST_CASE("a medium of phase g holds the delta-M transport, isotropic() the similarity relation's, actual() the material's", "[phase]")
{
    vxf::Material m = vxf::test::greyMaterial(1.0, 4.0);
    m.phaseG = 0.75;
    vxf::VoxelSet set = vxf::test::uniformSphere(m, 1.0, 8);
    const vxf::Medium medium(set, m);
    const openvdb::Vec3d centre(0.0);
    // f = g⁴ = 0.31640625 of σs kept in the beam: σs* = 4(1 − f) = 2.734375, σt* = 5 − 4f =
    // 3.734375; the rest's mean cosine g* = (g − f)/(1 − f) = 0.634286, and σt* − g*σs* = 2 =
    // σt − gσs (transport-corrected).
    vxf::Medium::Sampler transport(medium);
    CHECK(transport.sigmaS(centre).x() == Approx(2.734375));
    CHECK(transport.sigmaT(centre).x() == Approx(3.734375));
    CHECK(medium.material().phaseG == Approx(0.43359375 / 0.68359375));
    CHECK(medium.material().sigmaT().x() - medium.material().phaseG * medium.material().sigmaS.x() == Approx(2.0));
    CHECK(medium.phaseG() == 0.75);
    // The similarity relation: σs' = (1 − g)σs = 1, σt' = σt − gσs = 2, isotropic.
    const vxf::Medium isotropic = medium.isotropic();
    vxf::Medium::Sampler reduced(isotropic);
    CHECK(reduced.sigmaS(centre).x() == Approx(1.0));
    CHECK(reduced.sigmaT(centre).x() == Approx(2.0));
    CHECK(isotropic.material().phaseG == 0.0); // a medium made from it (coarse levels) is not scaled again
    CHECK(isotropic.phaseG() == 0.75);
    const vxf::Medium actual = medium.actual();
    vxf::Medium::Sampler own(actual);
    CHECK(own.sigmaS(centre).x() == Approx(4.0));
    CHECK(own.sigmaT(centre).x() == Approx(5.0));
    CHECK(actual.phaseG() == 0.75);
    // A back-scattering phase keeps the similarity relation: σs' = (1 − g)σs = 5.6, isotropic.
    m.phaseG = -0.4;
    const vxf::Medium back(set, m);
    vxf::Medium::Sampler backSampler(back);
    CHECK(backSampler.sigmaS(centre).x() == Approx(5.6));
    CHECK(back.material().phaseG == 0.0);
    m.phaseG = 0.75;

    // Per-voxel sigma_s grids are scaled alike; the set's own grid is left as it is.
    auto sigmaS = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    sigmaS->setName("sigma_s");
    sigmaS->setTransform(set.transformPtr());
    sigmaS->tree().topologyUnion(set.get<openvdb::FloatGrid>("density")->tree());
    for (auto it = sigmaS->beginValueOn(); it; ++it) it.setValue(openvdb::Vec3f(8.0f));
    set.put(sigmaS);
    const vxf::Medium gridded(set, m);
    vxf::Medium::Sampler griddedTransport(gridded);
    CHECK(griddedTransport.sigmaS(centre).x() == Approx(8.0 * 0.68359375));
    CHECK(griddedTransport.sigmaT(centre).x() == Approx(1.0 + 8.0 * 0.68359375));
    const vxf::Medium griddedIsotropic = gridded.isotropic(), griddedActual = gridded.actual();
    vxf::Medium::Sampler griddedReduced(griddedIsotropic);
    CHECK(griddedReduced.sigmaS(centre).x() == Approx(2.0));
    vxf::Medium::Sampler griddedOwn(griddedActual);
    CHECK(griddedOwn.sigmaS(centre).x() == Approx(8.0));
    CHECK(sigmaS->tree().getValue(openvdb::Coord(0)).x() == 8.0f);

    // g = 0: all three are the material's, bit for bit.
    const vxf::Medium plain(set, vxf::test::greyMaterial(1.0, 4.0));
    vxf::Medium::Sampler a(plain);
    const vxf::Medium plainActual = plain.actual(), plainIsotropic = plain.isotropic();
    vxf::Medium::Sampler b(plainActual), c(plainIsotropic);
    const openvdb::Vec3d p(0.3, -1.2, 2.7);
    CHECK(a.sigmaT(p) == b.sigmaT(p));
    CHECK(a.sigmaS(p) == b.sigmaS(p));
    CHECK(a.sigmaT(p) == c.sigmaT(p));
    CHECK(a.sigmaS(p) == c.sigmaS(p));
}

TEST_CASE("the rest of the phase: delta-M's moments, and its angular factor's Legendre moments chi_l k^l", "[phase]")
{
    // g = 0.6: f = g⁴ kept in the beam, the rest's χ_l = (g^l − f)/(1 − f) for l = 1…3.
    const double g = 0.6, f = std::pow(g, 4.0);
    const vxf::PhaseScaling scaling = vxf::transportScaling(g);
    CHECK(scaling.forward == Approx(f));
    for (int l = 1; l <= 3; ++l) CHECK(scaling.rest[l - 1] == Approx((std::pow(g, l) - f) / (1.0 - f)));
    CHECK(scaling.restG() == Approx((g - f) / (1.0 - f))); // the mean cosine the diffusion correction takes
    CHECK(vxf::transportScaling(-0.3).forward == -0.3); // a backward phase: the similarity relation
    CHECK(vxf::transportScaling(-0.3).restG() == 0.0);
    // Light of mean direction a = k·â scattered by the rest: RestPhase(a, ω) depends on μ = â·ω
    // alone, and its Legendre moments ½∫ R·P_l dμ are χ_l·k^l (a Henyey-Greenstein lobe of
    // parameter k scattered by the rest): 1, χ1·k, χ2·k², χ3·k³, and 0 beyond (no clamp at g 0.6).
    const vxf::RestPhase rest(scaling);
    const openvdb::Vec3f axis = openvdb::Vec3f(1.0f, 2.0f, -2.0f).unit();
    for (const double k : {0.0, 0.35, 0.8, 1.0}) {
        double moment[5] = {0, 0, 0, 0, 0};
        const int steps = 20000;
        for (int i = 0; i < steps; ++i) {
            const double mu = -1.0 + (i + 0.5) * 2.0 / steps;
            // ω at angle acos(μ) from the axis, in any plane through it.
            const openvdb::Vec3f side = axis.cross(openvdb::Vec3f(0.0f, 0.0f, 1.0f)).unit();
            const openvdb::Vec3f omega = axis * float(mu) + side * float(std::sqrt(1.0 - mu * mu));
            const double r = rest(axis * float(k), omega);
            const double p[5] = {
                1.0, mu, 0.5 * (3 * mu * mu - 1), 0.5 * (5 * mu * mu * mu - 3 * mu), (35 * std::pow(mu, 4) - 30 * mu * mu + 3) / 8};
            for (int l = 0; l < 5; ++l) moment[l] += 0.5 * r * p[l] * 2.0 / steps;
        }
        INFO("k " << k);
        CHECK(moment[0] == Approx(1.0).epsilon(1e-5));
        for (int l = 1; l <= 3; ++l) CHECK(moment[l] == Approx(scaling.rest[l - 1] * std::pow(k, l)).margin(1e-5));
        CHECK(std::abs(moment[4]) < 1e-5);
    }
}

TEST_CASE("the rest of the phase on the sweep's directions: mean 1 and first moment chi1 a, with their correction", "[phase][sweep]")
{
    // On the sweep's N directions (opposite pairs, isotropic second moments) the factor's mean
    // is 1 and, less β·ω_i (QuadratureCorrection, a cubic form in a per direction), its first
    // moment Σ R·ω_i/N is χ1·a as on the sphere; without β the cubic term's aliasing puts it off.
    // (g 0.6: R nowhere clamped.)
    const vxf::RestPhase rest(vxf::transportScaling(0.6));
    for (const int count : {16, 32}) {
        const std::vector<openvdb::Vec3d> directions = vxf::sweepDirections(count, 7);
        std::vector<openvdb::Vec3d> firsts;
        for (std::size_t i = 0; i < directions.size(); i += 2) firsts.push_back(directions[i]);
        const openvdb::Vec3f a = openvdb::Vec3f(0.3f, -0.5f, 0.6f);
        double mean = 0.0;
        openvdb::Vec3d moment(0.0), plain(0.0);
        for (const openvdb::Vec3d& w : directions) {
            const openvdb::Vec3f omega(w);
            const float betaDotOmega = vxf::QuadratureCorrection(rest, w, firsts).betaDotOmega(a);
            mean += rest(a, omega, betaDotOmega) / double(count);
            moment += w * (rest(a, omega, betaDotOmega) / double(count));
            plain += w * (rest(a, omega) / double(count));
        }
        INFO(count << " directions");
        CHECK(mean == Approx(1.0).epsilon(1e-5));
        for (int axis = 0; axis < 3; ++axis) CHECK(moment[axis] == Approx(rest.chi[0] * a[axis]).margin(1e-5));
        CHECK((plain - openvdb::Vec3d(a) * double(rest.chi[0])).length() > 1e-3);
    }
}

TEST_CASE("the rest of the phase over a block, by component, is the per-voxel factor to the bit", "[phase][sweep]")
{
    // restFactors is what a sweep with a phase reads (vectorized); the solve's results must not
    // move with it. Mean directions over the unit ball, some clamped (g 0.95: a strong cubic term).
    for (const double g : {0.6, 0.95}) {
        const vxf::RestPhase rest(vxf::transportScaling(g));
        const std::vector<openvdb::Vec3d> directions = vxf::sweepDirections(16, 3);
        std::vector<openvdb::Vec3d> firsts;
        for (std::size_t i = 0; i < directions.size(); i += 2) firsts.push_back(directions[i]);
        constexpr int n = 203;
        std::vector<float> x(n), y(n), z(n), out(n);
        for (int i = 0; i < n; ++i) {
            const double t = i * 0.37, r = double(i % 11) / 10.0;
            x[i] = float(r * std::sin(t) * std::cos(2.3 * t));
            y[i] = float(r * std::sin(t) * std::sin(2.3 * t));
            z[i] = float(r * std::cos(t));
        }
        int clamped = 0;
        for (const openvdb::Vec3d& w : directions) {
            const openvdb::Vec3f omega(w);
            const vxf::QuadratureCorrection beta(rest, w, firsts);
            for (const vxf::QuadratureCorrection* b : {static_cast<const vxf::QuadratureCorrection*>(nullptr), &beta}) {
                vxf::restFactors(rest, omega, b, x.data(), y.data(), z.data(), n, out.data());
                for (int i = 0; i < n; ++i) {
                    const openvdb::Vec3f a(x[i], y[i], z[i]);
                    const float one = b ? rest(a, omega, b->betaDotOmega(a)) : rest(a, omega);
                    INFO("g " << g << ", voxel " << i);
                    REQUIRE(out[i] == one);
                    clamped += one == 0.0f;
                }
            }
        }
        if (g > 0.9) CHECK(clamped > 0);
    }
}

TEST_CASE("the material's phase is recorded in the voxel set, and isotropic sets' records are as before", "[phase]")
{
    vxf::Material m = vxf::test::greyMaterial(1.0, 4.0);
    vxf::VoxelSet set = vxf::test::uniformSphere(m, 1.0, 4);
    vxf::recordMaterial(set, m);
    const std::string isotropic = set.metadata().metaValue<std::string>(vxf::kMaterialMetaKey);
    CHECK(isotropic.find("phase") == std::string::npos);
    m.phaseG = -0.4;
    vxf::recordMaterial(set, m);
    CHECK(vxf::recordedMaterial(set).phaseG == -0.4);
    // A file claiming a phase no medium can have is refused, not solved with σs' < 0.
    set.metadata().insertMeta(
        vxf::kMaterialMetaKey, openvdb::StringMetadata(R"({"sigma_a": [1, 1, 1], "sigma_s": [4, 4, 4], "phase_g": 5})"));
    CHECK_THROWS_WITH(vxf::recordedMaterial(set), "malformed 'vxf:material' metadata: phase_g 5 is outside [-0.95, 0.95]");
}
