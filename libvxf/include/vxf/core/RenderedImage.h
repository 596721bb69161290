// vxf — a rendered image's layers: what the render stage makes and the image files hold.
#pragma once

#include <openvdb/Types.h>

#include <cstddef>
#include <vector>

namespace vxf {

/// Image layers, row-major from the top-left pixel.
struct RenderedImage
{
    int width = 0, height = 0;
    std::vector<openvdb::Vec3f> combined, surface, direct, scatter, normal;
    std::vector<float> alpha, depth; ///< depth: distance along the camera ray to the surface (0 where it misses)
    std::vector<float> samples; ///< camera rays per pixel (more where adaptive sampling refined it)
    std::size_t refinedPixels = 0; ///< pixels that got more than the render's samples per pixel
};

} // namespace vxf
