#include <vxf/light/DirectLight.h>

#include <vxf/core/Hash.h>
#include <vxf/core/SphericalFibonacci.h>
#include <vxf/io/VoxelSetFile.h>

#include <openvdb/tools/Morphology.h>
#include <openvdb/tree/LeafManager.h>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>

namespace vxf {

namespace {

double falloff(Light::Falloff f, double r)
{
    switch (f) {
    case Light::Falloff::InverseSquare: return 1.0 / (r * r);
    case Light::Falloff::Linear: return 1.0 / r;
    case Light::Falloff::None: return 1.0;
    }
    return 0.0;
}

/// Orthonormal tangents of unit normal @a n.
void frame(const openvdb::Vec3d& n, openvdb::Vec3d& u, openvdb::Vec3d& v)
{
    const openvdb::Vec3d helper = std::abs(n.x()) < 0.9 ? openvdb::Vec3d(1, 0, 0) : openvdb::Vec3d(0, 1, 0);
    u = n.cross(helper).unit();
    v = n.cross(u);
}

/// Fluence from an emitting point @a q (world) with radiant intensity @a intensity toward x.
openvdb::Vec3d fromPoint(const openvdb::Vec3d& q, const openvdb::Vec3d& intensity, Light::Falloff f,
    Medium::Sampler& sampler, const Medium& medium, const openvdb::Vec3d& xIjk, const openvdb::Vec3d& xWorld,
    const MarchOptions& options)
{
    // Never divide by zero: distances below half a voxel are taken as half a voxel.
    const double r = std::max((q - xWorld).length(), 0.5 * medium.voxelSize());
    const openvdb::Vec3d t = transmittance(sampler, medium, xIjk, medium.transform().worldToIndex(q), options);
    return intensity * falloff(f, r) * t;
}

} // namespace

openvdb::Vec3d lightFluence(const Light& light, Medium::Sampler& sampler, const Medium& medium,
    const openvdb::Coord& voxel, const MarchOptions& options)
{
    const openvdb::Vec3d xIjk = voxel.asVec3d();
    const openvdb::Vec3d xWorld = medium.transform().indexToWorld(xIjk);
    const openvdb::Vec3d power = light.power();
    switch (light.type) {
    case Light::Type::Point:
        return fromPoint(light.position, power, light.falloff, sampler, medium, xIjk, xWorld, options);
    case Light::Type::Spot: {
        // Cone factor: 1 within (half angle − softness), smoothstep to 0 at the half angle.
        const openvdb::Vec3d toX = xWorld - light.position;
        const double length = toX.length();
        const double cosAngle = length > 0.0 ? light.direction.dot(toX) / length : 1.0;
        const double angle = std::acos(std::clamp(cosAngle, -1.0, 1.0)) * 180.0 / M_PI;
        const double outer = 0.5 * light.coneAngleDegrees, inner = outer - light.coneSoftnessDegrees;
        double cone = angle <= inner ? 1.0 : angle >= outer ? 0.0 : (outer - angle) / (outer - inner);
        cone = cone * cone * (3.0 - 2.0 * cone);
        if (cone <= 0.0) return openvdb::Vec3d(0.0);
        return cone * fromPoint(light.position, power, light.falloff, sampler, medium, xIjk, xWorld, options);
    }
    case Light::Type::Directional: {
        const openvdb::Vec3d towardLight = medium.transform().worldToIndex(xWorld - light.direction) - xIjk;
        return power * transmittanceToBoundary(sampler, medium, xIjk, towardLight, options);
    }
    case Light::Type::Environment: {
        if (!light.file.empty()) {
            throw UsageError(fmt::format("light '{}': environment maps are not supported yet; give a constant colour",
                light.name));
        }
        // φ = ∫ L T dω ≈ Σ (4π/N) L T(ω_i).
        static thread_local std::vector<openvdb::Vec3d> directions;
        if (int(directions.size()) != light.samples) directions = sphericalFibonacci(light.samples);
        openvdb::Vec3d sum(0.0);
        for (const auto& w : directions) {
            sum += transmittanceToBoundary(sampler, medium, xIjk, medium.transform().worldToIndex(xWorld + w) - xIjk, options);
        }
        return power * sum * (4.0 * M_PI / double(directions.size()));
    }
    case Light::Type::Area: {
        // Lambertian emitter of radiance L = color·intensity: dφ = L cosθ_l dA f(r) T.
        const int n = light.samples;
        openvdb::Vec3d sum(0.0);
        if (light.shape == Light::Shape::Sphere) {
            const double area = 4.0 * M_PI * light.radius * light.radius;
            for (int i = 0; i < n; ++i) {
                // Stratified in z (equal-area bands) and jittered in angle, per voxel.
                const double z = 1.0 - 2.0 * (i + unitHash(coordKey(voxel), std::uint64_t(i), 1)) / n;
                const double phi = 2.0 * M_PI * unitHash(coordKey(voxel), std::uint64_t(i), 2);
                const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
                const openvdb::Vec3d normal(s * std::cos(phi), s * std::sin(phi), z);
                const openvdb::Vec3d q = light.position + light.radius * normal;
                const openvdb::Vec3d toX = xWorld - q;
                const double cosTheta = toX.length() > 0.0 ? normal.dot(toX) / toX.length() : 0.0;
                if (cosTheta <= 0.0) continue;
                sum += fromPoint(q, power * cosTheta * (area / n), light.falloff, sampler, medium, xIjk, xWorld, options);
            }
            return sum;
        }
        openvdb::Vec3d u, v;
        frame(light.direction, u, v);
        const int side = std::max(1, int(std::lround(std::sqrt(double(n)))));
        const int count = side * side;
        const double area = light.shape == Light::Shape::Disk ? M_PI * light.radius * light.radius : light.width * light.height;
        for (int i = 0; i < count; ++i) {
            const double a = (i % side + unitHash(coordKey(voxel), std::uint64_t(i), 3)) / side;
            const double b = (i / side + unitHash(coordKey(voxel), std::uint64_t(i), 4)) / side;
            openvdb::Vec3d q;
            if (light.shape == Light::Shape::Disk) {
                const double r = light.radius * std::sqrt(a), phi = 2.0 * M_PI * b; // area-preserving
                q = light.position + r * (std::cos(phi) * u + std::sin(phi) * v);
            } else {
                q = light.position + (a - 0.5) * light.width * u + (b - 0.5) * light.height * v;
            }
            const openvdb::Vec3d toX = xWorld - q;
            const double cosTheta = toX.length() > 0.0 ? light.direction.dot(toX) / toX.length() : 0.0;
            if (cosTheta <= 0.0) continue; // one-sided emitter
            sum += fromPoint(q, power * cosTheta * (area / count), light.falloff, sampler, medium, xIjk, xWorld, options);
        }
        return sum;
    }
    case Light::Type::Volume: return openvdb::Vec3d(0.0);
    }
    return openvdb::Vec3d(0.0);
}

DirectLightReport computeDirectLight(VoxelSet& set, const Medium& medium, const std::vector<Light>& lights,
    const DirectLightOptions& options, Interrupter* interrupter)
{
    InterruptStep step(interrupter, "lighting");
    DirectLightReport report;
    std::vector<const Light*> active;
    std::vector<int> activeIndex; // per report entry: its index in `active`, or -1
    std::vector<openvdb::GridBase::ConstPtr> emission; // volume lights, sampled in world space
    for (const Light& light : lights) {
        DirectLightReport::PerLight entry;
        entry.name = light.name;
        if (light.power() == openvdb::Vec3d(0.0)) {
            entry.skipped = true;
            entry.why = "zero colour or intensity";
        } else if (light.type == Light::Type::Volume) {
            const VoxelSet source = readVoxelSet(light.file);
            auto grid = source.find(light.grid);
            if (!grid) throw Error(fmt::format("light '{}': no grid '{}' in {}", light.name, light.grid, light.file));
            if (!grid->isType<openvdb::FloatGrid>() && !grid->isType<openvdb::Vec3SGrid>()) {
                throw Error(fmt::format("light '{}': grid '{}' must be float or vec3s", light.name, light.grid));
            }
            emission.push_back(grid);
            entry.why = "volume light: its emission adds to scatter_source";
        } else {
            if (light.type == Light::Type::Environment && !light.file.empty()) {
                throw UsageError(fmt::format("light '{}': environment maps are not supported yet; give a constant colour", light.name));
            }
            activeIndex.push_back(int(active.size()));
            active.push_back(&light);
            report.lights.push_back(entry);
            continue;
        }
        activeIndex.push_back(-1);
        report.lights.push_back(entry);
    }

    const openvdb::FloatGrid& density = medium.density();
    auto direct = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    direct->setTransform(density.transformPtr()->copy());
    direct->tree().topologyUnion(density.tree());
    direct->setName("direct");
    auto source = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    source->setTransform(density.transformPtr()->copy());
    source->tree().topologyUnion(density.tree());
    source->setName("scatter_source");
    if (!options.coarseTiles) {
        direct->tree().voxelizeActiveTiles();
        source->tree().voxelizeActiveTiles();
    }
    // One voxel beyond the medium (26-neighbourhood): trilinear lookups of φ near the surface
    // then blend real values, not the background 0 (which would dim the outermost half voxel).
    for (auto* grid : {direct.get(), source.get()}) {
        openvdb::tools::dilateActiveValues(grid->tree(), 1, openvdb::tools::NN_FACE_EDGE_VERTEX,
            options.coarseTiles ? openvdb::tools::PRESERVE_TILES : openvdb::tools::IGNORE_TILES);
    }

    // Work items: leaf voxels (per leaf) and active tiles (value at the tile centre).
    openvdb::tree::LeafManager<openvdb::Vec3STree> leaves(direct->tree());
    openvdb::tree::LeafManager<openvdb::Vec3STree> sourceLeaves(source->tree());
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
    std::vector<openvdb::Vec3f> tileDirect(tiles.size()), tileSource(tiles.size());
    std::atomic<std::size_t> done{0};
    std::atomic<bool> cancelled{false};

    const auto evaluate = [&](Medium::Sampler& sampler, const openvdb::Coord& ijk, const openvdb::Vec3d& pointIjk,
                              std::vector<openvdb::Vec3d>& sums, openvdb::Vec3f& outDirect, openvdb::Vec3f& outSource,
                              double weight) {
        openvdb::Vec3d phi(0.0);
        for (std::size_t l = 0; l < active.size(); ++l) {
            const openvdb::Vec3d f = lightFluence(*active[l], sampler, medium, ijk, options.march);
            phi += f;
            sums[l] += f * weight;
        }
        // J0 = σs φ0 / 4π (+ emission of volume lights, radiance per unit length).
        openvdb::Vec3d j = sampler.sigmaS(pointIjk) * phi / (4.0 * M_PI);
        const openvdb::Vec3d world = medium.transform().indexToWorld(pointIjk);
        for (const auto& e : emission) {
            if (auto f = openvdb::gridConstPtrCast<openvdb::FloatGrid>(e)) {
                j += openvdb::Vec3d(openvdb::tools::BoxSampler::sample(f->tree(), f->transform().worldToIndex(world)));
            } else if (auto v = openvdb::gridConstPtrCast<openvdb::Vec3SGrid>(e)) {
                j += openvdb::Vec3d(openvdb::tools::BoxSampler::sample(v->tree(), v->transform().worldToIndex(world)));
            }
        }
        for (int c = 0; c < 3; ++c) {
            if (!std::isfinite(phi[c])) phi[c] = 0.0; // cannot happen by construction; never let NaN in
            if (!std::isfinite(j[c])) j[c] = 0.0;
        }
        outDirect = openvdb::Vec3f(phi);
        outSource = openvdb::Vec3f(j);
    };

    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, total, 1), [&](const tbb::blocked_range<std::size_t>& range) {
        Medium::Sampler sampler(medium);
        for (std::size_t item = range.begin(); item != range.end(); ++item) {
            if (cancelled) return;
            auto& sums = perLight[item];
            sums.assign(active.size(), openvdb::Vec3d(0.0));
            if (item < leafCount) {
                auto& leaf = leaves.leaf(item);
                auto& sourceLeaf = sourceLeaves.leaf(item);
                for (auto it = leaf.beginValueOn(); it; ++it) {
                    openvdb::Vec3f d, s;
                    evaluate(sampler, it.getCoord(), it.getCoord().asVec3d(), sums, d, s, 1.0);
                    it.setValue(d);
                    sourceLeaf.setValueOnly(it.pos(), s);
                }
            } else {
                const std::size_t t = item - leafCount;
                const openvdb::CoordBBox& box = tiles[t];
                const openvdb::Coord centre = box.min() + openvdb::Coord(box.dim().x() / 2);
                evaluate(sampler, centre, centre.asVec3d(), sums, tileDirect[t], tileSource[t], double(box.volume()));
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
    }

    // Per-light energy sums in a fixed order (deterministic for any thread count).
    for (std::size_t e = 0; e < report.lights.size(); ++e) {
        if (activeIndex[e] < 0) continue;
        for (const auto& sums : perLight) report.lights[e].fluenceSum += sums[std::size_t(activeIndex[e])];
    }
    set.put(direct);
    set.put(source);
    return report;
}

} // namespace vxf
