#include <vxf/light/InteriorField.h>

#include <vxf/core/GridRoles.h>
#include <vxf/core/MaskedTrilinear.h>

#include <openvdb/tools/Interpolation.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace vxf {

namespace {

constexpr float kNoLog = -std::numeric_limits<float>::infinity();

} // namespace

openvdb::Vec3SGrid::Ptr sourceFromFluence(const Medium& medium, const openvdb::Vec3SGrid& phi)
{
    auto j = phi.deepCopy();
    j->setName(grids::kScatterSource);
    openvdb::tree::LeafManager<openvdb::Vec3STree> leaves(j->tree());
    leaves.foreach ([&](openvdb::Vec3STree::LeafNodeType& leaf, std::size_t) {
        Medium::Sampler sampler(medium);
        // Inactive values too: trilinear lookups read them.
        for (auto it = leaf.beginValueAll(); it; ++it) {
            it.setValue(openvdb::Vec3f(sampler.sigmaS(it.getCoord()) * openvdb::Vec3d(*it) / (4.0 * M_PI)));
        }
    });
    Medium::Sampler sampler(medium);
    for (auto it = j->tree().beginValueOn(); it; ++it) {
        if (!it.isTileValue()) continue;
        openvdb::CoordBBox box;
        it.getBoundingBox(box);
        const openvdb::Coord centre = box.min() + openvdb::Coord(box.dim().x() / 2);
        it.setValue(openvdb::Vec3f(sampler.sigmaS(centre) * openvdb::Vec3d(*it) / (4.0 * M_PI)));
    }
    return j;
}

InteriorField::InteriorField(const Medium& medium, const openvdb::Vec3SGrid& phi)
    : mValues(sourceFromFluence(medium, phi))
{
    if (medium.surface()) continueOutward(medium, phi);
    mValuesDense = DenseCopy<openvdb::Vec3SGrid>::create(*mValues, kDenseCopyMargin, kDenseCopyBytes);
    if (mLogs) mLogsDense = DenseCopy<openvdb::Vec3SGrid>::create(*mLogs, kDenseCopyMargin, kDenseCopyBytes);
}

void InteriorField::continueOutward(const Medium& medium, const openvdb::Vec3SGrid& phi)
{
    openvdb::Vec3SGrid& values = *mValues;

    // Interior values where the centre is inside (voxels wholly inside keep theirs); the
    // voxels to continue, per thread. Tiles lie wholly inside.
    tbb::enumerable_thread_specific<std::vector<openvdb::Coord>> outside;
    openvdb::tree::LeafManager<openvdb::Vec3STree> leaves(values.tree());
    leaves.foreach ([&](openvdb::Vec3STree::LeafNodeType& leaf, std::size_t) {
        Medium::Sampler sampler(medium);
        for (auto it = leaf.beginValueOn(); it; ++it) {
            const double d = sampler.signedDistance(it.getCoord().asVec3d());
            if (d <= -0.5) continue;
            if (d <= 0.0) {
                it.setValue(*it / float(0.5 - d));
            } else if (d < kReach) {
                outside.local().push_back(it.getCoord());
            }
        }
    });

    // Continue the interior field outward along the normal, reading only voxels whose centre
    // is inside (their values are final above).
    std::vector<openvdb::Coord> coords;
    for (const auto& local : outside) coords.insert(coords.end(), local.begin(), local.end());
    std::vector<openvdb::Vec3f> continued(coords.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, coords.size(), 256), [&](const tbb::blocked_range<std::size_t>& range) {
        Medium::Sampler sampler(medium);
        const auto known = values.getConstAccessor();
        const auto fluence = phi.getConstAccessor();
        const auto inside = [&](const openvdb::Coord& c) { return sampler.signedDistance(c.asVec3d()) <= 0.0; };
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const openvdb::Vec3d c = coords[i].asVec3d();
            const double d = sampler.signedDistance(c);
            openvdb::Vec3d n;
            const bool normal = sampler.surfaceNormal(c, n);
            openvdb::Vec3d v1(0.0), v2(0.0);
            if (!normal || !maskedTrilinear(known, c - n * (d + 1.0), inside, v1, true)) {
                // No normal, or nothing inside along it: the interior voxels around, if any.
                if (!maskedTrilinear(known, c, inside, v1, true)) v1 = openvdb::Vec3d(0.0);
                continued[i] = openvdb::Vec3f(v1);
                continue;
            }
            const openvdb::Vec3d q2 = c - n * (d + 2.0);
            const bool deep = sampler.signedDistance(q2) < -1.0 && maskedTrilinear(known, q2, inside, v2, true);
            openvdb::Vec3d out = v1;
            for (int ch = 0; ch < 3; ++ch) {
                if (!deep || !(v1[ch] > 0.0) || !(v2[ch] > 0.0)) continue;
                const double slope = std::clamp(std::log(v1[ch] / v2[ch]), -kMaxLogSlope, kMaxLogSlope);
                out[ch] = v1[ch] * std::exp(slope * (d + 1.0));
                if (!std::isfinite(out[ch])) out[ch] = v1[ch];
            }
            // Where J rises outward the light comes in through this side, and the medium
            // continued would only dim what reaches c: J of c's own fluence with the interior
            // σs bounds the continuation from below. It matters at the terminator, where the
            // path of grazing light to the surface grows as the square root of the depth and
            // the log-linear continuation comes out low.
            const openvdb::Vec3d q1 = c - n * (d + 1.0);
            const openvdb::Vec3d bound =
                sampler.sigmaS(q1) * sampler.interiorScale(q1, -1.0) * openvdb::Vec3d(fluence.getValue(coords[i])) / (4.0 * M_PI);
            for (int ch = 0; ch < 3; ++ch) {
                if (deep && v1[ch] > v2[ch]) out[ch] = std::max(out[ch], bound[ch]);
            }
            continued[i] = openvdb::Vec3f(out);
        }
    });
    auto acc = values.getAccessor();
    for (std::size_t i = 0; i < coords.size(); ++i) acc.setValueOnly(coords[i], continued[i]);

    mLogs = values.deepCopy();
    const auto toLog = [](const openvdb::Vec3f& v) {
        openvdb::Vec3f l;
        for (int ch = 0; ch < 3; ++ch) l[ch] = v[ch] > 0.0f ? std::log(v[ch]) : kNoLog;
        return l;
    };
    openvdb::tree::LeafManager<openvdb::Vec3STree> logLeaves(mLogs->tree());
    logLeaves.foreach ([&](openvdb::Vec3STree::LeafNodeType& leaf, std::size_t) {
        for (auto it = leaf.beginValueAll(); it; ++it) it.setValue(toLog(*it));
    });
    for (auto it = mLogs->tree().beginValueAll(); it; ++it) {
        if (it.isTileValue()) it.setValue(toLog(*it));
    }
    mLogs->tree().root().setBackground(toLog(mLogs->background()), /*updateChildNodes=*/true);
}

InteriorField::Sampler::Sampler(const InteriorField& field)
    : mValues(*field.mValues, field.mValuesDense.get())
{
    if (field.mLogs) mLogs.emplace(*field.mLogs, field.mLogsDense.get());
}

openvdb::Vec3d InteriorField::Sampler::sample(const openvdb::Vec3d& ijk) const
{
    if (!mLogs) return openvdb::Vec3d(mValues.sampleTrilinear(ijk));
    const TrilinearCell cell(ijk);
    openvdb::Vec3f logs[2][2][2];
    mLogs->getBlock(cell.base, logs);
    openvdb::Vec3d logSum(0.0);
    bool positive[3] = {true, true, true};
    for (int i = 0; i < 8; ++i) {
        const openvdb::Vec3f l = logs[i & 1][(i >> 1) & 1][(i >> 2) & 1];
        for (int ch = 0; ch < 3; ++ch) {
            if (l[ch] == kNoLog)
                positive[ch] = false;
            else
                logSum[ch] += cell.weight[i] * double(l[ch]);
        }
    }
    if (positive[0] && positive[1] && positive[2]) return openvdb::Vec3d(std::exp(logSum[0]), std::exp(logSum[1]), std::exp(logSum[2]));
    const openvdb::Vec3d linear(mValues.sampleTrilinear(ijk));
    openvdb::Vec3d out;
    for (int ch = 0; ch < 3; ++ch) out[ch] = positive[ch] ? std::exp(logSum[ch]) : linear[ch];
    return out;
}

} // namespace vxf
