// Images (vxf/io/ImageFile.h, vxf/core/RenderedImage.h): an EXR's RGB layer reads back as written,
// in full and half floats, and a PNG preview is written for any image.
#include <vxf/io/ImageFile.h>

#include <vxf/core/RenderedImage.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <filesystem>

namespace {
vxf::RenderedImage gradientImage(int width, int height)
{
    vxf::RenderedImage image;
    image.width = width;
    image.height = height;
    const std::size_t n = std::size_t(width) * std::size_t(height);
    image.combined.resize(n);
    image.surface.assign(n, openvdb::Vec3f(0.0f));
    image.direct.assign(n, openvdb::Vec3f(0.0f));
    image.scatter.assign(n, openvdb::Vec3f(0.0f));
    image.normal.assign(n, openvdb::Vec3f(0.0f, 0.0f, 1.0f));
    image.alpha.assign(n, 1.0f);
    image.depth.assign(n, 2.0f);
    image.samples.assign(n, 4.0f);
    for (std::size_t i = 0; i < n; ++i) image.combined[i] = openvdb::Vec3f(float(i) / float(n), 0.25f, 1e-3f * float(i));
    return image;
}
} // namespace

TEST_CASE("an EXR reads back its combined layer, exactly as floats and to a half's precision as halves", "[io][image]")
{
    vxf::test::TempDir dir;
    const vxf::RenderedImage image = gradientImage(7, 5);
    vxf::writeExr(dir.path("full.exr"), image);
    const vxf::RgbImage full = vxf::readExr(dir.path("full.exr"));
    REQUIRE(full.width == 7);
    REQUIRE(full.height == 5);
    for (std::size_t i = 0; i < full.pixels.size(); ++i) CHECK(full.pixels[i] == image.combined[i]);

    vxf::writeExr(dir.path("half.exr"), image, /*half=*/true);
    const vxf::RgbImage half = vxf::readExr(dir.path("half.exr"));
    for (std::size_t i = 0; i < half.pixels.size(); ++i) {
        for (int c = 0; c < 3; ++c) CHECK(half.pixels[i][c] == Approx(image.combined[i][c]).epsilon(1e-3).margin(1e-6));
    }
    CHECK(std::filesystem::file_size(dir.path("half.exr")) < std::filesystem::file_size(dir.path("full.exr")));

    vxf::writePng(dir.path("preview.png"), image, 1.0);
    const std::string png = vxf::test::slurp(dir.path("preview.png"));
    REQUIRE(png.size() > 8);
    CHECK(png.substr(1, 3) == "PNG");
}
