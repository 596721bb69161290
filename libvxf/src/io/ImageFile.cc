#include <vxf/io/ImageFile.h>

#include <vxf/io/AtomicFile.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <png.h>

#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <memory>

namespace vxf {

void writeExr(const std::string& path, const RenderedImage& image, bool half)
{
    const int w = image.width, h = image.height;
    if (w < 1 || h < 1) throw Error(fmt::format("{}: cannot write an empty image", path));
    // OpenEXR converts float slices to half channels on writing.
    const Imf::PixelType type = half ? Imf::HALF : Imf::FLOAT;
    Imf::Header header(w, h);
    Imf::FrameBuffer frame;
    const std::size_t vecStride = sizeof(openvdb::Vec3f), rowVec = vecStride * std::size_t(w);
    const auto addVec = [&](const std::vector<openvdb::Vec3f>& layer, const std::string& prefix, const char* names) {
        for (int c = 0; c < 3; ++c) {
            const std::string name = prefix + names[c];
            header.channels().insert(name, Imf::Channel(type));
            frame.insert(name, Imf::Slice(Imf::FLOAT, (char*)(const_cast<float*>(layer.data()->asPointer()) + c), vecStride, rowVec));
        }
    };
    const auto addScalar = [&](const std::vector<float>& layer, const std::string& name) {
        header.channels().insert(name, Imf::Channel(type));
        frame.insert(name, Imf::Slice(Imf::FLOAT, (char*)layer.data(), sizeof(float), sizeof(float) * std::size_t(w)));
    };
    addVec(image.combined, "", "RGB");
    addScalar(image.alpha, "A");
    addVec(image.direct, "direct.", "RGB");
    addVec(image.scatter, "scatter.", "RGB");
    addVec(image.normal, "normal.", "XYZ");
    addScalar(image.depth, "depth.Z");
    writeAtomically(path, [&](const std::string& tmp) {
        try {
            Imf::OutputFile file(tmp.c_str(), header);
            file.setFrameBuffer(frame);
            file.writePixels(h);
        } catch (const std::exception& e) {
            throw Error(fmt::format("{}: cannot write OpenEXR: {}", path, e.what()));
        }
    });
}

namespace {
unsigned char toSrgb8(double linear)
{
    const double c = std::clamp(std::isfinite(linear) ? linear : 0.0, 0.0, 1.0);
    const double s = c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055;
    return static_cast<unsigned char>(std::lround(s * 255.0));
}
} // namespace

void writePng(const std::string& path, const RenderedImage& image, double exposureStops)
{
    const int w = image.width, h = image.height;
    if (w < 1 || h < 1) throw Error(fmt::format("{}: cannot write an empty image", path));
    const double scale = std::pow(2.0, exposureStops);
    std::vector<unsigned char> rgb(std::size_t(w) * std::size_t(h) * 3);
    for (std::size_t i = 0; i < image.combined.size(); ++i) {
        for (int c = 0; c < 3; ++c) rgb[3 * i + std::size_t(c)] = toSrgb8(image.combined[i][c] * scale);
    }
    writeAtomically(path, [&](const std::string& tmp) {
        std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(tmp.c_str(), "wb"), std::fclose);
        if (!file) throw Error(fmt::format("{}: cannot create", path));
        png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
        png_infop info = png ? png_create_info_struct(png) : nullptr;
        if (!png || !info) throw Error(fmt::format("{}: libpng: out of memory", path));
        if (setjmp(png_jmpbuf(png))) {
            png_destroy_write_struct(&png, &info);
            throw Error(fmt::format("{}: libpng failed to write", path));
        }
        png_init_io(png, file.get());
        png_set_IHDR(png, info, png_uint_32(w), png_uint_32(h), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
            PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
        png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
        png_write_info(png, info);
        for (int y = 0; y < h; ++y) png_write_row(png, &rgb[std::size_t(y) * std::size_t(w) * 3]);
        png_write_end(png, nullptr);
        png_destroy_write_struct(&png, &info);
        if (std::fflush(file.get()) != 0) throw Error(fmt::format("{}: write failed", path));
    });
}

} // namespace vxf
