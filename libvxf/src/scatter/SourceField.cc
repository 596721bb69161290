#include <vxf/scatter/SourceField.h>

#include <vxf/core/MaskedTrilinear.h>

#include <openvdb/tools/Morphology.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace vxf {

namespace {

struct Outside
{
    openvdb::Coord ijk;
    double distance; ///< voxels from the surface
    bool onSurface;  ///< its value is J at its surface point (a rim voxel: the passes gather it there)
};

} // namespace

SourceField::SourceField(const Medium& medium, const openvdb::Vec3SGrid& source)
    : mValues(source.deepCopy())
    , mQuadratic(medium.surface() != nullptr)
{
    if (mQuadratic) {
        for (auto it = source.cbeginValueAll(); it; ++it) {
            for (int ch = 0; ch < 3; ++ch) mNonNegative[ch] = mNonNegative[ch] && (*it)[ch] >= 0.0f;
        }
        openvdb::Vec3SGrid& values = *mValues;
        openvdb::tools::dilateActiveValues(values.tree(), int(std::ceil(kReach)), openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::IGNORE_TILES);

        // Interior values at the centres inside and on the rim's surface points; the voxels to
        // continue, per thread. Tiles lie wholly inside.
        tbb::enumerable_thread_specific<std::vector<Outside>> outside;
        openvdb::tree::LeafManager<openvdb::Vec3STree> leaves(values.tree());
        leaves.foreach([&](openvdb::Vec3STree::LeafNodeType& leaf, std::size_t) {
            Medium::Sampler sampler(medium);
            const auto known = source.getConstAccessor();
            for (auto it = leaf.beginValueOn(); it; ++it) {
                const double d = sampler.signedDistance(it.getCoord().asVec3d());
                if (d <= -0.5) continue;
                const bool rim = d < 0.5 && known.isValueOn(it.getCoord());
                if (d <= 0.0 || rim) it.setValue(*it / float(0.5 - d));
                if (d > 0.0) {
                    if (d < kReach) outside.local().push_back({it.getCoord(), d, rim});
                    else it.setValue(openvdb::Vec3f(0.0f));
                }
            }
        });

        // Continue the interior field outward along the normal through the surface.
        std::vector<Outside> voxels;
        for (const auto& local : outside) voxels.insert(voxels.end(), local.begin(), local.end());
        std::vector<openvdb::Vec3f> continued(voxels.size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, voxels.size(), 256), [&](const tbb::blocked_range<std::size_t>& range) {
            Medium::Sampler sampler(medium);
            const auto interior = values.getConstAccessor();
            const auto known = source.getConstAccessor();
            const auto inside = [&](const openvdb::Coord& c) { return sampler.signedDistance(c.asVec3d()) <= 0.0; };
            const auto rim = [&](const openvdb::Coord& c) {
                const double d = sampler.signedDistance(c.asVec3d());
                return d > 0.0 && d < 0.5 && known.isValueOn(c);
            };
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                const Outside& v = voxels[i];
                const openvdb::Vec3d c = v.ijk.asVec3d();
                openvdb::Vec3d n, surface(0.0), beneath(0.0), deeper(0.0);
                if (!sampler.surfaceNormal(c, n)) {
                    // No normal: the interior values around, if any.
                    if (!maskedTrilinear(interior, c, inside, surface)) surface = openvdb::Vec3d(0.0);
                    continued[i] = openvdb::Vec3f(surface);
                    continue;
                }
                const openvdb::Vec3d p = c - n * v.distance;
                const bool below = maskedTrilinear(interior, p - n, inside, beneath);
                if (v.onSurface || maskedTrilinear(interior, p, rim, surface)) {
                    // The line through J on the surface and J a voxel beneath it.
                    if (v.onSurface) surface = openvdb::Vec3d(interior.getValue(v.ijk));
                    continued[i] = openvdb::Vec3f(below ? surface + (surface - beneath) * v.distance : surface);
                } else if (below) {
                    // No rim here (the surface lies within half a voxel of the centres inside):
                    // the line through J one and two voxels beneath the surface.
                    const bool twoBelow = maskedTrilinear(interior, p - n * 2.0, inside, deeper);
                    continued[i] = openvdb::Vec3f(twoBelow ? beneath + (beneath - deeper) * (v.distance + 1.0) : beneath);
                } else {
                    continued[i] = openvdb::Vec3f(0.0f);
                }
            }
        });
        auto acc = values.getAccessor();
        for (std::size_t i = 0; i < voxels.size(); ++i) acc.setValueOnly(voxels[i].ijk, continued[i]);
    }
    mValuesDense = DenseCopy<openvdb::Vec3SGrid>::create(*mValues, 2, kDenseCopyBytes);
}

SourceField::Sampler::Sampler(const SourceField& field)
    : mValues(*field.mValues, field.mValuesDense.get())
    , mQuadratic(field.mQuadratic)
    , mNonNegative{field.mNonNegative[0], field.mNonNegative[1], field.mNonNegative[2]}
{
}

} // namespace vxf
