#include <vxf/ops/Paint.h>

#include "Dispatch.h"

#include <algorithm>
#include <cmath>

namespace vxf::ops {

namespace {

void checkPaint(const PaintOptions& o)
{
    if (o.points.empty()) throw UsageError("paint: the stroke has no points");
    if (!(o.radius > 0.0)) throw UsageError(fmt::format("paint: radius {} must be > 0", o.radius));
    if (!(o.falloff >= 0.0)) throw UsageError(fmt::format("paint: falloff {} must be >= 0", o.falloff));
    if (!(o.strength >= 0.0 && o.strength <= 1.0)) throw UsageError(fmt::format("paint: strength {} must be in [0, 1]", o.strength));
}

/// The stroke's weight per voxel of @a grid's index space (the largest of its points'), on the
/// active voxels of @a grid only.
template <typename GridT>
openvdb::FloatGrid::Ptr strokeWeights(const GridT& grid, const PaintOptions& o)
{
    checkPaint(o);
    auto weights = openvdb::FloatGrid::create(0.0f);
    auto w = weights->getAccessor();
    const auto active = grid.getConstAccessor();
    const openvdb::math::Transform& xform = grid.transform();
    const double r2 = o.radius * o.radius;
    for (const openvdb::Vec3d& centre : o.points) {
        const openvdb::Vec3d lo = xform.worldToIndex(centre - openvdb::Vec3d(o.radius)),
                             hi = xform.worldToIndex(centre + openvdb::Vec3d(o.radius));
        const openvdb::CoordBBox box(
            openvdb::Coord::floor(openvdb::Vec3d(std::min(lo[0], hi[0]), std::min(lo[1], hi[1]), std::min(lo[2], hi[2]))),
            openvdb::Coord::ceil(openvdb::Vec3d(std::max(lo[0], hi[0]), std::max(lo[1], hi[1]), std::max(lo[2], hi[2]))));
        if (double(box.volume()) > 1e8) throw UsageError(fmt::format("paint: radius {} covers over 1e8 voxels", o.radius));
        for (auto c = box.begin(); c; ++c) {
            if (!active.isValueOn(*c)) continue;
            const double d2 = (xform.indexToWorld(*c) - centre).lengthSqr();
            if (d2 > r2) continue;
            const double weight = o.strength * (o.falloff == 0.0 ? 1.0 : std::pow(std::max(0.0, 1.0 - d2 / r2), o.falloff));
            if (!w.isValueOn(*c) || float(weight) > w.getValue(*c)) w.setValueOn(*c, float(weight));
        }
    }
    return weights;
}

} // namespace

std::uint64_t paint(openvdb::Vec3SGrid& grid, const PaintOptions& o)
{
    const auto weights = strokeWeights(grid, o);
    auto values = grid.getAccessor();
    for (auto it = weights->cbeginValueOn(); it; ++it) {
        const openvdb::Vec3d v(values.getValue(it.getCoord()));
        const double w = *it;
        const openvdb::Vec3d painted = o.mode == PaintMode::Add ? v + o.value * w : v + (o.value - v) * w;
        values.setValueOn(
            it.getCoord(), openvdb::Vec3f(detail::finite(painted[0]), detail::finite(painted[1]), detail::finite(painted[2])));
    }
    return weights->activeVoxelCount();
}

std::uint64_t paint(openvdb::FloatGrid& grid, const PaintOptions& o)
{
    const auto weights = strokeWeights(grid, o);
    auto values = grid.getAccessor();
    for (auto it = weights->cbeginValueOn(); it; ++it) {
        const double v = values.getValue(it.getCoord()), w = *it;
        values.setValueOn(it.getCoord(), detail::finite(o.mode == PaintMode::Add ? v + o.value[0] * w : v + (o.value[0] - v) * w));
    }
    return weights->activeVoxelCount();
}

} // namespace vxf::ops
