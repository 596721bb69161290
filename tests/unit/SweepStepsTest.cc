// The sweeps' step arithmetic (src/transport/lattice/SweepSteps.h, private to transport/): the weights of
// a step's linear source against their integrals, and the varying step against the uniform one.
#include "transport/lattice/SweepSteps.h"

#include <catch2/catch.hpp>

#include <cmath>

namespace {

/// in = ∫₀¹ v e^{−τv} dv and own = ∫₀¹ (1−v) e^{−τv} dv in long double: by the midpoint rule
/// where τ is small (an answer independent of the series), their closed forms where it is not
/// (no cancellation left there at long double's precision).
void integrated(long double tau, long double& in, long double& own)
{
    if (tau > 0.5L) {
        const long double e = std::exp(-tau);
        in = (1.0L - e - tau * e) / (tau * tau);
        own = (tau - 1.0L + e) / (tau * tau);
        return;
    }
    constexpr int kSteps = 20000;
    in = own = 0.0L;
    for (int i = 0; i < kSteps; ++i) {
        const long double v = (i + 0.5L) / kSteps, e = std::exp(-tau * v) / kSteps;
        in += v * e;
        own += (1.0L - v) * e;
    }
}

} // namespace

TEST_CASE("a step's weights are the integrals of its linear source, on both sides of the series' switch", "[transport][sweep]")
{
    for (const double tau : {0.0, 1e-9, 1e-4, 0.01, 0.1, 0.2, 0.2499999, 0.25, 0.2500001, 0.5, 2.0, 30.0}) {
        const vxf::detail::StepWeights w = vxf::detail::stepWeights(tau);
        long double in = 0, own = 0;
        integrated(tau, in, own);
        INFO("tau " << tau);
        CHECK(w.transmittance == std::exp(-tau));
        CHECK(w.in == Approx(double(in)).epsilon(1e-8));
        CHECK(w.own == Approx(double(own)).epsilon(1e-8));
    }
    // No step: J integrated as it is, half from each end.
    CHECK(vxf::detail::stepWeights(0.0).in == 0.5);
    CHECK(vxf::detail::stepWeights(0.0).own == 0.5);
    // Optically thick: ψ → J/σt, all of it the end's.
    const vxf::detail::StepWeights thick = vxf::detail::stepWeights(1e6);
    CHECK(thick.in == Approx(0.0).margin(1e-11));
    CHECK(thick.own * 1e6 == Approx(1.0).epsilon(1e-5));
}

TEST_CASE(
    "a varying step tends to the uniform step as its ends' sigma_t meet, and keeps its weights for the next channel", "[transport][sweep]")
{
    // J following σt (scattered light, J = c·σt): the source function S = c is constant, so the
    // step from ψ_in gives ψ_in e^{−τ} + c(1 − e^{−τ}) exactly, σt varying or not.
    const double h = 0.7, c = 2.5, psiIn = 1.25;
    vxf::detail::VaryingWeights kept;
    for (const double sa : {0.3, 1.0, 4.0}) {
        for (const double sb : {0.5, 2.0}) {
            const vxf::detail::VaryingWeights& w = vxf::detail::varyingWeights(sa, sb, h, kept);
            const double tau = 0.5 * (sa + sb) * h;
            INFO("sigma " << sa << " to " << sb);
            CHECK(
                vxf::detail::varyingStep(psiIn, c * sa, c * sb, w) == Approx(psiIn * std::exp(-tau) + c * -std::expm1(-tau)).epsilon(1e-9));
            // The same weights for the next channel: another J, the same σt.
            CHECK(&vxf::detail::varyingWeights(sa, sb, h, kept) == &kept);
            CHECK(kept.sa == sa);
            CHECK(vxf::detail::varyingStep(0.0, 2 * c * sa, 2 * c * sb, kept) == Approx(2 * c * -std::expm1(-tau)).epsilon(1e-9));
        }
    }
    // σt nearly the same at both ends: the uniform step's answer.
    vxf::detail::UniformWeights uniform;
    const float expected = vxf::detail::uniformStep(float(psiIn), 1.0f, 3.0f, 1.5, h, uniform);
    CHECK(
        vxf::detail::varyingStep(psiIn, 1.0, 3.0, vxf::detail::varyingWeights(1.5, 1.5 + 1e-9, h, kept)) == Approx(expected).epsilon(1e-6));
    // An end without medium takes the other's source function: no division by 0.
    const double open = vxf::detail::varyingStep(psiIn, 0.0, c * 2.0, vxf::detail::varyingWeights(0.0, 2.0, h, kept));
    CHECK(std::isfinite(open));
    CHECK(open == Approx(psiIn * std::exp(-h) + c * -std::expm1(-h)).epsilon(1e-9));
}
