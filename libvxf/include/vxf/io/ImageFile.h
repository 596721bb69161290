// vxf — writing rendered images: multi-layer OpenEXR and an sRGB PNG preview.
#pragma once

#include <vxf/core/RenderedImage.h>

#include <string>

namespace vxf {

/// Write @a image as OpenEXR (atomically): R G B A (combined + alpha), surface.R/G/B,
/// direct.R/G/B, scatter.R/G/B, depth.Z, normal.X/Y/Z; 32-bit float, or 16-bit half when @a half.
void writeExr(const std::string& path, const RenderedImage& image, bool half = false);

/// An RGB image read from a file, row-major from the top-left pixel.
struct RgbImage
{
    int width = 0, height = 0;
    std::vector<openvdb::Vec3f> pixels;
};

/// Read the R, G, B channels of an OpenEXR file (any pixel type; a missing channel reads 0,
/// a luminance-only Y file reads grey). Throws vxf::InputError naming the file for an
/// unreadable file, and the pixel for a NaN, infinite or negative value.
RgbImage readExr(const std::string& path);

/// Write the combined layer as an 8-bit sRGB PNG (atomically), scaled by @a exposure
/// (2^stops) and clamped to [0,1].
void writePng(const std::string& path, const RenderedImage& image, double exposureStops = 0.0);

} // namespace vxf
