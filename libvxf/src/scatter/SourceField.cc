#include <vxf/scatter/SourceField.h>

#include <vxf/core/MaskedTrilinear.h>

#include <boost/math/special_functions/expint.hpp>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace vxf {

namespace {

/// E2(x) = ∫₁^∞ e^{−xt}/t² dt for x ≥ 0 (boost::math::expint), tabulated: linear between
/// entries 1/1024 apart it is within 4e-4 of the function (worst in the first interval, where
/// E2 − 1 ~ x·ln x), and below 1e-8 beyond 16.
class E2Table
{
public:
    static const E2Table& instance()
    {
        static const E2Table table;
        return table;
    }
    double operator()(double x) const
    {
        if (!(x > 0.0)) return 1.0;
        const double u = x * kPerUnit;
        if (u >= double(mValues.size() - 1)) return 0.0;
        const std::size_t i = std::size_t(u);
        return mValues[i] + (mValues[i + 1] - mValues[i]) * (u - double(i));
    }

private:
    E2Table()
        : mValues(16 * kPerUnit + 1)
    {
        mValues[0] = 1.0;
        for (std::size_t i = 1; i < mValues.size(); ++i) mValues[i] = boost::math::expint(2, double(i) / kPerUnit);
    }
    static constexpr int kPerUnit = 1024;
    std::vector<double> mValues;
};

/// 1 − E2(τz): how the light scattered from a uniform source rises beneath a surface it leaves
/// by, z voxels deep, τ = σt·dx (the layer's second shape; the first is z itself).
double rise(double tau, double z) { return 1.0 - E2Table::instance()(tau * std::max(z, 0.0)); }

/// J read beneath a surface point over the deep voxels around it, and what the layer's shapes
/// read there the same way: the trilinear weights' mean depth and mean rise per channel. The
/// fit then matches the lattice's own values, not J at the point: trilinear between the
/// centres of a rise as steep as 1 − E2 reads it up to 1.4% low a voxel and a half deep.
/// Voxels: how far a corner's distance from the surface may differ from its depth along the
/// normal and still be taken for it (readAnchor).
constexpr double kSameSheet = 0.25;

struct Anchor
{
    openvdb::Vec3d j{0.0}, depth{0.0}, rise{0.0};
};

template <typename Values, typename Use>
bool readAnchor(const Values& values, Medium::Sampler& sampler, const openvdb::Vec3d& surfacePoint, const openvdb::Vec3d& normal,
    double depth, const openvdb::Vec3d& tau, const Use& use, Anchor& anchor)
{
    const TrilinearCell cell(surfacePoint - normal * depth);
    double total = 0.0;
    for (int i = 0; i < 8; ++i) {
        if (cell.weight[i] <= 0.0) continue;
        const openvdb::Coord c = cell.corner(i);
        if (!use(c)) continue;
        // The corner's depth along the normal, (p − c)·n, or its own distance from the surface
        // where the two agree to kSameSheet: on a sphere of 10 voxels the plane's is 0.04
        // voxels off a voxel aside (a linear field came out 1.5% low half a voxel deep), but
        // where the nearest surface is another sheet (creases, thin parts) the distance is
        // not the depth beneath this point (taken always, the thick bunny's dim 64 rung went
        // from 3.98% to 6.1%, its shadowed third's multiple scattering to −12%).
        const double planar = (surfacePoint - c.asVec3d()).dot(normal), distance = -sampler.signedDistance(c.asVec3d());
        const double w = cell.weight[i], z = std::max(0.0, std::abs(distance - planar) < kSameSheet ? distance : planar);
        total += w;
        anchor.j += w * openvdb::Vec3d(values.getValue(c));
        for (int ch = 0; ch < 3; ++ch) {
            anchor.depth[ch] += w * z;
            anchor.rise[ch] += w * rise(tau[ch], z);
        }
    }
    if (total < 0.5) return false;
    anchor.j /= total;
    anchor.depth /= total;
    anchor.rise /= total;
    return true;
}

/// The Layer through J on the surface @a js and the anchors beneath it (either absent), per
/// channel: with both, the two shapes' coefficients solve the two anchors; with one, the rise
/// alone; with none, J on the surface throughout.
SourceField::Layer fitLayer(const openvdb::Vec3d& js, const Anchor* a, const Anchor* b, const openvdb::Vec3d& tau, double depth)
{
    SourceField::Layer layer;
    layer.surface = openvdb::Vec3f(js);
    layer.tau = openvdb::Vec3f(tau);
    layer.depth = float(depth);
    for (int ch = 0; ch < 3; ++ch) {
        if (!a) continue;
        const double dA = a->j[ch] - js[ch];
        double slope = 0.0, rises = 0.0;
        // → 0 as τ → 0, where the rise turns linear in z.
        const double det = b ? a->depth[ch] * b->rise[ch] - b->depth[ch] * a->rise[ch] : 0.0;
        if (b && std::abs(det) > 1e-6) {
            const double dB = b->j[ch] - js[ch];
            slope = (dA * b->rise[ch] - dB * a->rise[ch]) / det;
            rises = (a->depth[ch] * dB - b->depth[ch] * dA) / det;
        } else if (a->rise[ch] > 1e-6) {
            rises = dA / a->rise[ch];
        } else if (a->depth[ch] > 1e-6) {
            slope = dA / a->depth[ch];
        }
        layer.slope[ch] = float(slope);
        layer.rise[ch] = float(rises);
    }
    return layer;
}

openvdb::Vec3d evaluate(const SourceField::Layer& layer, double z)
{
    openvdb::Vec3d j;
    double g = 0.0;
    for (int ch = 0; ch < 3; ++ch) {
        if (ch == 0 || layer.tau[ch] != layer.tau[ch - 1]) g = rise(layer.tau[ch], z);
        j[ch] = layer.surface[ch] + layer.slope[ch] * z + layer.rise[ch] * g;
    }
    return j;
}

/// A voxel within the layers' band: its coordinates and signed distance (voxels).
struct BandVoxel
{
    openvdb::Coord ijk;
    double distance;
};

} // namespace

SourceField::SourceField(const Medium& medium, const openvdb::Vec3SGrid& source, Near near)
    : mMedium(medium)
    , mValues(source.deepCopy())
    , mQuadratic(medium.surface() != nullptr)
{
    if (mQuadratic) {
        for (auto it = source.cbeginValueAll(); it; ++it) {
            for (int ch = 0; ch < 3; ++ch) mNonNegative[ch] = mNonNegative[ch] && (*it)[ch] >= 0.0f;
        }
        openvdb::Vec3SGrid& values = *mValues;
        openvdb::tools::dilateActiveValues(
            values.tree(), int(std::ceil(kReach)), openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::IGNORE_TILES);

        // J on the surface from the skin voxels (the passes gather them there: skinPoint), the
        // interior's voxels whose centre lies half a voxel inside or deeper, and the band's
        // voxels, per thread. Tiles lie wholly inside.
        auto skin = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
        auto shallowMask = openvdb::BoolGrid::create(false); // voxels of the lattice that are not deep
        tbb::enumerable_thread_specific<std::vector<BandVoxel>> bandLocal;
        tbb::enumerable_thread_specific<std::vector<std::pair<openvdb::Coord, openvdb::Vec3f>>> skinLocal;
        tbb::enumerable_thread_specific<std::vector<openvdb::Coord>> shallowLocal;
        openvdb::tree::LeafManager<openvdb::Vec3STree> leaves(values.tree());
        leaves.foreach ([&](openvdb::Vec3STree::LeafNodeType& leaf, std::size_t) {
            Medium::Sampler sampler(medium);
            const auto known = source.getConstAccessor();
            for (auto it = leaf.beginValueOn(); it; ++it) {
                const openvdb::Coord c = it.getCoord();
                const double d = sampler.signedDistance(c.asVec3d());
                // The lattice alone needs the layers of the skin and the voxels outside only.
                const bool inBand = d > (near == Near::Layers ? -kLayerInside : -0.5) && d < kReach;
                if (inBand) bandLocal.local().push_back({c, d});
                // Beyond the band, what the dilation added holds nothing (in it, the layers decide).
                if (d >= kReach || (!inBand && !known.isValueOn(c))) it.setValue(openvdb::Vec3f(0.0f));
                if (d <= -0.5 && known.isValueOn(c)) continue;
                shallowLocal.local().push_back(c);
                if (std::abs(d) < 0.5 && known.isValueOn(c)) skinLocal.local().emplace_back(c, *it / float(0.5 - d));
            }
        });
        {
            auto skinAcc = skin->getAccessor();
            for (const auto& local : skinLocal) {
                for (const auto& [c, v] : local) skinAcc.setValue(c, v);
            }
            auto shallowAcc = shallowMask->getAccessor();
            for (const auto& local : shallowLocal) {
                for (const openvdb::Coord& c : local) shallowAcc.setValueOn(c, true);
            }
        }
        std::vector<BandVoxel> band;
        for (const auto& local : bandLocal) band.insert(band.end(), local.begin(), local.end());

        // The layers: J along the normal beneath each band voxel's surface point.
        std::vector<std::optional<Layer>> layers(band.size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, band.size(), 256), [&](const tbb::blocked_range<std::size_t>& range) {
            Medium::Sampler sampler(medium);
            const auto interior = values.getConstAccessor();
            const auto known = source.getConstAccessor();
            const auto skinValues = skin->getConstAccessor();
            const auto shallow = shallowMask->getConstAccessor();
            const auto isSkin = [&](const openvdb::Coord& c) { return skinValues.isValueOn(c); };
            const auto isDeep = [&](const openvdb::Coord& c) { return known.isValueOn(c) && !shallow.isValueOn(c); };
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                const BandVoxel& v = band[i];
                openvdb::Vec3d n, js;
                if (!sampler.surfaceNormal(v.ijk.asVec3d(), n)) continue;
                const openvdb::Vec3d p = v.ijk.asVec3d() - n * v.distance;
                if (!maskedTrilinear(skinValues, p, isSkin, js, false, 0.05)) continue;
                const openvdb::Vec3d tau = sampler.sigmaT(p - n * kAnchorA) * medium.voxelSize();
                Anchor a, b;
                const bool haveA = readAnchor(interior, sampler, p, n, kAnchorA, tau, isDeep, a);
                const bool haveB = haveA && readAnchor(interior, sampler, p, n, kAnchorB, tau, isDeep, b);
                layers[i] = fitLayer(js, haveA ? &a : nullptr, haveB ? &b : nullptr, tau, -v.distance);
            }
        });

        // The lattice for the reads deeper than the layers': skin voxels inside hold the layer
        // at their centre, those outside and the rest within kReach the line through J on the
        // surface and J a voxel beneath it, continued out to their centre.
        std::optional<openvdb::Int32Grid::Accessor> index;
        if (near == Near::Layers) {
            mLayerIndex = openvdb::Int32Grid::create(-1);
            mLayerIndex->setTransform(source.transformPtr()->copy());
            index.emplace(mLayerIndex->getAccessor());
        }
        auto acc = values.getAccessor();
        const auto skinValues = skin->getConstAccessor();
        for (std::size_t i = 0; i < band.size(); ++i) {
            const BandVoxel& v = band[i];
            if (!layers[i]) {
                // No normal or no skin near: a skin voxel keeps J on the surface, a voxel
                // outside takes nothing.
                if (v.distance > -0.5) acc.setValueOnly(v.ijk, skinValues.getValue(v.ijk));
                continue;
            }
            const Layer& layer = *layers[i];
            if (index) {
                index->setValue(v.ijk, int(mLayers.size()));
                mLayers.push_back(layer);
            }
            if (v.distance <= -0.5) continue;
            const openvdb::Vec3d js(layer.surface);
            const openvdb::Vec3d j = v.distance <= 0.0 ? evaluate(layer, -v.distance) : js - (evaluate(layer, 1.0) - js) * v.distance;
            acc.setValueOnly(v.ijk, openvdb::Vec3f(j));
        }
        if (mLayerIndex) mLayerIndexDense = DenseCopy<openvdb::Int32Grid>::create(*mLayerIndex, kDenseCopyMargin, kDenseCopyBytes);
    }
    mValuesDense = DenseCopy<openvdb::Vec3SGrid>::create(*mValues, kDenseCopyMargin, kDenseCopyBytes);
}

SourceField::Sampler::Sampler(const SourceField& field)
    : mField(field)
    , mValues(*field.mValues, field.mValuesDense.get())
{
    if (!field.mLayerIndex) return;
    mLayerIndex.emplace(*field.mLayerIndex, field.mLayerIndexDense.get());
    mMedium.emplace(field.mMedium);
}

openvdb::Vec3d SourceField::Sampler::lattice(const openvdb::Vec3d& ijk) const
{
    // The parabolas through the nearest voxel and its neighbours (QuadraticSampler's
    // arithmetic; its own stencil starts at the voxel below and so leans a parabola on a voxel
    // up to two away, a one-sided fit that doubled the slab model's error).
    const openvdb::Coord nearest = openvdb::Coord::round(ijk);
    openvdb::Vec3f data[3][3][3];
    mValues.getBlock(nearest.offsetBy(-1), data);
    return openvdb::Vec3d(openvdb::tools::QuadraticSampler::triquadraticInterpolation(data, ijk - nearest.asVec3d()));
}

openvdb::Vec3d SourceField::Sampler::sample(const openvdb::Vec3d& ijk) const
{
    if (!mField.mQuadratic) return openvdb::Vec3d(mValues.sampleTrilinear(ijk));
    openvdb::Vec3d j = mLayerIndex ? nearSurface(ijk) : lattice(ijk);
    // A parabola overshoots below zero next to a steep fall-off (σt of 1e6 per voxel), and a
    // continued line may cross zero outside: a source without negative values reads none.
    for (int ch = 0; ch < 3; ++ch) {
        if (mField.mNonNegative[ch]) j[ch] = std::max(j[ch], 0.0);
    }
    return j;
}

openvdb::Vec3d SourceField::Sampler::nearSurface(const openvdb::Vec3d& ijk) const
{
    const TrilinearCell cell(ijk);
    openvdb::Int32 index[2][2][2];
    mLayerIndex->getBlock(cell.base, index);
    openvdb::Vec3d j;
    // Near the surface where a corner has a layer, unless the nearest voxel's own depth puts the
    // point beyond the layers' reach (the distance changes by at most 0.87 voxels to a corner).
    bool near = false;
    for (int i = 0; i < 8; ++i) near = near || index[i & 1][(i >> 1) & 1][(i >> 2) & 1] >= 0;
    if (near) {
        const openvdb::Coord nearest = openvdb::Coord::round(ijk) - cell.base;
        const openvdb::Int32 own = index[nearest.x()][nearest.y()][nearest.z()];
        near = own < 0 || mField.mLayers[std::size_t(own)].depth < kModelDepth + kBlendWidth + 0.87;
    }
    const double z = near ? -mMedium->signedDistance(ijk) : kModelDepth + kBlendWidth;
    if (z >= kModelDepth + kBlendWidth) {
        j = lattice(ijk);
    } else {
        // The layers around, weighted trilinearly over the voxels that have one.
        double total = 0.0;
        openvdb::Vec3d surface(0.0), slope(0.0), rise(0.0), tau(0.0);
        for (int i = 0; i < 8; ++i) {
            const openvdb::Int32 k = index[i & 1][(i >> 1) & 1][(i >> 2) & 1];
            if (k < 0 || cell.weight[i] <= 0.0) continue;
            const Layer& l = mField.mLayers[std::size_t(k)];
            const double w = cell.weight[i];
            total += w;
            surface += w * openvdb::Vec3d(l.surface);
            slope += w * openvdb::Vec3d(l.slope);
            rise += w * openvdb::Vec3d(l.rise);
            tau += w * openvdb::Vec3d(l.tau);
        }
        if (total < 0.25) {
            j = lattice(ijk);
        } else {
            Layer l;
            l.surface = openvdb::Vec3f(surface / total);
            l.slope = openvdb::Vec3f(slope / total);
            l.rise = openvdb::Vec3f(rise / total);
            l.tau = openvdb::Vec3f(tau / total);
            j = evaluate(l, std::max(z, 0.0));
            if (z > kModelDepth) {
                const double w = (z - kModelDepth) / kBlendWidth;
                j = j * (1.0 - w) + lattice(ijk) * w;
            }
        }
    }
    return j;
}

} // namespace vxf
