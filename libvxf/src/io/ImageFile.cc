#include <vxf/io/ImageFile.h>

#include <vxf/io/AtomicFile.h>
#include <vxf/io/InputFile.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <Imath/half.h>
#include <png.h>

#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <deque>
#include <memory>

namespace vxf {

void writeExr(const std::string& path, const RenderedImage& image, bool half)
{
    const int w = image.width, h = image.height;
    if (w < 1 || h < 1) throw Error(fmt::format("{}: cannot write an empty image", path));
    // OpenEXR 3.1's OutputFile does not convert a float slice into a half channel (it refuses the
    // frame buffer: `vxf render --half` failed so until 2026-12): half channels get half copies.
    const Imf::PixelType type = half ? Imf::HALF : Imf::FLOAT;
    Imf::Header header(w, h);
    Imf::FrameBuffer frame;
    const std::size_t n = std::size_t(w) * std::size_t(h);
    std::deque<std::vector<Imath::half>> halves; // the half copies, alive until written
    const auto addChannel = [&](const std::string& name, const float* values, std::size_t stride) {
        header.channels().insert(name, Imf::Channel(type));
        if (!half) {
            frame.insert(name, Imf::Slice(Imf::FLOAT, (char*)const_cast<float*>(values), stride, stride * std::size_t(w)));
            return;
        }
        std::vector<Imath::half>& copy = halves.emplace_back(n);
        for (std::size_t i = 0; i < n; ++i)
            copy[i] = Imath::half(*reinterpret_cast<const float*>(reinterpret_cast<const char*>(values) + i * stride));
        frame.insert(name, Imf::Slice(Imf::HALF, (char*)copy.data(), sizeof(Imath::half), sizeof(Imath::half) * std::size_t(w)));
    };
    const auto addVec = [&](const std::vector<openvdb::Vec3f>& layer, const std::string& prefix, const char* names) {
        for (int c = 0; c < 3; ++c) addChannel(prefix + names[c], layer.data()->asPointer() + c, sizeof(openvdb::Vec3f));
    };
    const auto addScalar = [&](const std::vector<float>& layer, const std::string& name) { addChannel(name, layer.data(), sizeof(float)); };
    addVec(image.combined, "", "RGB");
    addScalar(image.alpha, "A");
    addVec(image.surface, "surface.", "RGB");
    addVec(image.direct, "direct.", "RGB");
    addVec(image.scatter, "scatter.", "RGB");
    addVec(image.normal, "normal.", "XYZ");
    addScalar(image.depth, "depth.Z");
    if (image.samples.size() == image.depth.size()) addScalar(image.samples, "samples.count");
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

RgbImage readExr(const std::string& path)
{
    requireRegularFile(path);
    RgbImage image;
    try {
        Imf::InputFile file(path.c_str());
        const Imath::Box2i window = file.header().dataWindow();
        image.width = window.max.x - window.min.x + 1;
        image.height = window.max.y - window.min.y + 1;
        if (image.width < 1 || image.height < 1) throw InputError(path, 0, 0, "the image is empty");
        image.pixels.assign(std::size_t(image.width) * std::size_t(image.height), openvdb::Vec3f(0.0f));
        const bool grey = !file.header().channels().findChannel("R") && file.header().channels().findChannel("Y");
        Imf::FrameBuffer frame;
        const std::size_t stride = sizeof(openvdb::Vec3f), row = stride * std::size_t(image.width);
        // Slices are addressed by absolute pixel coordinates: shift the base by the window origin.
        char* base = reinterpret_cast<char*>(image.pixels.data()->asPointer()) - std::ptrdiff_t(window.min.x) * std::ptrdiff_t(stride) -
            std::ptrdiff_t(window.min.y) * std::ptrdiff_t(row);
        for (int c = 0; c < 3; ++c) {
            const char* name = grey ? "Y" : (c == 0 ? "R" : c == 1 ? "G" : "B");
            frame.insert(name, Imf::Slice(Imf::FLOAT, base + c * sizeof(float), stride, row, 1, 1, 0.0));
            if (grey) {
                frame.insert(name, Imf::Slice(Imf::FLOAT, base, stride, row, 1, 1, 0.0));
                break;
            }
        }
        file.setFrameBuffer(frame);
        file.readPixels(window.min.y, window.max.y);
        if (grey) {
            for (auto& p : image.pixels) p = openvdb::Vec3f(p[0]);
        }
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(path, 0, 0, fmt::format("cannot read OpenEXR: {}", e.what()));
    }
    for (std::size_t i = 0; i < image.pixels.size(); ++i) {
        for (int c = 0; c < 3; ++c) {
            const float v = image.pixels[i][c];
            if (!std::isfinite(v) || v < 0.0f) {
                throw InputError(path, 0, 0,
                    fmt::format("pixel ({}, {}) channel {} is {}: radiance must be finite and >= 0", i % std::size_t(image.width),
                        i / std::size_t(image.width), "RGB"[c], v));
            }
        }
    }
    return image;
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
        png_set_IHDR(png, info, png_uint_32(w), png_uint_32(h), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
            PNG_FILTER_TYPE_DEFAULT);
        png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
        png_write_info(png, info);
        for (int y = 0; y < h; ++y) png_write_row(png, &rgb[std::size_t(y) * std::size_t(w) * 3]);
        png_write_end(png, nullptr);
        png_destroy_write_struct(&png, &info);
        if (std::fflush(file.get()) != 0) throw Error(fmt::format("{}: write failed", path));
    });
}

} // namespace vxf
