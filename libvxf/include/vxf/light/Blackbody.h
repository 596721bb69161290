// vxf — the light of a blackbody: emission from a temperature grid, as Cycles' Principled Volume gives it.
#pragma once

#include <openvdb/Types.h>

#include <cmath>

namespace vxf {

/// Cycles' blackbody emission per unit length per K⁴, in luminance: its Principled Volume with
/// Blackbody Intensity 1 emits kCyclesBlackbody·T⁴ (Rec.709 luminance per world unit; not
/// scaled by density): the Stefan–Boltzmann radiance σ/π·T⁴ scaled by 1e-6. Checked against
/// Blender 4.5.15's Cycles through a slab ten voxels thick of uniform temperature from 1500 to
/// 10000 K: the same T⁴ law to 0.4%, and vxf's render of that slab within 0.2% of Cycles' at
/// 6500 K (docs/accuracy-notes.md, "Blackbody").
inline constexpr double kCyclesBlackbody = 5.670374419e-8 / M_PI * 1e-6;

/// The colour of a blackbody at @a kelvin in linear Rec.709 (sRGB primaries, D65), scaled to
/// luminance 1: Planck's law integrated against the CIE 1931 2° observer (Wyman, Sloan and
/// Shirley's 2013 multi-lobe fit of it) from 360 to 830 nm, channels outside the gamut clamped to
/// 0. Within 1.1% of Cycles' blackbody per channel from 4000 K up, 1.7% at 3000 K, 2.3% at 2000 K (Cycles fits a
/// table of its own; measured, tests/unit/BlackbodyTest.cc). Tabulated on a log scale from
/// 400 K to 100 000 K and interpolated; held at those ends beyond them.
openvdb::Vec3d blackbodyColour(double kelvin);

/// Emission per unit length of a blackbody at @a kelvin as Cycles' Principled Volume gives it at
/// Blackbody Intensity 1: kCyclesBlackbody·T⁴·blackbodyColour(T); 0 for T ≤ 0.
openvdb::Vec3d blackbodyEmission(double kelvin);

} // namespace vxf
