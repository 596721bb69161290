#include <vxf/render/Render.h>

#include <vxf/core/GridLookup.h>
#include <vxf/core/GridRoles.h>
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

namespace {

/// Radiance gathered along one ray through the medium, per layer.
struct Gathered
{
    openvdb::Vec3d direct{0.0}, scatter{0.0}, transmittance{1.0};
    /// The transmittance of the transport's medium (σt − g·σs, Medium), which the light in the
    /// grids crosses toward the camera; `transmittance` where the phase is isotropic.
    openvdb::Vec3d reducedTransmittance{1.0};
    bool touched = false; ///< the march met any medium
};

class Marcher
{
public:
    /// Single scattering is read from @a direct (the `direct` grid's J), or with @a lights
    /// (options.directFromLights) marched to them at every step; multiple scattering from
    /// @a scatter, J = σs·φ/4π of the `scatter` grid (SourceField: near a surface, its layers;
    /// the passes read the lattice alone there). Either layer may be null (none).
    /// @a medium holds the material's own coefficients (Medium::actual). With a phase of g ≠ 0
    /// the light marched to the lights is scattered toward the camera by the phase through the
    /// medium's own σt; the grids' J, solved in the transport's scaled medium, reaches the
    /// camera through that medium's σt − @a gridForward·σs (the share of σs kept in the beam:
    /// g⁴ by delta-M, g by the similarity relation; Phase.h). With @a scatterAnisotropy
    /// (`scatter_anisotropy`, the mean direction of travel a) the scattered light's J toward
    /// the camera is J·@a rest(a, ω), the rest of the phase; with @a directAnisotropy
    /// (`scatter_source_anisotropy`) the `direct` grid's J alike. @a emitters (volume lights)
    /// are seen along the march, in the direct layer, through the medium's own σt, where the
    /// medium is.
    /// With @a boundary (the media's meshes) the marches cross the surface where the meshes
    /// do (Medium::Sampler::snapCrossingsTo): grazing rays, at silhouettes and terminators.
    Marcher(const Medium& medium, const RenderOptions& options, const InteriorField* direct, const SourceField* scatter,
        const std::vector<LightSampler>* lights = nullptr, const RayScene* occluders = nullptr, const RayScene* boundary = nullptr,
        const std::vector<VolumeEmission>* emitters = nullptr, double gridForward = 0.0,
        const openvdb::Vec3SGrid* scatterAnisotropy = nullptr, const RestPhase& rest = {},
        const openvdb::Vec3SGrid* directAnisotropy = nullptr)
        : mMedium(medium)
        , mSampler(medium)
        , mShadowSampler(medium)
        , mOptions(options)
        , mLights(lights)
        , mOccluders(occluders)
        , mPhaseG(medium.phaseG())
        , mGridForward(gridForward)
        , mRest(rest)
    {
        if (scatterAnisotropy && rest.chi[0] != 0.0f) mScatterAnisotropy.emplace(scatterAnisotropy->getConstAccessor());
        if (directAnisotropy && rest.chi[0] != 0.0f) mDirectAnisotropy.emplace(directAnisotropy->getConstAccessor());
        if (emitters) {
            for (const VolumeEmission& e : *emitters) mEmitters.emplace_back(e);
        }
        // Camera and shadow rays cross the surface where the meshes do, as the reference's do.
        if (boundary && !boundary->empty()) {
            mSampler.snapCrossingsTo(boundary);
            mShadowSampler.snapCrossingsTo(boundary);
        }
        mShadowMarch.step = options.step;
        mShadowMarch.cutoff = options.cutoff;
        if (direct && !mLights) mDirect.emplace(*direct);
        if (scatter) mScatter.emplace(*scatter);
        mBounds = marchBounds(medium);
        mTauCutoff = -std::log(std::max(options.cutoff, std::numeric_limits<double>::min()));
    }

    /// Whether world point @a x lies in the medium: inside its surface where it has one, else
    /// where σt is above 0 (a camera there sees the medium around it, no surface first).
    bool contains(const openvdb::Vec3d& x)
    {
        const openvdb::Vec3d p = mMedium.transform().worldToIndex(x);
        if (mMedium.activeBounds().empty() || !mBounds.isInside(p)) return false;
        if (mMedium.surface()) return mSampler.signedDistance(p) < 0.0;
        const openvdb::Vec3d sigmaT = mSampler.sigmaT(p);
        return std::max({sigmaT[0], sigmaT[1], sigmaT[2]}) > 0.0;
    }

    /// March from world point @a start along unit world direction @a dir, at most @a maxDistance (world).
    Gathered march(const openvdb::Vec3d& start, const openvdb::Vec3d& dir, double maxDistance = std::numeric_limits<double>::infinity(),
        std::uint64_t key = 0)
    {
        Gathered g;
        if (mMedium.activeBounds().empty()) return g;
        const openvdb::math::Transform& xform = mMedium.transform();
        const openvdb::Vec3d o = xform.worldToIndex(start);
        openvdb::Vec3d d = xform.worldToIndex(start + dir) - o;
        d.normalize();
        double t0 = 0.0, t1 = std::numeric_limits<double>::max();
        if (std::isfinite(maxDistance)) t1 = maxDistance / mMedium.voxelSize(); // index units (uniform voxels)
        if (!clipRay(mBounds, o, d, t0, t1)) return g;
        const int steps = std::max(1, int(std::ceil((t1 - t0) / std::max(mOptions.step, 1e-3))));
        const double h = (t1 - t0) / steps;
        mExtraPoint = 3 * std::uint64_t(steps); // per ray: a ray traced again gets the same light picks
        mRayDirection = dir;
        openvdb::Vec3d tau(0.0), reducedTau(0.0);
        const bool reduced = mGridForward != 0.0;
        InsideSteps inside(mSampler, o, d, t0, h);
        InsideStep step;
        Emission eStart, eMiddle, eEnd; // J at the step's start, middle and end
        bool endRead = false; // eEnd is the last step's (an empty step reads none)
        const UniformBricks* uniform = mMedium.uniformBricks();
        for (int i = 0; i < steps; ++i) {
            // Empty space (a region of density 0, or outside the surface) crossed at once.
            float density = 0.0f;
            const int empty = uniform ? uniform->stepsWithin(o + d * inside.t(), d, h, steps - i, density) : 0;
            if (empty > 0 && density == 0.0f) {
                inside.skip(empty);
                i += empty - 1;
                endRead = false;
                continue;
            }
            // Only the part of the step inside the surface holds medium (sharp boundary).
            if (!inside.next(step)) continue;
            const std::uint64_t point = 3 * std::uint64_t(i); // the ray's emission points, 3 per step
            // An empty step adds nothing: its J is not read (a volume object's empty space, where
            // marching to the lights from every step was most of the render).
            const openvdb::Vec3d sigmaT = mSampler.sigmaT(step.midpoint) * step.interior;
            if (sigmaT[0] <= 0.0 && sigmaT[1] <= 0.0 && sigmaT[2] <= 0.0) {
                endRead = false;
                continue;
            }
            // The interior scale at the step's ends, where σs is read there (lights).
            const auto scaleAt = [&](const openvdb::Vec3d& p) { return mLights ? mSampler.interiorScale(p, step.distanceBound) : 1.0; };
            // A joined step starts where the last ended: its J there, read as the last step's end
            // (point − 1) would have been.
            eStart = !step.joined ? emission(step.start, scaleAt(step.start), key, point)
                : endRead         ? eEnd
                                  : emission(step.start, scaleAt(step.start), key, point - 1);
            eMiddle = emission(step.midpoint, step.interior, key, point + 1);
            eEnd = emission(step.end, scaleAt(step.end), key, point + 2);
            endRead = true;
            g.touched = true;
            const double hWorld = step.length * mMedium.voxelSize();
            const Segment whole{step.start, step.end, hWorld, eStart, eMiddle, eEnd};
            const openvdb::Vec3d reducedSigmaT =
                reduced ? sigmaT - mSampler.sigmaS(step.midpoint) * (mGridForward * step.interior) : sigmaT;
            integrate(whole, sigmaT, reduced ? &reducedSigmaT : nullptr, scaleAt, key, kRefineDepth, g);
            for (int c = 0; c < 3; ++c) tau[c] += std::max(0.0, sigmaT[c]) * hWorld;
            for (int c = 0; c < 3 && reduced; ++c) reducedTau[c] += std::max(0.0, reducedSigmaT[c]) * hWorld;
            // Stop where neither transmittance lets anything through (σt' < σt for g > 0).
            if (std::min({tau[0], tau[1], tau[2]}) > mTauCutoff &&
                (!reduced || std::min({reducedTau[0], reducedTau[1], reducedTau[2]}) > mTauCutoff)) {
                g.transmittance = openvdb::Vec3d(0.0);
                break;
            }
        }
        return g;
    }

private:
    /// J = σs·φ/4π of single scattering and of the scattered light at one point.
    struct Emission
    {
        openvdb::Vec3d direct{0.0}, scatter{0.0};
        openvdb::Vec3d emitted{0.0}; ///< volume lights' emission (radiance per unit length)
        /// The part of `direct` that is a function of the point, not one random sample of a
        /// light of many (environment, area): what tells whether a step resolves it.
        openvdb::Vec3d directExact{0.0};
    };

    /// A piece of a march step: its ends (index space), world length and J at its ends and middle.
    struct Segment
    {
        openvdb::Vec3d start, end;
        double length;
        Emission eStart, eMiddle, eEnd;
    };

    /// Adds ΔL = T·∫ J(s)·e^{−σt s} ds over @a s to @a g (J quadratic through its three values,
    /// emissionWeights) and multiplies g's T by e^{−σt·length}; σt constant over the step.
    /// With @a reducedSigmaT (a phase of g ≠ 0) the grids' J is taken through it and g's
    /// reducedTransmittance; the light marched to the lights through @a sigmaT.
    /// Where single scattering changes by more than kRefineRatio across @a s, the quadratic
    /// cannot follow it and @a s is halved (up to @a depth times), J read at the quarter
    /// points: light that reaches the medium only by grazing it (beyond the terminator; lit at
    /// a grazing angle) lives in a layer far thinner than a voxel, where a quadratic through a
    /// step's three points counted it several times over. On a sphere lit by a point light (1.3
    /// voxels per mean free path) the darkest third's single scattering came out 7.9% bright
    /// at one-voxel steps and 1.8% at a tenth of a voxel; halved so from one-voxel steps, 1.6%.
    template <typename ScaleAt>
    void integrate(const Segment& s, const openvdb::Vec3d& sigmaT, const openvdb::Vec3d* reducedSigmaT, const ScaleAt& scaleAt,
        std::uint64_t key, int depth, Gathered& g)
    {
        const std::array<EmissionWeights, 3> w = emissionWeights(sigmaT, s.length);
        if (depth > 0 && needsRefinement(s, w, g)) {
            const openvdb::Vec3d middle = 0.5 * (s.start + s.end);
            const openvdb::Vec3d q1 = 0.5 * (s.start + middle), q3 = 0.5 * (middle + s.end);
            const Emission e1 = emission(q1, scaleAt(q1), key, mExtraPoint++);
            const Emission e3 = emission(q3, scaleAt(q3), key, mExtraPoint++);
            integrate(Segment{s.start, middle, 0.5 * s.length, s.eStart, e1, s.eMiddle}, sigmaT, reducedSigmaT, scaleAt, key, depth - 1, g);
            integrate(Segment{middle, s.end, 0.5 * s.length, s.eMiddle, e3, s.eEnd}, sigmaT, reducedSigmaT, scaleAt, key, depth - 1, g);
            return;
        }
        if (!mEmitters.empty()) { // seen as emitted, through the medium's own σt
            for (int c = 0; c < 3; ++c) {
                g.direct[c] += g.transmittance[c] * emissionIntegral(w[c], s.eStart.emitted[c], s.eMiddle.emitted[c], s.eEnd.emitted[c]);
            }
        }
        // The grids' J through the reduced medium (the same weights where the phase is isotropic,
        // so reducedTransmittance stays transmittance to the bit); the marched light through σt.
        std::array<EmissionWeights, 3> reducedWeights;
        if (reducedSigmaT) reducedWeights = emissionWeights(*reducedSigmaT, s.length);
        const std::array<EmissionWeights, 3>& wReduced = reducedSigmaT ? reducedWeights : w;
        const bool directMarched = mLights != nullptr; // else read from the grid, solved in the reduced medium
        for (int c = 0; c < 3; ++c) {
            const EmissionWeights& wDirect = directMarched ? w[c] : wReduced[c];
            const double directWeight = directMarched ? g.transmittance[c] : g.reducedTransmittance[c];
            g.direct[c] += directWeight * emissionIntegral(wDirect, s.eStart.direct[c], s.eMiddle.direct[c], s.eEnd.direct[c]);
            g.scatter[c] +=
                g.reducedTransmittance[c] * emissionIntegral(wReduced[c], s.eStart.scatter[c], s.eMiddle.scatter[c], s.eEnd.scatter[c]);
            g.transmittance[c] *= w[c].transmittance;
            g.reducedTransmittance[c] *= wReduced[c].transmittance;
        }
    }

    /// Whether single scattering over @a s varies by more than kRefineRatio and what it could
    /// add matters (at least kRefineShare of what the ray has gathered so far, with it). Only
    /// its exact part counts: one random sample of an environment differs from the next by
    /// chance, not for want of resolution (counted, the translucent bunny's render took twice
    /// as long for nothing).
    static bool needsRefinement(const Segment& s, const std::array<EmissionWeights, 3>& w, const Gathered& g)
    {
        for (int c = 0; c < 3; ++c) {
            const double lo = std::min({s.eStart.directExact[c], s.eMiddle.directExact[c], s.eEnd.directExact[c]});
            const double hi = std::max({s.eStart.directExact[c], s.eMiddle.directExact[c], s.eEnd.directExact[c]});
            if (!(hi > kRefineRatio * std::max(lo, 0.0))) continue;
            const double could = (hi - std::max(lo, 0.0)) * w[c].total * g.transmittance[c];
            if (could >= kRefineShare * (g.direct[c] + g.scatter[c] + could)) return true;
        }
        return false;
    }

    static constexpr double kRefineRatio = 4.0; ///< J's max/min over a step piece beyond which it is halved
    static constexpr double kRefineShare = 1e-3; ///< ... when it could add this share of the ray's light
    static constexpr int kRefineDepth = 4; ///< halvings at most: pieces down to 1/16 of a step

    /// The rest of the phase toward the camera (−mRayDirection) of light whose mean direction of
    /// travel @a anisotropy holds, at index point @a p (the medium's index space).
    double towardCamera(openvdb::Vec3SGrid::ConstAccessor& anisotropy, const openvdb::Vec3d& p) const
    {
        openvdb::Vec3s sampled;
        openvdb::tools::BoxSampler::sample(anisotropy, p, sampled);
        return double(mRest(openvdb::Vec3f(clampedToUnit(openvdb::Vec3d(sampled))), -openvdb::Vec3f(mRayDirection)));
    }

    /// J at index point @a p inside the surface, whose interior scale is @a interior
    /// (Medium::Sampler::interiorScale). Single scattering: marched to the lights (one sample
    /// per light, the @a point-th of the ray of @a key) with σs(p)·interior when
    /// options.directFromLights, else the `direct` grid's InteriorField. Multiple scattering:
    /// σs·φ/4π of the `scatter` grid, continued to the surface by SourceField's layers (the
    /// passes read its lattice alone; σs·φ is one per-voxel quantity: interpolating σs and φ
    /// apart would square the ramp where both fall to zero at the surface).
    Emission emission(const openvdb::Vec3d& p, double interior, std::uint64_t key, std::uint64_t point)
    {
        Emission e;
        if (mLights) {
            openvdb::Vec3d exact;
            const openvdb::Vec3d scale = mSampler.sigmaS(p) * (interior / (4.0 * M_PI));
            e.direct = scale * fluenceFromLights(mMedium.transform().indexToWorld(p), key, point, exact);
            e.directExact = scale * exact;
        }
        if (mDirect) {
            e.direct = mDirect->sample(p);
            if (mDirectAnisotropy) e.direct *= towardCamera(*mDirectAnisotropy, p);
            e.directExact = e.direct;
        }
        if (mScatter) e.scatter = mScatter->sample(p);
        if (mScatterAnisotropy) e.scatter *= towardCamera(*mScatterAnisotropy, p);
        if (!mEmitters.empty()) {
            const openvdb::Vec3d world = mMedium.transform().indexToWorld(p);
            for (VolumeEmission::Sampler& emitter : mEmitters) e.emitted += emitter.at(world);
        }
        return e;
    }

    /// φ0 at world point @a x, the @a point-th emission point of the ray of @a key: Σ over the
    /// lights of fluence × transmittance × visibility. A light of many samples (area,
    /// environment) gives one of them per call, weighted by their count: one shadow march per
    /// light and point, unbiased. The picks along one ray follow a golden-ratio sequence from a
    /// random start (each uniform, together spread over the light's samples), so the ray's
    /// points see the whole environment or area light, not the same few samples by chance:
    /// independent picks left the translucent bunny's environment-lit image noisy in every
    /// pixel at 64 camera rays.
    openvdb::Vec3d fluenceFromLights(const openvdb::Vec3d& x, std::uint64_t key, std::uint64_t point, openvdb::Vec3d& exact)
    {
        constexpr double kGolden = 0.6180339887498949; // (√5 − 1)/2
        openvdb::Vec3d phi(0.0);
        exact = openvdb::Vec3d(0.0);
        const std::uint64_t pointKey = mixBits(key + point);
        for (std::size_t l = 0; l < mLights->size(); ++l) {
            const LightSampler& light = (*mLights)[l];
            const std::size_t n = light.count();
            if (n == 0) continue;
            const double u = unitHash(key, l, 11) + double(point % (1u << 20)) * kGolden;
            const std::size_t pick = std::min(n - 1, std::size_t((u - std::floor(u)) * double(n)));
            light.sample(x, pointKey, 0.5 * mMedium.voxelSize(), mLightSamples, pick, pick + 1);
            if (mLightSamples.empty()) continue; // a sample that carries nothing
            const LightSample& s = mLightSamples.front();
            // The phase scatters the light's direction of travel (−s.direction) toward the camera (−mRayDirection).
            const double phase = henyeyGreenstein4Pi(mPhaseG, s.direction.dot(mRayDirection));
            const openvdb::Vec3d f =
                s.fluence * (double(n) * phase) * sampleTransmittance(s, mShadowSampler, mMedium, x, mShadowMarch, mOccluders);
            phi += f;
            if (n == 1) exact += f;
        }
        return phi;
    }

    const Medium& mMedium;
    Medium::Sampler mSampler, mShadowSampler;
    const RenderOptions& mOptions;
    const std::vector<LightSampler>* mLights;
    const RayScene* mOccluders;
    MarchOptions mShadowMarch;
    std::vector<LightSample> mLightSamples;
    std::optional<InteriorField::Sampler> mDirect;
    std::optional<SourceField::Sampler> mScatter; ///< J of the scattered light
    openvdb::BBoxd mBounds;
    double mTauCutoff;
    std::uint64_t mExtraPoint = 0; ///< the next refined point's index along the ray (after the steps' 3 per step)
    double mPhaseG; ///< Henyey-Greenstein g (0: isotropic)
    double mGridForward; ///< the share of σs the grids' transport kept in the beam
    RestPhase mRest; ///< the rest of the phase, with mScatterAnisotropy or mDirectAnisotropy
    /// The `scatter_anisotropy` grid, read trilinearly (none: the scattered light isotropic).
    std::optional<openvdb::Vec3SGrid::ConstAccessor> mScatterAnisotropy;
    /// The `scatter_source_anisotropy` grid with the `direct` grid read (none: its J isotropic).
    std::optional<openvdb::Vec3SGrid::ConstAccessor> mDirectAnisotropy;
    std::vector<VolumeEmission::Sampler> mEmitters; ///< volume lights (none: empty)
    openvdb::Vec3d mRayDirection; ///< the marched ray's world direction (the phase's outgoing one)
};

} // namespace

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

/// What one camera ray brings back.
struct CameraSample
{
    openvdb::Vec3d combined{0.0}, surface{0.0}, direct{0.0}, scatter{0.0}, normal{0.0};
    double alpha = 0.0, depth = 0.0;
    int object = -1; ///< what it met first (an index in Scene::objects; the level set and a volume are the medium object's, 0 without one),
                     ///< -1: nothing
};

/// A pixel's camera rays so far, and whether they disagree enough to call for more.
struct PixelSum
{
    CameraSample total; ///< sums of every layer (object unused)
    double luminance = 0.0, luminanceSquared = 0.0;
    int count = 0, firstObject = -2;
    bool mixed = false; ///< the rays met different objects, or some met one and some none

    void add(const CameraSample& c)
    {
        total.combined += c.combined;
        total.surface += c.surface;
        total.direct += c.direct;
        total.scatter += c.scatter;
        total.normal += c.normal;
        total.alpha += c.alpha;
        total.depth += c.depth;
        const double y = 0.2126 * c.combined[0] + 0.7152 * c.combined[1] + 0.0722 * c.combined[2];
        if (std::isfinite(y)) {
            luminance += y;
            luminanceSquared += y * y;
        }
        if (count == 0) firstObject = c.object;
        mixed = mixed || c.object != firstObject;
        ++count;
    }

    /// Silhouettes and object edges, or a standard error of the mean luminance above
    /// @a noiseLevel of the mean (needs two rays or more).
    bool disagrees(double noiseLevel) const
    {
        if (mixed) return true;
        if (count < 2) return false;
        const double mean = luminance / count;
        const double variance = std::max(0.0, (luminanceSquared - count * mean * mean) / (count - 1));
        return std::sqrt(variance / count) > noiseLevel * std::abs(mean);
    }
};

/// The surface term at world point @a x with unit normal @a n facing the viewer direction @a v:
/// Σ_samples φ_s·T·V·cosθ·(kd/π + ks·(e+8)/(8π)·(n·h)^e).
class SurfaceShader
{
public:
    /// @a media: the medium's meshes (null: none), which tell a shadow ray where it meets the
    /// medium, so that it marches only from there (visibility). Shadow rays march at @a march's
    /// step and cutoff, as the camera rays' do.
    SurfaceShader(const Medium& medium, const std::vector<LightSampler>& lights, const RayScene* occluders, const RayScene* media,
        const MarchOptions& march)
        : mMedium(medium)
        , mSampler(medium)
        , mLights(lights)
        , mOccluders(occluders)
        , mMedia(media && !media->empty() ? media : nullptr)
        , mMarch(march)
    {
    }

    openvdb::Vec3d shade(
        const SurfaceShading& shading, const openvdb::Vec3d& x, const openvdb::Vec3d& n, const openvdb::Vec3d& v, std::uint64_t key)
    {
        // Start half a voxel off the surface: the medium's own fog ramp must not shadow it.
        const openvdb::Vec3d start = x + n * (0.5 * mMedium.voxelSize());
        const double specularNorm = (shading.shininess + 8.0) / (8.0 * M_PI);
        openvdb::Vec3d sum(0.0);
        for (const LightSampler& light : mLights) {
            light.sample(start, key, 1e-6 * mMedium.voxelSize(), mSamples);
            for (const LightSample& s : mSamples) {
                const double cosTheta = n.dot(s.direction);
                if (cosTheta <= 0.0) continue;
                const openvdb::Vec3d visible = visibility(s, start);
                if (visible == openvdb::Vec3d(0.0)) continue;
                const openvdb::Vec3d h = (s.direction + v).unit();
                const double specular = specularNorm * std::pow(std::max(0.0, n.dot(h)), shading.shininess);
                for (int c = 0; c < 3; ++c) {
                    sum[c] += s.fluence[c] * visible[c] * cosTheta * (shading.diffuse[c] / M_PI + shading.specular[c] * specular);
                }
            }
        }
        return sum;
    }

private:
    /// T·V of light sample @a s seen from @a start (outside the medium, half a voxel off a
    /// surface): with the medium's meshes, the vacuum before them is not marched (vacuumAhead).
    openvdb::Vec3d visibility(const LightSample& s, const openvdb::Vec3d& start)
    {
        if (!mMedia) return sampleTransmittance(s, mSampler, mMedium, start, mMarch, mOccluders);
        // The occluders over the whole way (as sampleTransmittance asks them); the medium from where the vacuum ends.
        const double dx = mMedium.voxelSize();
        if (mOccluders && mOccluders->occluded(start, s.direction, 1e-4 * dx, s.distance)) return openvdb::Vec3d(0.0);
        const double skip = vacuumAhead(*mMedia, start, s.direction, kVacuumMargin * dx, s.distance);
        if (std::isinf(skip)) return openvdb::Vec3d(1.0);
        LightSample rest = s;
        if (std::isfinite(rest.distance)) rest.distance -= skip;
        return sampleTransmittance(rest, mSampler, mMedium, start + s.direction * skip, mMarch, nullptr);
    }

    const Medium& mMedium;
    Medium::Sampler mSampler;
    const std::vector<LightSampler>& mLights;
    const RayScene* mOccluders;
    const RayScene* mMedia;
    MarchOptions mMarch;
    std::vector<LightSample> mSamples;
};

/// What render() sets up once and every thread's CameraTracer reads: the scene, the lights
/// each term samples, the camera's frame and what camera rays hit.
struct RenderContext
{
    RenderContext(
        const VoxelSet& set_, const Medium& medium_, const Scene& scene_, const RenderOptions& options_, const RenderMeshes& meshes_)
        : set(set_)
        , medium(medium_)
        , actual(medium_.actual())
        , firstMoment(medium_.material().phaseG != 0.0 && set_.find(grids::kScatterAnisotropy))
        , grids(firstMoment ? medium_ : medium_.isotropic())
        , scene(scene_)
        , options(options_)
        , meshes(meshes_)
        , useMeshes(meshes_.visible && !meshes_.visible->empty())
    {
        // Hits report RayScene ids, which index scene.objects.
        for (const RayScene* rays : {meshes.visible, meshes.occluders, meshes.media}) {
            if (rays && rays->largestId() >= int(scene.objects.size())) {
                throw Error(fmt::format(
                    "render: a mesh is given as object {}, but the scene has {} object(s)", rays->largestId(), scene.objects.size()));
            }
        }
        // What the level set stands for: the scene's medium object, if it names one.
        for (const auto& o : scene.objects) {
            if (o.role == SceneObject::Role::Medium) {
                levelSetObject = &o;
                break;
            }
        }
        volumeMedium = levelSetObject && levelSetObject->isVolume();
        if (!useMeshes && !volumeMedium) {
            levelSet = set.get<openvdb::FloatGrid>(grids::kSurface);
            if (levelSet->getGridClass() != openvdb::GRID_LEVEL_SET) throw Error("grid 'surface' must be a level set");
            levelSetIntersector.emplace(*levelSet);
        }
        const auto shining = [&](std::vector<LightSampler>& out) {
            for (const Light& l : scene.lights) {
                if (l.type != Light::Type::Volume && l.power() != openvdb::Vec3d(0.0)) out.emplace_back(l);
            }
        };
        bool anyReflects = false;
        for (const auto& o : scene.objects) anyReflects = anyReflects || o.surface.reflects();
        if (options.surface && anyReflects) shining(surfaceLights);
        if (options.directFromLights) shining(volumeLights);
        for (const Light& l : scene.lights) {
            if (l.type == Light::Type::Volume && l.power() != openvdb::Vec3d(0.0)) emitters.emplace_back(l);
        }
        if (!options.directFromLights && set.find(grids::kDirect)) directField.emplace(grids, *set.get<openvdb::Vec3SGrid>(grids::kDirect));
        if (set.find(grids::kScatter)) {
            scatterField.emplace(
                grids, *sourceFromFluence(grids, *set.get<openvdb::Vec3SGrid>(grids::kScatter)), SourceField::Near::Layers);
        }
        if (firstMoment) {
            scatterAnisotropy = set.get<openvdb::Vec3SGrid>(grids::kScatterAnisotropy);
            if (set.find(grids::kSourceAnisotropy)) sourceAnisotropy = set.get<openvdb::Vec3SGrid>(grids::kSourceAnisotropy);
            for (const auto& grid : {scatterAnisotropy, sourceAnisotropy}) { // read in the medium's index space
                if (grid && grid->transform() != medium.transform()) {
                    throw Error(fmt::format("grid '{}' does not share the transform of 'density'", grid->getName()));
                }
            }
        }

        const Camera& camera = scene.camera;
        forward = (camera.lookAt - camera.position).unit();
        right = forward.cross(camera.up).unit();
        up = right.cross(forward);
        aspect = double(options.width) / double(options.height);
        tanHalf = std::tan(0.5 * camera.fovDegrees * M_PI / 180.0);
    }

    /// The camera ray through image point (@a px, @a py) (pixels from the top-left corner).
    void cameraRay(double px, double py, openvdb::Vec3d& origin, openvdb::Vec3d& dir) const
    {
        const Camera& camera = scene.camera;
        const double sx = 2.0 * px / options.width - 1.0, sy = 1.0 - 2.0 * py / options.height;
        origin = camera.position;
        dir = forward;
        if (camera.orthographic) {
            origin += right * (0.5 * camera.width * sx) + up * (0.5 * camera.width / aspect * sy);
        } else {
            dir = (forward + right * (sx * tanHalf * aspect) + up * (sy * tanHalf)).unit();
        }
    }

    const VoxelSet& set;
    /// The transport's medium (σs scaled by the phase, Medium) and the medium itself, which
    /// camera and shadow rays cross.
    const Medium& medium;
    const Medium actual;
    /// The scatter solve carried the phase's first moment (it wrote `scatter_anisotropy`: the
    /// accelerated sweeps); otherwise it took the similarity relation's isotropic medium.
    const bool firstMoment;
    /// The medium the grids' J is read in and reaches the camera through: the transport's
    /// (firstMoment) or its isotropic() one. (The `direct` grid's J, read without the lights,
    /// scatters toward the camera by the rest of the phase with firstMoment, from
    /// `scatter_source_anisotropy`: a front-lit smoke's backscatter is a sixth of isotropic's;
    /// isotropically otherwise.)
    const Medium grids;
    openvdb::Vec3SGrid::ConstPtr scatterAnisotropy; ///< with firstMoment
    openvdb::Vec3SGrid::ConstPtr sourceAnisotropy; ///< with firstMoment, where the set has it
    const Scene& scene;
    const RenderOptions& options;
    const RenderMeshes& meshes;
    const bool useMeshes;
    /// Without meshes, camera rays meet the `surface` level set, through a copy of the intersector per thread.
    openvdb::FloatGrid::ConstPtr levelSet;
    std::optional<openvdb::tools::LevelSetRayIntersector<openvdb::FloatGrid>> levelSetIntersector;
    const SceneObject* levelSetObject = nullptr;
    /// The medium's index in scene.objects (what a camera ray that meets it first reports), 0 without one.
    int mediumIndex() const { return levelSetObject ? int(levelSetObject - scene.objects.data()) : 0; }
    /// The medium is a volume object's grid: no surface, every camera ray marches from the camera.
    bool volumeMedium = false;
    std::vector<LightSampler> surfaceLights; ///< the lights the surface term reflects (none: no surface term)
    std::vector<LightSampler> volumeLights; ///< the lights single scattering is marched to (directFromLights)
    std::optional<InteriorField> directField; ///< single scattering read from the `direct` grid (not directFromLights)
    std::optional<SourceField> scatterField; ///< J = σs·φ/4π of the `scatter` grid, or none
    std::vector<VolumeEmission> emitters; ///< the volume lights, seen along camera rays
    openvdb::Vec3d forward, right, up; ///< the camera's frame
    double aspect = 1.0, tanHalf = 1.0;
};

/// One thread's camera rays: its own intersector, Marcher and shader over a shared RenderContext.
class CameraTracer
{
public:
    explicit CameraTracer(const RenderContext& context)
        : mContext(context)
        , mOptions(context.options)
        , mIntersector(context.levelSetIntersector)
        , mMarcher(context.actual, context.options, context.directField ? &*context.directField : nullptr,
              context.scatterField ? &*context.scatterField : nullptr, context.options.directFromLights ? &context.volumeLights : nullptr,
              context.meshes.occluders, context.meshes.media, &context.emitters,
              context.firstMoment ? transportScaling(context.medium.phaseG()).forward : context.medium.phaseG(),
              context.scatterAnisotropy.get(), context.firstMoment ? RestPhase(transportScaling(context.medium.phaseG())) : RestPhase(),
              context.directField ? context.sourceAnisotropy.get() : nullptr)
        , mShader(context.actual, context.surfaceLights, context.meshes.occluders, context.meshes.media,
              MarchOptions{context.options.step, context.options.cutoff})
        , mEpsilon(1e-4 * context.medium.voxelSize())
    {
    }

    /// One camera ray through image point (x + u, y + v).
    CameraSample trace(int x, int y, double u, double v, std::uint64_t key)
    {
        openvdb::Vec3d origin, dir;
        mContext.cameraRay(x + u, y + v, origin, dir);
        CameraSample c;
        if (mContext.volumeMedium) return throughVolume(origin, dir, key);
        if (mMarcher.contains(origin)) return fromInside(origin, dir, key);
        const std::optional<Hit> hit = firstSurface(origin, dir);
        if (!hit) {
            c.combined = mOptions.background;
            return c;
        }
        c.object = hit->id;
        c.alpha = 1.0;
        c.depth = hit->distance;
        c.normal = hit->normal;
        c.surface = surfaceTerm(hit->object, hit->point, hit->normal, dir, key);
        c.combined = c.surface;
        if (hit->object && hit->object->role != SceneObject::Role::Medium) return c; // opaque
        addVolume(c, mOptions.gather ? gatherInward(*hit, key) : marchOn(hit->point, hit->distance, dir, key));
        return c;
    }

private:
    /// Where a camera ray first meets something (normal facing the ray), and what it is.
    struct Hit
    {
        openvdb::Vec3d point, normal;
        double distance = 0.0;
        int id = 0; ///< CameraSample::object
        const SceneObject* object = nullptr; ///< null: the level set of a scene without a medium object
    };

    /// The volume's radiance per layer, and what lies behind the medium seen through its transmittance.
    struct VolumeTerm
    {
        openvdb::Vec3d direct{0.0}, scatter{0.0}, transmittance{0.0}, behind{0.0};
        bool touched = false; ///< the march met medium
        int opaque = -1; ///< the occluder or emitter behind (its object index), or −1
    };

    std::optional<Hit> firstSurface(const openvdb::Vec3d& origin, const openvdb::Vec3d& dir)
    {
        Hit hit;
        if (mContext.useMeshes) {
            const auto h = mContext.meshes.visible->intersect(origin, dir);
            if (!h) return std::nullopt;
            hit.distance = h->distance;
            hit.point = origin + dir * hit.distance;
            hit.normal = h->normal;
            hit.id = int(h->id);
            hit.object = &mContext.scene.objects[std::size_t(h->id)];
            return hit;
        }
        openvdb::math::Ray<double> ray(origin, dir);
        if (!mIntersector->intersectsWS(ray, hit.point, hit.normal, hit.distance)) return std::nullopt;
        hit.normal.normalize();
        if (hit.normal.dot(dir) > 0.0) hit.normal = -hit.normal;
        hit.id = mContext.mediumIndex(); // the level set is the medium's surface
        hit.object = mContext.levelSetObject;
        return hit;
    }

    openvdb::Vec3d surfaceTerm(
        const SceneObject* object, const openvdb::Vec3d& x, const openvdb::Vec3d& normal, const openvdb::Vec3d& dir, std::uint64_t key)
    {
        if (!object) return openvdb::Vec3d(0.0);
        if (mContext.surfaceLights.empty() || !object->surface.reflects()) return object->surface.emission;
        return object->surface.emission + mShader.shade(object->surface, x, normal, -dir, key);
    }

    /// Adds the volume term @a g to @a c: its layers, and to the combined image the volume's
    /// light plus what lies behind it seen through its transmittance.
    static void addVolume(CameraSample& c, const VolumeTerm& g)
    {
        c.direct = g.direct;
        c.scatter = g.scatter;
        for (int ch = 0; ch < 3; ++ch) c.combined[ch] += g.direct[ch] + g.scatter[ch] + g.transmittance[ch] * g.behind[ch];
    }

    /// A camera inside the medium (fog, a cloud around the viewer): no surface first; the ray
    /// marches from the camera on (marchOn), in view and gather mode alike, and what lies
    /// behind shows through the medium's transmittance. Alpha 1, depth and normal 0: the
    /// medium fills the view.
    CameraSample fromInside(const openvdb::Vec3d& origin, const openvdb::Vec3d& dir, std::uint64_t key)
    {
        CameraSample c;
        c.object = mContext.mediumIndex(); // every ray from inside meets the medium first, as a ray hitting its surface does
        c.alpha = 1.0;
        addVolume(c, marchOn(origin, 0.0, dir, key));
        return c;
    }

    /// A medium without a surface (a volume object's grid: smoke, a cloud): the ray marches from
    /// the camera through the density, over empty space in the marches' uniform bricks, up to
    /// the first occluder or emitter, in view and gather mode alike (gather mode has no surface
    /// to gather under). Alpha is 1 − T (the mean over the channels) where nothing opaque is
    /// met, so the volume composites over a plate; for the adaptive rays a ray that meets the
    /// medium met its object, else what it meets behind.
    CameraSample throughVolume(const openvdb::Vec3d& origin, const openvdb::Vec3d& dir, std::uint64_t key)
    {
        CameraSample c;
        const VolumeTerm g = marchOn(origin, 0.0, dir, key);
        addVolume(c, g);
        c.alpha = g.opaque >= 0 ? 1.0 : 1.0 - (g.transmittance[0] + g.transmittance[1] + g.transmittance[2]) / 3.0;
        c.object = g.touched ? mContext.mediumIndex() : g.opaque;
        return c;
    }

    /// View mode: the ray marches on through the medium from @a from (where it met the medium,
    /// @a distance along the camera ray, or the camera inside it), up to the first occluder or
    /// emitter behind.
    VolumeTerm marchOn(const openvdb::Vec3d& from, double distance, const openvdb::Vec3d& dir, std::uint64_t key)
    {
        VolumeTerm out;
        double behindDistance = std::numeric_limits<double>::infinity();
        out.behind = mOptions.background;
        if (mContext.useMeshes) {
            double t = mEpsilon;
            while (auto h = mContext.meshes.visible->intersect(from, dir, t)) {
                const SceneObject& o = mContext.scene.objects[std::size_t(h->id)];
                if (o.role != SceneObject::Role::Medium) { // opaque: an occluder or an emitter
                    behindDistance = h->distance;
                    out.opaque = int(h->id);
                    out.behind = surfaceTerm(&o, from + dir * h->distance, h->normal, dir, key);
                    break;
                }
                t = h->distance + mEpsilon; // the medium's own surfaces: the march covers them
            }
        }
        // From half a voxel before the hit: without a `surface` level set the voxels the
        // surface cuts hold medium on its outer side too (their volume fraction); with one,
        // the march skips what lies outside it.
        const double back = std::min(0.5 * mContext.medium.voxelSize(), distance);
        const auto g = mMarcher.march(from - dir * back, dir, behindDistance + back, key);
        out.direct = g.direct;
        out.scatter = g.scatter;
        out.transmittance = g.transmittance;
        out.touched = g.touched;
        return out;
    }

    /// Gather mode: the mean of marches over cosine-weighted directions about the inward
    /// normal; those that leave the volume at once are dropped and the rest re-weighted.
    VolumeTerm gatherInward(const Hit& hit, std::uint64_t key)
    {
        VolumeTerm out;
        const int directions = std::max(1, mOptions.gatherDirections);
        const openvdb::Vec3d inward = -hit.normal;
        const openvdb::Vec3d helper = std::abs(inward.x()) < 0.9 ? openvdb::Vec3d(1, 0, 0) : openvdb::Vec3d(0, 1, 0);
        const openvdb::Vec3d t1 = inward.cross(helper).unit(), t2 = inward.cross(t1);
        int kept = 0;
        for (int k = 0; k < directions; ++k) {
            const double a = (k + unitHash(key, std::uint64_t(k), 2)) / directions;
            const double phi = 2.0 * M_PI * unitHash(key, std::uint64_t(k), 3);
            const double r = std::sqrt(a);
            const openvdb::Vec3d w =
                (t1 * (r * std::cos(phi)) + t2 * (r * std::sin(phi)) + inward * std::sqrt(std::max(0.0, 1.0 - a))).unit();
            const auto g = mMarcher.march(hit.point, w, std::numeric_limits<double>::infinity(), mixBits(key + std::uint64_t(k) * 7919u));
            if (!g.touched) continue;
            out.direct += g.direct;
            out.scatter += g.scatter;
            ++kept;
        }
        if (kept > 0) {
            out.direct /= kept;
            out.scatter /= kept;
        }
        return out;
    }

    const RenderContext& mContext;
    const RenderOptions& mOptions;
    std::optional<openvdb::tools::LevelSetRayIntersector<openvdb::FloatGrid>> mIntersector;
    Marcher mMarcher;
    SurfaceShader mShader;
    double mEpsilon;
};

/// Pixel @a pixel's layers: the means of its rays, NaN and Inf written as 0.
void storePixel(RenderedImage& image, std::size_t pixel, const PixelSum& sum)
{
    const double inv = 1.0 / sum.count;
    const auto finite = [](openvdb::Vec3d v) {
        for (int c = 0; c < 3; ++c) v[c] = std::isfinite(v[c]) ? v[c] : 0.0;
        return openvdb::Vec3f(v);
    };
    const CameraSample& t = sum.total;
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

RenderedImage render(const VoxelSet& set, const Medium& medium, const Scene& scene, const RenderOptions& options,
    const RenderMeshes& meshes, Interrupter* interrupter)
{
    InterruptStep step(interrupter, "rendering");
    if (options.width < 1 || options.height < 1 || options.samples < 1) {
        throw UsageError(
            fmt::format("image size {}x{} with {} samples per pixel is empty", options.width, options.height, options.samples));
    }
    requireMemory("render",
        stageMemory(kStageFixedBytes, double(medium.density().activeVoxelCount()), kRenderBytesPerVoxel,
            double(options.width) * double(options.height), kRenderBytesPerPixel));
    const RenderContext context(set, medium, scene, options, meshes);

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
    const auto tracePixel = [&](CameraTracer& tracer, int x, int y, bool refining) {
        const std::size_t pixel = std::size_t(y) * std::size_t(options.width) + std::size_t(x);
        const auto key = [&](int s) { return std::uint64_t(pixel) * 65536u + std::uint64_t(s); };
        PixelSum sum;
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
            CameraTracer tracer(context);
            std::size_t refinedHere = 0;
            for (int y = rows.begin(); y != rows.end() && !cancelled; ++y) {
                for (int x = 0; x < options.width; ++x) {
                    if (refining && !needsMore(x, y)) continue;
                    const std::size_t pixel = std::size_t(y) * std::size_t(options.width) + std::size_t(x);
                    const PixelSum sum = tracePixel(tracer, x, y, refining);
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
