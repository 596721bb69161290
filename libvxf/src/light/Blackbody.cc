#include <vxf/light/Blackbody.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace vxf {

namespace {

/// A lobe of the CIE fit: a Gaussian of mean @a mu and widths @a below, @a above either side.
double lobe(double nm, double mu, double below, double above)
{
    const double t = (nm - mu) / (nm < mu ? below : above);
    return std::exp(-0.5 * t * t);
}

/// Planck's spectral radiance at @a nm nanometres (its scale cancels in the luminance-1 colour).
double planck(double nm, double kelvin)
{
    constexpr double h = 6.62607015e-34, c = 2.99792458e8, k = 1.380649e-23;
    const double metres = nm * 1e-9;
    return 2.0 * h * c * c / std::pow(metres, 5) / std::expm1(h * c / (metres * k * kelvin));
}

openvdb::Vec3d integratedColour(double kelvin)
{
    double x = 0.0, y = 0.0, z = 0.0;
    for (double nm = 360.0; nm <= 830.0; nm += 1.0) {
        const double p = planck(nm, kelvin);
        x += p * (1.056 * lobe(nm, 599.8, 37.9, 31.0) + 0.362 * lobe(nm, 442.0, 16.0, 26.7) - 0.065 * lobe(nm, 501.1, 20.4, 26.2));
        y += p * (0.821 * lobe(nm, 568.8, 46.9, 40.5) + 0.286 * lobe(nm, 530.9, 16.3, 31.1));
        z += p * (1.217 * lobe(nm, 437.0, 11.8, 36.0) + 0.681 * lobe(nm, 459.0, 26.0, 13.8));
    }
    // CIE XYZ to linear Rec.709 (D65), clamped to the gamut, then luminance 1.
    openvdb::Vec3d rgb(3.2404542 * x - 1.5371385 * y - 0.4985314 * z, -0.9692660 * x + 1.8760108 * y + 0.0415560 * z,
        0.0556434 * x - 0.2040259 * y + 1.0572252 * z);
    for (int i = 0; i < 3; ++i) rgb[i] = std::max(rgb[i], 0.0);
    const double luminance = 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
    return luminance > 0.0 ? rgb / luminance : openvdb::Vec3d(0.0);
}

constexpr double kLowest = 400.0, kHighest = 100000.0;
constexpr int kEntries = 1024;

const std::array<openvdb::Vec3d, kEntries>& colourTable()
{
    static const std::array<openvdb::Vec3d, kEntries> table = [] {
        std::array<openvdb::Vec3d, kEntries> t{};
        for (int i = 0; i < kEntries; ++i) {
            t[std::size_t(i)] = integratedColour(kLowest * std::pow(kHighest / kLowest, double(i) / (kEntries - 1)));
        }
        return t;
    }();
    return table;
}

} // namespace

openvdb::Vec3d blackbodyColour(double kelvin)
{
    const auto& table = colourTable();
    const double at = std::log(std::clamp(kelvin, kLowest, kHighest) / kLowest) / std::log(kHighest / kLowest) * (kEntries - 1);
    const int i = std::min(int(at), kEntries - 2);
    const double f = at - i;
    return table[std::size_t(i)] * (1.0 - f) + table[std::size_t(i) + 1] * f;
}

openvdb::Vec3d blackbodyEmission(double kelvin)
{
    if (!(kelvin > 0.0)) return openvdb::Vec3d(0.0);
    const double t2 = kelvin * kelvin;
    return blackbodyColour(kelvin) * (kCyclesBlackbody * t2 * t2);
}

} // namespace vxf
