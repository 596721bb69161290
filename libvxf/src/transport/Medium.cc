#include <vxf/transport/Medium.h>

#include <vxf/core/GridRoles.h>
#include <vxf/transport/Phase.h>
#include <vxf/transport/UniformBricks.h>

#include <vxf/core/RayScene.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/ValueTransformer.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace vxf {

namespace {

/// The level set the marches clip to: @a surface where it resolves the medium, and "whole voxel
/// inside" (φ ≤ −dx) within one voxel of where it does not. A boundary voxel (volume fraction
/// in (0, 1)) is resolved when a whole voxel (φ ≤ −½dx) lies among its 26 neighbours, as on
/// any surface at least about a voxel from the medial axis (the neighbour towards the inside
/// is a voxel deeper). Thinner features — sheets, fibres and rims of a voxel or less — have
/// no whole voxel, and the trilinear zero crossing between centres loses them (a sub-voxel
/// sheet vanishes); there the voxels' volume fractions alone carry the medium (soft edge: no
/// clipping, interior scale 1). The dilation by one voxel covers every cell that reads an
/// unresolved voxel. Returns @a surface itself when every boundary voxel is resolved.
openvdb::FloatGrid::ConstPtr marchSurface(const openvdb::FloatGrid::ConstPtr& surface)
{
    const float dx = float(surface->voxelSize()[0]);
    openvdb::tree::LeafManager<const openvdb::FloatTree> leaves(surface->tree());
    tbb::enumerable_thread_specific<std::vector<openvdb::Coord>> found;
    leaves.foreach ([&](const openvdb::FloatTree::LeafNodeType& leaf, size_t) {
        openvdb::FloatGrid::ConstAccessor phi = surface->getConstAccessor();
        for (auto it = leaf.cbeginValueOn(); it; ++it) {
            const float v = *it;
            if (v <= -0.5f * dx || v >= 0.5f * dx) continue; // whole or empty voxel
            const openvdb::Coord c = it.getCoord();
            bool resolved = false;
            for (int n = 0; n < 27 && !resolved; ++n) {
                resolved = phi.getValue(c.offsetBy(n % 3 - 1, (n / 3) % 3 - 1, n / 9 - 1)) <= -0.5f * dx;
            }
            if (!resolved) found.local().push_back(c);
        }
    });
    openvdb::BoolTree unresolved(false);
    for (const auto& coords : found) {
        for (const openvdb::Coord& c : coords) unresolved.setValueOn(c, true);
    }
    if (unresolved.empty()) return surface;
    openvdb::tools::dilateActiveValues(unresolved, 1, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::IGNORE_TILES);
    openvdb::FloatGrid::Ptr march = surface->deepCopy();
    openvdb::FloatGrid::Accessor out = march->getAccessor();
    for (auto it = unresolved.cbeginValueOn(); it; ++it) {
        out.setValue(it.getCoord(), std::min(out.getValue(it.getCoord()), -dx));
    }
    return march;
}

} // namespace

const std::set<std::string>& Medium::gridsRead()
{
    static const std::set<std::string> names = {grids::kDensity, grids::kSigmaA, grids::kSigmaS, grids::kSurface};
    return names;
}

Medium::Medium(const VoxelSet& set, const Material& material, Lookups lookups)
    : mDensity(set.get<openvdb::FloatGrid>(grids::kDensity))
    , mMaterial(material)
    , mActualMaterial(material)
{
    // Errors name the file the set came from, when it came from one.
    const std::string file = set.path().empty() ? "" : set.path() + ": ";
    for (const char* name : {grids::kSigmaA, grids::kSigmaS}) {
        if (auto grid = set.find(name)) {
            auto typed = openvdb::gridConstPtrCast<openvdb::Vec3SGrid>(grid);
            if (!typed) throw Error(fmt::format("{}grid '{}' must hold vec3s values, not {}", file, name, grid->valueType()));
            if (typed->transform() != mDensity->transform()) {
                throw Error(fmt::format("{}grid '{}' does not share the transform of 'density'", file, name));
            }
            (std::string(name) == grids::kSigmaA ? mSigmaA : mSigmaS) = typed;
        }
    }
    if (auto grid = set.find(grids::kSurface)) {
        auto typed = openvdb::gridConstPtrCast<openvdb::FloatGrid>(grid);
        if (typed && typed->getGridClass() == openvdb::GRID_LEVEL_SET) {
            if (typed->transform() != mDensity->transform()) {
                throw Error(file +
                    "grid 'surface' does not share the transform of 'density'; resample it or remove it "
                    "(then the medium ends where the density does)");
            }
            mSurface = marchSurface(typed);
        }
    }
    mActualSigmaS = mSigmaS;
    mBounds = mDensity->evalActiveVoxelBoundingBox();
    const bool dense = lookups == Lookups::Dense;
    if (dense && mSigmaA) mSigmaADense = DenseCopy<openvdb::Vec3SGrid>::create(*mSigmaA, kDenseCopyMargin, kDenseCopyBytes);
    if (dense && mSigmaS)
        mSigmaSDense = mActualSigmaSDense = DenseCopy<openvdb::Vec3SGrid>::create(*mSigmaS, kDenseCopyMargin, kDenseCopyBytes);
    if (material.phaseG != 0.0) {
        // The transport's medium: σs* = (1 − f)·σs, σa as it is, the rest's g* (Phase.h).
        const PhaseScaling scaling = transportScaling(material.phaseG);
        scaleScattering(1.0 - scaling.forward, scaling.restG());
    }
    if (!dense) return;
    // Trilinear lookups reach a voxel beyond the active voxels (marchBounds).
    mDensityDense = DenseCopy<openvdb::FloatGrid>::create(*mDensity, kDenseCopyMargin, kDenseCopyBytes);
    if (mSurface) mSurfaceDense = DenseCopy<openvdb::FloatGrid>::create(*mSurface, kDenseCopyMargin, kDenseCopyBytes);
    if (!mSigmaA && !mSigmaS && mDensityDense) {
        mUniform = std::make_shared<const UniformBricks>(mDensityDense.get(), mBounds, mSurfaceDense.get(), voxelSize(), bool(mSurface));
    } else if (!mSigmaA && !mSigmaS && !mSurface && !mBounds.empty()) {
        mUniform = std::make_shared<const UniformBricks>(mDensity); // too large for a dense copy: the tree's regions
    }
}

void Medium::scaleScattering(double factor, double restG)
{
    mMaterial = mActualMaterial;
    mMaterial.sigmaS *= factor;
    mMaterial.phaseG = restG;
    mSigmaS = mActualSigmaS;
    mSigmaSDense = mActualSigmaSDense;
    if (mSigmaS) {
        openvdb::Vec3SGrid::Ptr scaled = mSigmaS->deepCopy();
        openvdb::tools::foreach (scaled->beginValueAll(),
            [factor](const openvdb::Vec3SGrid::ValueAllIter& it) { it.setValue(openvdb::Vec3f(openvdb::Vec3d(*it) * factor)); });
        mSigmaS = scaled;
        if (mSigmaSDense) mSigmaSDense = DenseCopy<openvdb::Vec3SGrid>::create(*mSigmaS, kDenseCopyMargin, kDenseCopyBytes);
    }
}

Medium Medium::actual() const
{
    Medium m(*this);
    m.mMaterial = mActualMaterial;
    m.mSigmaS = mActualSigmaS;
    m.mSigmaSDense = mActualSigmaSDense;
    return m;
}

Medium Medium::isotropic() const
{
    Medium m(*this);
    if (mActualMaterial.phaseG != 0.0) m.scaleScattering(reducedScatteringFactor(mActualMaterial.phaseG), 0.0);
    return m;
}

Medium::Sampler::Sampler(const Medium& medium)
    : mMedium(medium)
    , mDensity(*medium.mDensity, medium.mDensityDense.get())
{
    if (medium.mSigmaA) mSigmaA.emplace(*medium.mSigmaA, medium.mSigmaADense.get());
    if (medium.mSigmaS) mSigmaS.emplace(*medium.mSigmaS, medium.mSigmaSDense.get());
    if (medium.mSurface) mSurface.emplace(*medium.mSurface, medium.mSurfaceDense.get());
}

double Medium::Sampler::signedDistance(const openvdb::Vec3d& ijk)
{
    if (!mSurface) return -1.0;
    const double linear = double(mSurface->sampleTrilinear(ijk)) / mMedium.voxelSize();
    if (std::abs(linear) > kQuadraticBand) return linear;
    const double quadratic = double(mSurface->sampleTriquadratic(ijk)) / mMedium.voxelSize();
    return std::abs(quadratic - linear) <= kQuadraticLimit ? quadratic : linear;
}

double Medium::Sampler::interiorScale(const openvdb::Vec3d& ijk, double distanceBound)
{
    // The eight voxels lie within √3/2 of ijk: below −½ (whole) when ijk is below −1.37.
    if (!mSurface || distanceBound < -1.5) return 1.0;
    const openvdb::Coord base = openvdb::Coord::floor(ijk);
    const openvdb::Vec3d f = ijk - base.asVec3d();
    const double dx = mMedium.voxelSize();
    float phi[2][2][2];
    mSurface->getBlock(base, phi);
    double fraction = 0.0;
    for (int corner = 0; corner < 8; ++corner) {
        const int i = corner & 1, j = (corner >> 1) & 1, k = (corner >> 2) & 1;
        const double w = (i ? f[0] : 1.0 - f[0]) * (j ? f[1] : 1.0 - f[1]) * (k ? f[2] : 1.0 - f[2]);
        fraction += w * std::clamp(0.5 - double(phi[i][j][k]) / dx, 0.0, 1.0);
    }
    return 1.0 / std::max(fraction, kMinFraction);
}

bool Medium::Sampler::surfaceNormal(const openvdb::Vec3d& ijk, openvdb::Vec3d& normal)
{
    if (!mSurface) return false;
    for (int axis = 0; axis < 3; ++axis) {
        openvdb::Vec3d e(0.0);
        e[axis] = 1.0;
        normal[axis] = 0.5 * (signedDistance(ijk + e) - signedDistance(ijk - e));
    }
    const double slope = normal.length();
    if (!(slope > 0.1)) return false;
    normal /= slope;
    return true;
}

namespace {

/// The nearest hit of @a meshes on p + s·d, s in (0, @a reach], met from the side @a backFace
/// says (true: leaving an outward-oriented mesh); its distance, or a negative number.
double nearestFacing(const RayScene& meshes, const openvdb::Vec3d& p, const openvdb::Vec3d& d, double reach, bool backFace)
{
    double from = 0.0;
    for (int k = 0; k < 8; ++k) {
        const auto hit = meshes.intersect(p, d, from, reach);
        if (!hit) return -1.0;
        if (hit->backFace == backFace) return hit->distance;
        from = std::nextafter(hit->distance, reach) + 1e-9 * reach; // past this triangle
    }
    return -1.0;
}

} // namespace

double Medium::Sampler::snapCrossing(
    const openvdb::Vec3d& origin, const openvdb::Vec3d& direction, double t, double lo, double hi, bool entering)
{
    if (!mBoundary) return t;
    const openvdb::Vec3d q = origin + direction * t;
    // Along a ray that meets the surface at cosine c a depth error e moves the crossing by e/c.
    openvdb::Vec3d normal;
    const double cosine = surfaceNormal(q, normal) ? std::abs(normal.dot(direction)) : 1.0;
    const double reach = std::min(kSnapWindow / std::max(cosine, 1e-3), kSnapReach);
    const openvdb::math::Transform& xform = mMedium.transform();
    const openvdb::Vec3d p = xform.indexToWorld(q);
    openvdb::Vec3d d = xform.indexToWorld(q + direction) - p;
    const double voxel = d.length(); // world length of one index unit along the ray
    if (!(voxel > 0.0)) return t;
    d /= voxel;
    // Only a crossing of the same kind (into the meshes or out of them): a short chord's entry
    // and exit lie within each other's reach. Backwards the ray meets the same triangles from
    // the other side. Searched beyond [lo, hi] too: a crossing the meshes place in a
    // neighbouring step is taken to the step's end, so this step's part outside them counts nothing.
    const double ahead = nearestFacing(*mBoundary, p, d, reach * voxel, !entering);
    const double behind = nearestFacing(*mBoundary, p, -d, reach * voxel, entering);
    if (ahead < 0.0 && behind < 0.0) return t;
    const double tAhead = ahead >= 0.0 ? t + ahead / voxel : std::numeric_limits<double>::infinity();
    const double tBehind = behind >= 0.0 ? t - behind / voxel : -std::numeric_limits<double>::infinity();
    return std::clamp(tAhead - t < t - tBehind ? tAhead : tBehind, lo, hi);
}

bool Medium::Sampler::boundaryHit(
    const openvdb::Vec3d& origin, const openvdb::Vec3d& direction, double lo, double hi, double& t, bool& entering) const
{
    if (!mBoundary || !mFindMissed || !(hi > lo)) return false;
    const openvdb::math::Transform& xform = mMedium.transform();
    const openvdb::Vec3d p = xform.indexToWorld(origin + direction * lo);
    openvdb::Vec3d d = xform.indexToWorld(origin + direction * (lo + 1.0)) - p;
    const double voxel = d.length();
    if (!(voxel > 0.0)) return false;
    const auto hit = mBoundary->intersect(p, d / voxel, 1e-6 * voxel, (hi - lo) * voxel); // not a crossing at lo itself
    if (!hit) return false;
    t = lo + hit->distance / voxel;
    entering = !hit->backFace;
    return true;
}

openvdb::Vec3d Medium::Sampler::mediumPoint(const openvdb::Coord& ijk)
{
    const openvdb::Vec3d c = ijk.asVec3d();
    if (!mSurface) return c;
    const double d = signedDistance(c);
    openvdb::Vec3d n;
    if (d <= 0.0 || d >= 0.5 || !surfaceNormal(c, n)) return c;
    return c - n * d;
}

bool Medium::Sampler::skinPoint(const openvdb::Coord& ijk, openvdb::Vec3d& point, openvdb::Vec3d& normal)
{
    if (!mSurface) return false;
    const openvdb::Vec3d c = ijk.asVec3d();
    const double d = signedDistance(c);
    if (!(std::abs(d) < 0.5) || !surfaceNormal(c, normal)) return false;
    point = c - normal * d;
    return true;
}

openvdb::Vec3d Medium::Sampler::sigmaS(const openvdb::Vec3d& ijk)
{
    if (mSigmaS) return openvdb::Vec3d(mSigmaS->sampleTrilinear(ijk));
    return mMedium.mMaterial.sigmaS * double(mDensity.sampleTrilinear(ijk));
}

openvdb::Vec3d Medium::Sampler::sigmaS(const openvdb::Coord& ijk)
{
    if (mSigmaS) return openvdb::Vec3d(mSigmaS->getValue(ijk));
    return mMedium.mMaterial.sigmaS * double(mDensity.getValue(ijk));
}

openvdb::Vec3d Medium::Sampler::sigmaT(const openvdb::Vec3d& ijk)
{
    if (!mSigmaA && !mSigmaS) {
        return mMedium.mMaterial.sigmaT() * double(mDensity.sampleTrilinear(ijk));
    }
    const double d = (mSigmaA && mSigmaS) ? 0.0 : double(mDensity.sampleTrilinear(ijk));
    const openvdb::Vec3d a = mSigmaA ? openvdb::Vec3d(mSigmaA->sampleTrilinear(ijk)) : mMedium.mMaterial.sigmaA * d;
    const openvdb::Vec3d s = mSigmaS ? openvdb::Vec3d(mSigmaS->sampleTrilinear(ijk)) : mMedium.mMaterial.sigmaS * d;
    return a + s;
}

void recordMaterial(VoxelSet& set, const Material& material)
{
    const auto rgb = [](const openvdb::Vec3d& v) { return nlohmann::json::array({v[0], v[1], v[2]}); };
    nlohmann::json j = {{"sigma_a", rgb(material.sigmaA)}, {"sigma_s", rgb(material.sigmaS)}};
    if (material.phaseG != 0.0) j["phase_g"] = material.phaseG; // isotropic sets' metadata as before
    set.metadata().insertMeta(kMaterialMetaKey, openvdb::StringMetadata(j.dump()));
}

Material recordedMaterial(const VoxelSet& set)
{
    auto meta = set.metadata().getMetadata<openvdb::StringMetadata>(kMaterialMetaKey);
    if (!meta)
        throw Error(
            fmt::format("the voxel set records no material ('{}' metadata); run vxf light first or give --scene", kMaterialMetaKey));
    const auto j = nlohmann::json::parse(meta->value(), nullptr, false);
    Material m;
    try {
        for (int c = 0; c < 3; ++c) {
            m.sigmaA[c] = j.at("sigma_a").at(std::size_t(c)).get<double>();
            m.sigmaS[c] = j.at("sigma_s").at(std::size_t(c)).get<double>();
        }
        m.phaseG = j.value("phase_g", 0.0);
    } catch (const nlohmann::json::exception&) {
        throw Error(fmt::format("malformed '{}' metadata: {}", kMaterialMetaKey, meta->value()));
    }
    if (!(std::abs(m.phaseG) <= kMaxPhaseG)) {
        throw Error(
            fmt::format("malformed '{}' metadata: phase_g {} is outside [-{}, {}]", kMaterialMetaKey, m.phaseG, kMaxPhaseG, kMaxPhaseG));
    }
    return m;
}

} // namespace vxf
