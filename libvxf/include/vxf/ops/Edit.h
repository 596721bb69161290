// vxf — edits on a selection (what the thesis's Maya tool did by hand).
#pragma once

#include <openvdb/openvdb.h>

#include <optional>

namespace vxf::ops {

struct EditOptions
{
    std::optional<openvdb::Vec3d> set; ///< set the colour
    double hueShift = 0.0; ///< degrees
    double saturation = 1.0, value = 1.0; ///< HSV scale factors (≥ 0); a float grid's scale
    double offset = 0.0; ///< added after the rest: to a float grid's value, to each channel of a colour
    bool add = false; ///< activate selected voxels that are inactive (then edit them)
    bool remove = false; ///< deactivate the selected voxels (no other edit)
};

/// Edit the voxels of a Vec3f grid selected by @a selection (its active voxels; null: every
/// active voxel): set an RGB colour, then rotate hue and scale saturation and value in HSV
/// (negative and above-one values keep their sign and magnitude through the conversion: the
/// HSV value is the largest channel, the colour's shape the rest). With add, selected
/// inactive voxels become active (at the grid's value there) first; with remove, selected
/// voxels become inactive. Voxels outside the selection are untouched.
void edit(openvdb::Vec3SGrid& grid, const openvdb::BoolGrid* selection, const EditOptions& options);

/// The same on a float grid (density, a mask of weights, a temperature): set the value (the
/// first channel of options.set, whose three must agree), scale it by options.value, add
/// options.offset, add or remove voxels. Hue and saturation are colours' (vxf::UsageError).
void edit(openvdb::FloatGrid& grid, const openvdb::BoolGrid* selection, const EditOptions& options);

/// RGB ↔ HSV (h in degrees [0, 360), s and v as in the usual hexcone model).
openvdb::Vec3d rgbToHsv(const openvdb::Vec3d& rgb);
openvdb::Vec3d hsvToRgb(const openvdb::Vec3d& hsv);

} // namespace vxf::ops
