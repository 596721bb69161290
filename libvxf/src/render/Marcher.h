// vxf — the camera's march through the medium: single and multiple scattering, emission and
// transmittance along one ray (private to render/).
#pragma once

#include <vxf/core/GridLookup.h>
#include <vxf/core/GridRoles.h>
#include <vxf/core/Hash.h>
#include <vxf/light/DirectLight.h>
#include <vxf/light/InteriorField.h>
#include <vxf/light/LightSampler.h>
#include <vxf/light/VolumeEmission.h>
#include <vxf/render/Render.h>
#include <vxf/scatter/SourceField.h>
#include <vxf/transport/Phase.h>
#include <vxf/transport/Transmittance.h>
#include <vxf/transport/UniformBricks.h>

#include <cmath>
#include <limits>
#include <optional>
#include <vector>

namespace vxf::detail {

/// Radiance gathered along one ray through the medium, per layer.
struct Gathered
{
    openvdb::Vec3d direct{0.0}, scatter{0.0}, transmittance{1.0};
    /// The transmittance of the transport's medium (σt − g·σs, Medium), which the light in the
    /// grids crosses toward the camera; `transmittance` where the phase is isotropic.
    openvdb::Vec3d reducedTransmittance{1.0};
    bool touched = false; ///< the march met any medium
};

/// What a Marcher reads along a camera ray besides the medium; every member may be null (none).
struct MarcherInputs
{
    /// Single scattering is read from `direct` (the `direct` grid's J), or with `lights`
    /// (RenderOptions::directFromLights) marched to them at every step; multiple scattering from
    /// `scatter`, J = σs·φ/4π of the `scatter` grid (SourceField: near a surface, its layers;
    /// the passes read the lattice alone there).
    const InteriorField* direct = nullptr;
    const SourceField* scatter = nullptr;
    const std::vector<LightSampler>* lights = nullptr;
    const RayScene* occluders = nullptr; ///< what shadows the marches to the lights
    /// The media's meshes: the marches cross the surface where the meshes do
    /// (Medium::Sampler::snapCrossingsTo): grazing rays, at silhouettes and terminators.
    const RayScene* boundary = nullptr;
    /// Volume lights, seen along the march, in the direct layer, through the medium's own σt,
    /// where the medium is.
    const std::vector<VolumeEmission>* emitters = nullptr;
    /// The grids' J, solved in the transport's scaled medium, reaches the camera through that
    /// medium's σt − gridForward·σs (the share of σs kept in the beam: g⁴ by delta-M, g by the
    /// similarity relation; Phase.h).
    double gridForward = 0.0;
    /// That scaled medium (σt − gridForward·σs), or null. With `lights` and gridForward > 0,
    /// single scattering is marched through it, to the lights and to the camera, with the phase
    /// itself, σs·p(θ): delta-M's single-scattering correction (Nakajima & Tanaka 1988, "TMS").
    /// The light the transport keeps in the beam (the phase's forward peak) is light on its way
    /// in the scaled medium, which the grids' orders beyond the first take as such: single
    /// scattering through the medium's own σt left out every path that crossed the peak before
    /// its one wide scattering (a front-lit smoke at g 0.8 came out 17–26% below Cycles).
    const Medium* scaled = nullptr;
    /// `scatter_anisotropy` (the mean direction of travel a): the scattered light's J toward the
    /// camera is J·rest(a, ω), the rest of the phase; `directAnisotropy`
    /// (`scatter_source_anisotropy`) the `direct` grid's J alike.
    const openvdb::Vec3SGrid* scatterAnisotropy = nullptr;
    RestPhase rest;
    const openvdb::Vec3SGrid* directAnisotropy = nullptr;
};

class Marcher
{
public:
    /// @a medium holds the material's own coefficients (Medium::actual). With a phase of g ≠ 0
    /// the light marched to the lights is scattered toward the camera by the phase through the
    /// medium's own σt; the grids' J as MarcherInputs says.
    Marcher(const Medium& medium, const RenderOptions& options, const MarcherInputs& in)
        : mMedium(medium)
        , mMarchedScaled(in.lights && in.scaled && in.gridForward > 0.0)
        , mShadowMedium(mMarchedScaled ? *in.scaled : medium)
        , mSampler(medium)
        , mShadowSampler(mShadowMedium)
        , mOptions(options)
        , mLights(in.lights)
        , mOccluders(in.occluders)
        , mPhaseG(medium.phaseG())
        , mGridForward(in.gridForward)
        , mRest(in.rest)
    {
        if (in.scatterAnisotropy && in.rest.chi[0] != 0.0f) mScatterAnisotropy.emplace(in.scatterAnisotropy->getConstAccessor());
        if (in.directAnisotropy && in.rest.chi[0] != 0.0f) mDirectAnisotropy.emplace(in.directAnisotropy->getConstAccessor());
        if (in.emitters) {
            for (const VolumeEmission& e : *in.emitters) mEmitters.emplace_back(e);
        }
        // Camera and shadow rays cross the surface where the meshes do, as the reference's do.
        if (in.boundary && !in.boundary->empty()) {
            mSampler.snapCrossingsTo(in.boundary);
            mShadowSampler.snapCrossingsTo(in.boundary);
        }
        mShadowMarch.step = options.step;
        mShadowMarch.cutoff = options.cutoff;
        if (in.direct && !mLights) mDirect.emplace(*in.direct);
        if (in.scatter) mScatter.emplace(*in.scatter);
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
        // The marched light through σt, or the scaled medium's (mMarchedScaled); the grid's as the grids'.
        const bool directTrue = mLights != nullptr && !mMarchedScaled;
        for (int c = 0; c < 3; ++c) {
            const EmissionWeights& wDirect = directTrue ? w[c] : wReduced[c];
            const double directWeight = directTrue ? g.transmittance[c] : g.reducedTransmittance[c];
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
                s.fluence * (double(n) * phase) * sampleTransmittance(s, mShadowSampler, mShadowMedium, x, mShadowMarch, mOccluders);
            phi += f;
            if (n == 1) exact += f;
        }
        return phi;
    }

    const Medium& mMedium;
    /// Single scattering marched through the scaled medium (MarcherInputs::scaled).
    const bool mMarchedScaled;
    const Medium& mShadowMedium; ///< what the marches to the lights cross: mMedium, or the scaled medium
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

} // namespace vxf::detail
