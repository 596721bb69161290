// vxf — a camera ray: what render() sets up once (RenderContext) and one thread's tracer of
// camera rays (CameraTracer), with what a ray brings back and a pixel's sum of rays (private to render/).
#pragma once

#include "Marcher.h"
#include "SurfaceShader.h"

#include <vxf/core/Error.h>
#include <vxf/core/RayScene.h>
#include <vxf/core/Scene.h>
#include <vxf/core/VoxelSet.h>

#include <openvdb/tools/RayIntersector.h>

#include <fmt/format.h>

namespace vxf::detail {

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
        , mMarcher(context.actual, context.options, marcherInputs(context))
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
    static MarcherInputs marcherInputs(const RenderContext& context)
    {
        MarcherInputs in;
        in.direct = context.directField ? &*context.directField : nullptr;
        in.scatter = context.scatterField ? &*context.scatterField : nullptr;
        in.lights = context.options.directFromLights ? &context.volumeLights : nullptr;
        in.occluders = context.meshes.occluders;
        in.boundary = context.meshes.media;
        in.emitters = &context.emitters;
        in.gridForward = context.firstMoment ? transportScaling(context.medium.phaseG()).forward : context.medium.phaseG();
        in.scaled = &context.grids;
        in.scatterAnisotropy = context.scatterAnisotropy.get();
        in.rest = context.firstMoment ? RestPhase(transportScaling(context.medium.phaseG())) : RestPhase();
        in.directAnisotropy = context.directField ? context.sourceAnisotropy.get() : nullptr;
        return in;
    }

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

} // namespace vxf::detail
