// An independent check of the scattering passes: a small Monte Carlo random walk, written
// here for the tests, solves the same transport problem and must agree with the converged
// `scatter` grid at interior points.
#include <vxf/light/DirectLight.h>
#include <vxf/scatter/Scatter.h>

#include <vxf/core/ProceduralMesh.h>
#include <vxf/voxelize/Voxelize.h>

#include <catch2/catch.hpp>

#include <random>

namespace {

/// φ_s(x) = Σ_{k≥1} of the collision series for isotropic scattering, by delta tracking
/// through σt(y) = σt·density(y) with the majorant σt, starting at x in a uniformly random
/// direction. Each real collision y scores albedo^k·φ0(y)·... with the estimator
/// φ(x) = φ0(x) + a·E[φ(y)], so the scatter part is E[Σ_{k≥1} a^k φ0(y_k)] (a = σs/σt).
double randomWalkScatter(const vxf::VoxelSet& set, const vxf::Material& m, const openvdb::Vec3d& xWorld, int walks, std::mt19937_64& rng)
{
    auto density = set.get<openvdb::FloatGrid>("density");
    auto direct = set.get<openvdb::Vec3SGrid>("direct");
    auto dAcc = density->getConstAccessor();
    auto pAcc = direct->getConstAccessor();
    const auto& xform = set.transform();
    const double sigmaT = m.sigmaT()[0], albedo = m.sigmaS[0] / sigmaT;
    const openvdb::CoordBBox box = density->evalActiveVoxelBoundingBox();
    const openvdb::BBoxd bounds(
        xform.indexToWorld(box.min().asVec3d() - openvdb::Vec3d(1.0)), xform.indexToWorld(box.max().asVec3d() + openvdb::Vec3d(1.0)));
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    double total = 0.0;
    for (int w = 0; w < walks; ++w) {
        openvdb::Vec3d y = xWorld;
        double weight = 1.0;
        while (true) {
            const double z = 1.0 - 2.0 * uniform(rng), phi = 2.0 * M_PI * uniform(rng);
            const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
            const openvdb::Vec3d dir(s * std::cos(phi), s * std::sin(phi), z);
            bool collided = false;
            while (true) { // delta tracking to the next real collision
                y += dir * (-std::log(1.0 - uniform(rng)) / sigmaT);
                if (!bounds.isInside(y)) break;
                const double rho = openvdb::tools::BoxSampler::sample(dAcc, xform.worldToIndex(y));
                if (uniform(rng) < rho) {
                    collided = true;
                    break;
                }
            }
            if (!collided) break;
            weight *= albedo;
            total += weight * double(openvdb::tools::BoxSampler::sample(pAcc, xform.worldToIndex(y))[0]);
            if (weight < 1e-4) break; // a^k below 1e-4 of the first term
        }
    }
    return total / walks;
}

} // namespace

TEST_CASE("converged scattering agrees with a Monte Carlo random walk", "[scatter][montecarlo]")
{
    vxf::VoxelizeOptions voxelize;
    voxelize.dim = 32;
    vxf::VoxelSet set = vxf::voxelize(vxf::makeSphere(openvdb::Vec3d(0.0), 1.0), voxelize);
    vxf::Material m;
    m.sigmaS = openvdb::Vec3d(2.4); // albedo 0.6, sigma_t = 4 per unit: a few mean free paths across
    m.sigmaA = openvdb::Vec3d(1.6);
    const vxf::Medium medium(set, m);
    vxf::Light sun;
    sun.type = vxf::Light::Type::Directional;
    sun.direction = openvdb::Vec3d(0, 0, -1);
    sun.intensity = 1.0;
    vxf::computeDirectLight(set, medium, {sun});
    vxf::ScatterOptions options;
    options.passes = 14; // 0.6^14 < 1e-3
    options.tolerance = 1e-4;
    options.pass.directions = 64;
    options.pass.step = 1.0;
    vxf::scatter(set, medium, options);
    auto scattered = set.get<openvdb::Vec3SGrid>("scatter");

    std::mt19937_64 rng(20121122);
    for (const openvdb::Vec3d x : {openvdb::Vec3d(0, 0, 0.5), openvdb::Vec3d(0, 0, 0), openvdb::Vec3d(0.3, -0.2, -0.4)}) {
        const double reference = randomWalkScatter(set, m, x, 20000, rng);
        const double vxfValue = openvdb::tools::BoxSampler::sample(scattered->tree(), set.transform().worldToIndex(x))[0];
        INFO("at " << x << ": vxf " << vxfValue << ", random walk " << reference);
        CHECK(vxfValue == Approx(reference).epsilon(0.05));
    }
}
