#include <vxf/ops/Edit.h>

#include "Dispatch.h"

#include <cmath>
#include <vector>

namespace vxf::ops {

openvdb::Vec3d rgbToHsv(const openvdb::Vec3d& c)
{
    const double hi = std::max({c[0], c[1], c[2]}), lo = std::min({c[0], c[1], c[2]}), d = hi - lo;
    double h = 0.0;
    if (d > 0.0) {
        if (hi == c[0]) {
            h = 60.0 * std::fmod((c[1] - c[2]) / d, 6.0);
        } else if (hi == c[1]) {
            h = 60.0 * ((c[2] - c[0]) / d + 2.0);
        } else {
            h = 60.0 * ((c[0] - c[1]) / d + 4.0);
        }
    }
    if (h < 0.0) h += 360.0;
    const double s = hi != 0.0 ? d / std::abs(hi) : 0.0;
    return {h, s, hi};
}

openvdb::Vec3d hsvToRgb(const openvdb::Vec3d& hsv)
{
    const double h = std::fmod(std::fmod(hsv[0], 360.0) + 360.0, 360.0) / 60.0, s = hsv[1], v = hsv[2];
    const double chroma = std::abs(v) * s;
    const double x = chroma * (1.0 - std::abs(std::fmod(h, 2.0) - 1.0));
    const double m = v - chroma;
    openvdb::Vec3d rgb;
    switch (int(h)) {
    case 0: rgb = {chroma, x, 0.0}; break;
    case 1: rgb = {x, chroma, 0.0}; break;
    case 2: rgb = {0.0, chroma, x}; break;
    case 3: rgb = {0.0, x, chroma}; break;
    case 4: rgb = {x, 0.0, chroma}; break;
    default: rgb = {chroma, 0.0, x}; break;
    }
    return rgb + openvdb::Vec3d(m);
}

namespace {

/// Apply @a change to the voxels of @a grid that @a selection holds (every active voxel without
/// one), or add or remove them, as EditOptions says; @a changes: whether change alters a value.
template <typename GridT, typename Change>
void editVoxels(GridT& grid, const openvdb::BoolGrid* selection, const EditOptions& o, bool changes, const Change& change)
{
    if (selection && selection->transform() != grid.transform()) {
        throw UsageError(fmt::format("edit: the selection does not share grid '{}''s transform", grid.getName()));
    }
    std::vector<openvdb::Coord> voxels;
    if (selection) {
        for (auto it = selection->cbeginValueOn(); it; ++it) {
            openvdb::CoordBBox box;
            it.getBoundingBox(box);
            for (auto c = box.begin(); c; ++c) voxels.push_back(*c);
        }
    }
    auto values = grid.getAccessor();
    if (o.remove) {
        if (!selection) throw UsageError("edit: remove needs a selection (it would empty the grid)");
        for (const auto& c : voxels) values.setValueOff(c);
        return;
    }
    if (!selection) {
        if (changes) {
            for (auto it = grid.beginValueOn(); it; ++it) it.setValue(change(*it));
        }
        return;
    }
    for (const auto& c : voxels) {
        const bool on = values.isValueOn(c);
        if (!on && !o.add) continue;
        values.setValueOn(c, changes ? change(values.getValue(c)) : values.getValue(c));
    }
}

} // namespace

void edit(openvdb::Vec3SGrid& grid, const openvdb::BoolGrid* selection, const EditOptions& o)
{
    if (o.saturation < 0.0 || o.value < 0.0) throw UsageError("edit: saturation and value scales must be >= 0");
    const bool hsv = o.hueShift != 0.0 || o.saturation != 1.0 || o.value != 1.0;
    const auto change = [&](const openvdb::Vec3f& in) {
        openvdb::Vec3d c = o.set ? *o.set : openvdb::Vec3d(in);
        if (hsv) {
            openvdb::Vec3d h = rgbToHsv(c);
            h[0] += o.hueShift;
            h[1] = std::min(1.0, h[1] * o.saturation);
            h[2] *= o.value;
            c = hsvToRgb(h);
        }
        c += openvdb::Vec3d(o.offset);
        return openvdb::Vec3f(detail::finite(c[0]), detail::finite(c[1]), detail::finite(c[2]));
    };
    editVoxels(grid, selection, o, o.set || hsv || o.offset != 0.0, change);
}

void edit(openvdb::FloatGrid& grid, const openvdb::BoolGrid* selection, const EditOptions& o)
{
    if (o.hueShift != 0.0 || o.saturation != 1.0) {
        throw UsageError(fmt::format("edit: grid '{}' holds numbers, not colours: hue_shift and saturation are for vec3s grids "
                                     "(a float grid takes set, value as a scale, and offset)",
            grid.getName()));
    }
    if (o.value < 0.0) throw UsageError("edit: the value scale must be >= 0");
    if (o.set && !((*o.set)[0] == (*o.set)[1] && (*o.set)[1] == (*o.set)[2])) {
        throw UsageError(fmt::format("edit: grid '{}' holds one number a voxel: set takes one number, not a colour", grid.getName()));
    }
    const auto change = [&](float in) {
        const double v = (o.set ? (*o.set)[0] : double(in)) * o.value + o.offset;
        return detail::finite(v);
    };
    editVoxels(grid, selection, o, o.set || o.value != 1.0 || o.offset != 0.0, change);
}

} // namespace vxf::ops
