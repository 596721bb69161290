#include <vxf/render/Render.h>

#include "CameraTracer.h"

#include <vxf/core/GridLookup.h>
#include <vxf/core/GridRoles.h>
#include <vxf/core/GridStats.h>
#include <vxf/core/MemoryBudget.h>
#include <vxf/core/Hash.h>
#include <vxf/light/DirectLight.h>
#include <vxf/light/InteriorField.h>
#include <vxf/light/LightSampler.h>
#include <vxf/light/VolumeEmission.h>
#include <vxf/scatter/SourceField.h>
#include <vxf/transport/Phase.h>
#include <vxf/transport/Transmittance.h>
#include <vxf/transport/UniformBricks.h>

#include <openvdb/tools/RayIntersector.h>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <optional>

namespace vxf {

RenderOptions renderOptionsFrom(const SceneSettings& s)
{
    RenderOptions o;
    o.width = s.width;
    o.height = s.height;
    o.samples = s.samples;
    o.maxSamples = s.maxSamples;
    o.noiseLevel = s.noiseLevel;
    o.gather = s.gather;
    o.gatherDirections = s.gatherDirections;
    o.background = s.background;
    o.step = s.step;
    o.surface = s.surface;
    o.directFromLights = s.directFromLights;
    return o;
}

std::string refinedSummary(const RenderedImage& image, const RenderOptions& options)
{
    if (image.refinedPixels == 0) return {};
    return fmt::format("{:.1f}% of the pixels refined to {} samples",
        100.0 * double(image.refinedPixels) / (double(image.width) * double(image.height)), options.maxSamples);
}

namespace {

/// Pixel @a pixel's layers: the means of its rays, NaN and Inf written as 0.
void storePixel(RenderedImage& image, std::size_t pixel, const detail::PixelSum& sum)
{
    const double inv = 1.0 / sum.count;
    const auto finite = [](openvdb::Vec3d v) {
        for (int c = 0; c < 3; ++c) v[c] = std::isfinite(v[c]) ? v[c] : 0.0;
        return openvdb::Vec3f(v);
    };
    const detail::CameraSample& t = sum.total;
    image.combined[pixel] = finite(t.combined * inv);
    image.surface[pixel] = finite(t.surface * inv);
    image.direct[pixel] = finite(t.direct * inv);
    image.scatter[pixel] = finite(t.scatter * inv);
    image.alpha[pixel] = float(t.alpha * inv);
    image.depth[pixel] = t.alpha > 0.0 ? float(t.depth / t.alpha) : 0.0f;
    image.normal[pixel] = t.alpha > 0.0 ? finite(t.normal / t.alpha) : openvdb::Vec3f(0.0f);
    image.samples[pixel] = float(sum.count);
}

} // namespace

MemoryEstimate renderMemory(const std::vector<GridFootprint>& read, const RenderOptions& options)
{
    double gridBytes = 0.0, surfaceBytes = 0.0, denseBytes = 0.0;
    for (const GridFootprint& g : read) {
        (g.name == grids::kSurface ? surfaceBytes : gridBytes) += g.bytes;
        denseBytes += g.denseBytes;
    }
    const double pixels = double(options.width) * double(options.height);
    MemoryEstimate e;
    e.bytes = kStageFixedBytes + gridBytes * kRenderBytesPerGridByte + surfaceBytes * kRenderBytesPerSurfaceByte + denseBytes +
        pixels * kRenderBytesPerPixel;
    e.how = fmt::format("grids of {} × {:.1f}, a surface of {} × {:.0f}, dense copies of {}, {:.3g} pixels × {:.0f} bytes + {}",
        formatBytes(std::uint64_t(gridBytes)), kRenderBytesPerGridByte, formatBytes(std::uint64_t(surfaceBytes)),
        kRenderBytesPerSurfaceByte, formatBytes(std::uint64_t(denseBytes)), pixels, kRenderBytesPerPixel,
        formatBytes(std::uint64_t(kStageFixedBytes)));
    return e;
}

std::set<std::string> renderGrids(const RenderOptions& options)
{
    std::set<std::string> names = Medium::gridsRead();
    names.insert({grids::kScatter, grids::kScatterAnisotropy, grids::kSourceAnisotropy}); // (CameraTracer)
    if (!options.directFromLights) names.insert(grids::kDirect);
    return names;
}

VoxelSetReadOptions renderInputRead(const RenderOptions& options)
{
    VoxelSetReadOptions read;
    read.wanted = [names = renderGrids(options)](const std::string& name) { return names.count(name) > 0; };
    return read;
}

RenderedImage render(const VoxelSet& set, const Medium& medium, const Scene& scene, const RenderOptions& options,
    const RenderMeshes& meshes, Interrupter* interrupter)
{
    InterruptStep step(interrupter, "rendering");
    if (options.width < 1 || options.height < 1 || options.samples < 1) {
        throw UsageError(
            fmt::format("image size {}x{} with {} samples per pixel is empty", options.width, options.height, options.samples));
    }
    std::vector<GridFootprint> footprints;
    const std::set<std::string> read = renderGrids(options);
    for (const openvdb::GridBase::Ptr& grid : set.grids())
        if (read.count(grid->getName())) footprints.push_back(footprintOf(*grid));
    requireMemory("render", renderMemory(footprints, options));
    const detail::RenderContext context(set, medium, scene, options, meshes);

    RenderedImage image;
    image.width = options.width;
    image.height = options.height;
    const std::size_t n = std::size_t(options.width) * std::size_t(options.height);
    image.combined.assign(n, openvdb::Vec3f(0.0f));
    image.surface.assign(n, openvdb::Vec3f(0.0f));
    image.direct.assign(n, openvdb::Vec3f(0.0f));
    image.scatter.assign(n, openvdb::Vec3f(0.0f));
    image.normal.assign(n, openvdb::Vec3f(0.0f));
    image.alpha.assign(n, 0.0f);
    image.depth.assign(n, 0.0f);
    image.samples.assign(n, 0.0f);

    const int side = std::max(1, int(std::lround(std::sqrt(double(options.samples)))));
    const int spp = side * side;
    const int maxSpp = std::max(spp, options.maxSamples);
    // Adaptive sampling runs as a second pass over the image: a pixel is refined when its first
    // rays disagree, or when what they met differs from what a neighbour's met. The first rays
    // of a pixel the silhouette only clips (an ear's tip, a corner) may all miss, or all hit,
    // and a wrong coverage there is an error of up to the whole pixel; the neighbour that saw
    // the other side calls for the rays. The refining pass re-traces a pixel's first rays
    // (same keys, same values) rather than keeping every pixel's sums.
    constexpr int kMixed = -3;
    const bool adaptive = maxSpp > spp;
    std::vector<int> seen(adaptive ? n : 0); // the object the first rays all met (-1: none), or kMixed
    std::vector<char> noisy(adaptive ? n : 0); // the first rays' mean is noisier than options.noiseLevel
    const auto needsMore = [&](int x, int y) {
        const std::size_t pixel = std::size_t(y) * std::size_t(options.width) + std::size_t(x);
        if (noisy[pixel] || seen[pixel] == kMixed) return true;
        for (int ny = std::max(0, y - 1); ny <= std::min(options.height - 1, y + 1); ++ny) {
            for (int nx = std::max(0, x - 1); nx <= std::min(options.width - 1, x + 1); ++nx) {
                if (seen[std::size_t(ny) * std::size_t(options.width) + std::size_t(nx)] != seen[pixel]) return true;
            }
        }
        return false;
    };
    // A pixel's rays: first a jittered side x side grid over the pixel; when refining, up to
    // maxSpp more from the R2 sequence (Roberts 2018, low discrepancy for any count), randomly
    // shifted per pixel so that every ray is uniform over the pixel and the mean of all of
    // them stays unbiased.
    const auto tracePixel = [&](detail::CameraTracer& tracer, int x, int y, bool refining) {
        const std::size_t pixel = std::size_t(y) * std::size_t(options.width) + std::size_t(x);
        const auto key = [&](int s) { return std::uint64_t(pixel) * 65536u + std::uint64_t(s); };
        detail::PixelSum sum;
        for (int s = 0; s < spp; ++s) {
            const double u = (s % side + unitHash(pixel, std::uint64_t(s), 0)) / side;
            const double v = (s / side + unitHash(pixel, std::uint64_t(s), 1)) / side;
            sum.add(tracer.trace(x, y, u, v, key(s)));
        }
        if (refining) {
            const double u0 = unitHash(pixel, 0, 4), v0 = unitHash(pixel, 0, 5);
            for (int s = spp; s < maxSpp; ++s) {
                const double u = std::fmod(u0 + (s - spp + 1) * 0.7548776662466927, 1.0);
                const double v = std::fmod(v0 + (s - spp + 1) * 0.5698402909980532, 1.0);
                sum.add(tracer.trace(x, y, u, v, key(s)));
            }
        }
        return sum;
    };
    const int progressRows = options.height * (adaptive ? 2 : 1);
    std::atomic<int> rowsDone{0};
    std::atomic<std::size_t> refined{0};
    std::atomic<bool> cancelled{false};
    const auto renderPass = [&](bool refining) {
        tbb::parallel_for(tbb::blocked_range<int>(0, options.height), [&](const tbb::blocked_range<int>& rows) {
            detail::CameraTracer tracer(context);
            std::size_t refinedHere = 0;
            for (int y = rows.begin(); y != rows.end() && !cancelled; ++y) {
                for (int x = 0; x < options.width; ++x) {
                    if (refining && !needsMore(x, y)) continue;
                    const std::size_t pixel = std::size_t(y) * std::size_t(options.width) + std::size_t(x);
                    const detail::PixelSum sum = tracePixel(tracer, x, y, refining);
                    if (adaptive && !refining) {
                        seen[pixel] = sum.mixed ? kMixed : sum.firstObject;
                        noisy[pixel] = sum.disagrees(options.noiseLevel);
                    }
                    if (refining) ++refinedHere;
                    storePixel(image, pixel, sum);
                }
                const int done = ++rowsDone;
                if (interrupter && interrupter->wasInterrupted(100 * done / progressRows)) cancelled = true;
            }
            refined += refinedHere;
        });
    };
    renderPass(false);
    if (adaptive && !cancelled) renderPass(true);
    if (cancelled) throw Interrupted();
    image.refinedPixels = refined;
    return image;
}

} // namespace vxf
