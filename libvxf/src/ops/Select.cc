#include <vxf/ops/Select.h>

#include <vxf/core/GridRoles.h>
#include "Dispatch.h"
#include "Topology.h"

#include <functional>

namespace vxf::ops {

namespace {

/// A bool mask of the active voxels of @a grid whose centre (world) satisfies @a keep.
openvdb::BoolGrid::Ptr selectWhere(const openvdb::GridBase& grid, const std::function<bool(const openvdb::Coord&)>& keep)
{
    auto mask = openvdb::BoolGrid::create(false);
    mask->setName(grids::kMask);
    mask->setTransform(grid.transform().copy());
    const openvdb::MaskTree::Ptr topology = detail::activeTopology(grid);
    auto out = mask->getAccessor();
    for (auto it = topology->cbeginValueOn(); it; ++it) {
        openvdb::CoordBBox box;
        it.getBoundingBox(box);
        for (auto c = box.begin(); c; ++c) {
            if (keep(*c)) out.setValueOn(*c, true);
        }
    }
    return mask;
}

} // namespace

openvdb::BoolGrid::Ptr selectBox(const openvdb::GridBase& grid, const openvdb::BBoxd& worldBox)
{
    const openvdb::math::Transform& xform = grid.transform();
    return selectWhere(grid, [&](const openvdb::Coord& c) { return worldBox.isInside(xform.indexToWorld(c)); });
}

openvdb::BoolGrid::Ptr selectSphere(const openvdb::GridBase& grid, const openvdb::Vec3d& centre, double radius)
{
    const openvdb::math::Transform& xform = grid.transform();
    const double r2 = radius * radius;
    return selectWhere(grid, [&](const openvdb::Coord& c) { return (xform.indexToWorld(c) - centre).lengthSqr() <= r2; });
}

openvdb::BoolGrid::Ptr selectRange(const openvdb::GridBase& grid, double lo, double hi)
{
    return detail::dispatch(grid, "select", [&](const auto& g) {
        auto values = g.getConstAccessor();
        return selectWhere(grid, [&](const openvdb::Coord& c) {
            const auto v = values.getValue(c);
            for (int ch = 0; ch < detail::channels(v); ++ch) {
                const double x = detail::get(v, ch);
                if (!(x >= lo && x <= hi)) return false;
            }
            return true;
        });
    });
}

void removeActive(openvdb::GridBase& a, const openvdb::GridBase& b) { detail::subtractTopology(a, *detail::activeTopology(b)); }

void includeActive(openvdb::GridBase& a, const openvdb::GridBase& b) { detail::unionTopology(a, *detail::activeTopology(b)); }

} // namespace vxf::ops
