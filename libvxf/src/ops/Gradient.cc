#include <vxf/ops/Gradient.h>

#include "Dispatch.h"
#include "Topology.h"

#include <openvdb/tools/Interpolation.h>

namespace vxf::ops {

openvdb::Vec3d rampColor(const std::vector<ColorStop>& stops, double t)
{
    if (t <= stops.front().t) return stops.front().color;
    if (t >= stops.back().t) return stops.back().color;
    for (std::size_t i = 1; i < stops.size(); ++i) {
        if (t <= stops[i].t) {
            const double span = stops[i].t - stops[i - 1].t;
            const double w = span > 0.0 ? (t - stops[i - 1].t) / span : 1.0;
            return stops[i - 1].color * (1.0 - w) + stops[i].color * w;
        }
    }
    return stops.back().color;
}

openvdb::Vec3SGrid::Ptr gradient(const openvdb::GridBase& topology, const openvdb::FloatGrid* surface, const GradientOptions& o)
{
    if (o.stops.size() < 2) throw UsageError("gradient: give at least two colours (stops)");
    for (std::size_t i = 1; i < o.stops.size(); ++i) {
        if (o.stops[i].t < o.stops[i - 1].t) throw UsageError("gradient: stops must be in increasing order of position");
    }
    const openvdb::Vec3d axis = o.to - o.from;
    if (o.kind == GradientKind::Directional && !(axis.lengthSqr() > 0.0)) throw UsageError("gradient: 'from' and 'to' must differ");
    if (o.kind == GradientKind::Radial && !(o.radius > 0.0)) throw UsageError("gradient: radius must be positive");
    if (o.kind == GradientKind::SurfaceDistance && !(o.distance > 0.0)) throw UsageError("gradient: distance must be positive");
    if (o.kind == GradientKind::SurfaceDistance && !surface) throw UsageError("gradient: surface distance needs the `surface` level set");

    auto out = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    out->setTransform(topology.transform().copy());
    out->setName("gradient");
    out->tree().topologyUnion(*detail::activeTopology(topology));
    const openvdb::math::Transform& xform = out->transform();
    // Thread-safe lookups: the surface is sampled through its tree (no shared accessor).
    const auto at = [&](const openvdb::Vec3d& world) {
        double t = 0.0;
        switch (o.kind) {
        case GradientKind::Directional: t = (world - o.from).dot(axis) / axis.lengthSqr(); break;
        case GradientKind::Radial: t = std::pow(std::max(0.0, (world - o.centre).length() / o.radius), o.falloff); break;
        case GradientKind::SurfaceDistance:
            t = -double(openvdb::tools::BoxSampler::sample(surface->tree(), surface->transform().worldToIndex(world))) / o.distance;
            break;
        }
        return openvdb::Vec3f(rampColor(o.stops, std::isfinite(t) ? t : 0.0));
    };
    detail::forEachActiveVoxel(
        *out, [&](const openvdb::Coord& c, openvdb::Vec3f& v) { v = at(xform.indexToWorld(c)); },
        [&](const openvdb::CoordBBox& box, openvdb::Vec3f& v) { v = at(xform.indexToWorld(box.getCenter())); });
    return out;
}

} // namespace vxf::ops
