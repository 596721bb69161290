#include <vxf/scatter/CoarseLevel.h>

#include <openvdb/tools/Interpolation.h>
#include <openvdb/tree/LeafManager.h>

namespace vxf {

namespace {

int floorDiv(int a, int f) { return a >= 0 ? a / f : -((-a + f - 1) / f); }

openvdb::Coord floorDiv(const openvdb::Coord& c, int f) { return {floorDiv(c.x(), f), floorDiv(c.y(), f), floorDiv(c.z(), f)}; }

template <typename GridT>
typename GridT::Ptr average(const GridT& fine, int factor, const openvdb::math::Transform::Ptr& xform)
{
    using ValueT = typename GridT::ValueType;
    auto coarse = GridT::create(fine.background());
    coarse->setTransform(xform);
    coarse->setName(fine.getName());
    coarse->setGridClass(fine.getGridClass());
    auto acc = coarse->getAccessor();
    const double cell = double(factor) * factor * factor;
    const auto add = [&](const openvdb::Coord& c, const ValueT& v, double voxels) {
        acc.setValueOn(c, ValueT(acc.getValue(c) + v * float(voxels / cell)));
    };
    for (auto it = fine.cbeginValueOn(); it; ++it) {
        if (it.isVoxelValue()) {
            add(floorDiv(it.getCoord(), factor), *it, 1.0);
            continue;
        }
        openvdb::CoordBBox box;
        it.getBoundingBox(box);
        const openvdb::Coord lo = floorDiv(box.min(), factor), hi = floorDiv(box.max(), factor);
        for (int x = lo.x(); x <= hi.x(); ++x)
            for (int y = lo.y(); y <= hi.y(); ++y)
                for (int z = lo.z(); z <= hi.z(); ++z) {
                    const openvdb::Coord c(x, y, z), first(x * factor, y * factor, z * factor);
                    openvdb::CoordBBox block(first, first + openvdb::Coord(factor - 1));
                    block.intersect(box);
                    add(c, *it, double(block.volume()));
                }
    }
    return coarse;
}

} // namespace

openvdb::math::Transform::Ptr coarseTransform(const openvdb::math::Transform& fine, int factor)
{
    // fine index = factor·i + (factor − 1)/2: translate first, then scale.
    auto xform = fine.copy();
    xform->preTranslate(openvdb::Vec3d(0.5 * (factor - 1)));
    xform->preScale(double(factor));
    return xform;
}

openvdb::FloatGrid::Ptr blockAverage(const openvdb::FloatGrid& fine, int factor, const openvdb::math::Transform::Ptr& coarse)
{
    return average(fine, factor, coarse);
}

openvdb::Vec3SGrid::Ptr blockAverage(const openvdb::Vec3SGrid& fine, int factor, const openvdb::math::Transform::Ptr& coarse)
{
    return average(fine, factor, coarse);
}

openvdb::Vec3SGrid::Ptr prolong(const openvdb::Vec3SGrid& coarse, const openvdb::Vec3SGrid& fine)
{
    auto out = fine.deepCopy();
    const openvdb::math::Transform &fineXform = fine.transform(), &coarseXform = coarse.transform();
    const auto sampleAt = [&](openvdb::Vec3SGrid::ConstAccessor& acc, const openvdb::Vec3d& fineIjk) {
        return openvdb::tools::BoxSampler::sample(acc, coarseXform.worldToIndex(fineXform.indexToWorld(fineIjk)));
    };
    openvdb::tree::LeafManager<openvdb::Vec3STree> leaves(out->tree());
    leaves.foreach ([&](openvdb::Vec3STree::LeafNodeType& leaf, std::size_t) {
        auto acc = coarse.getConstAccessor();
        for (auto it = leaf.beginValueOn(); it; ++it) it.setValue(sampleAt(acc, it.getCoord().asVec3d()));
    });
    auto acc = coarse.getConstAccessor();
    for (auto it = out->tree().beginValueOn(); it; ++it) {
        if (!it.isTileValue()) continue;
        openvdb::CoordBBox box;
        it.getBoundingBox(box);
        it.setValue(sampleAt(acc, (box.min().asVec3d() + box.max().asVec3d()) * 0.5));
    }
    return out;
}

CoarseMedium coarsenMedium(const Medium& medium, int factor)
{
    CoarseMedium out;
    auto xform = coarseTransform(medium.transform(), factor);
    out.transform = xform;
    out.set = VoxelSet(xform);
    out.set.put(blockAverage(medium.density(), factor, xform));
    if (const auto* a = medium.sigmaAGrid()) out.set.put(blockAverage(*a, factor, xform));
    if (const auto* s = medium.sigmaSGrid()) out.set.put(blockAverage(*s, factor, xform));
    out.medium = std::make_unique<Medium>(out.set, medium.material());
    return out;
}

} // namespace vxf
