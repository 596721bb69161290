#include <vxf/core/RayScene.h>

#include <vxf/core/Error.h>

#include <embree3/rtcore.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace vxf {

struct RayScene::Impl
{
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::vector<std::pair<TriangleMesh, int>> pending;
    std::vector<int> ids; ///< per Embree geometry id: the object id
    openvdb::Vec3d centre{0.0};
    bool committed = false;

    ~Impl()
    {
        if (scene) rtcReleaseScene(scene);
        if (device) rtcReleaseDevice(device);
    }

    void check(const char* what) const
    {
        const RTCError e = rtcGetDeviceError(device);
        if (e != RTC_ERROR_NONE) throw Error(fmt::format("Embree: {} failed (error {})", what, int(e)));
    }

    /// An Embree ray (relative to the centre) for origin + t·direction, t in (tNear, tFar).
    RTCRay ray(const openvdb::Vec3d& origin, const openvdb::Vec3d& direction, double tNear, double tFar) const
    {
        RTCRay r{};
        const openvdb::Vec3d o = origin - centre;
        r.org_x = float(o.x());
        r.org_y = float(o.y());
        r.org_z = float(o.z());
        r.dir_x = float(direction.x());
        r.dir_y = float(direction.y());
        r.dir_z = float(direction.z());
        r.tnear = float(std::max(0.0, tNear));
        r.tfar = std::isfinite(tFar) ? float(tFar) : std::numeric_limits<float>::infinity();
        r.mask = 0xffffffffu;
        r.flags = 0;
        return r;
    }
};

RayScene::RayScene()
    : mImpl(std::make_unique<Impl>())
{
}
RayScene::~RayScene() = default;
RayScene::RayScene(RayScene&&) noexcept = default;
RayScene& RayScene::operator=(RayScene&&) noexcept = default;

void RayScene::add(const TriangleMesh& mesh, int id)
{
    if (mImpl->committed) throw Error("RayScene::add after commit");
    if (!mesh.triangles.empty()) mImpl->pending.emplace_back(mesh, id);
}

bool RayScene::empty() const { return mImpl->ids.empty() && mImpl->pending.empty(); }

int RayScene::largestId() const
{
    int largest = -1;
    for (int id : mImpl->ids) largest = std::max(largest, id);
    for (const auto& [mesh, id] : mImpl->pending) largest = std::max(largest, id);
    return largest;
}

void RayScene::commit()
{
    Impl& s = *mImpl;
    if (s.committed) return;
    s.committed = true;
    openvdb::BBoxd bounds;
    for (const auto& [mesh, id] : s.pending) bounds.expand(mesh.bounds());
    if (s.pending.empty()) return;
    s.centre = bounds.getCenter();
    s.device = rtcNewDevice("threads=0");
    if (!s.device) throw Error(fmt::format("Embree: cannot create a device (error {})", int(rtcGetDeviceError(nullptr))));
    s.scene = rtcNewScene(s.device);
    rtcSetSceneFlags(s.scene, RTC_SCENE_FLAG_ROBUST); // watertight: rays do not slip between triangles
    rtcSetSceneBuildQuality(s.scene, RTC_BUILD_QUALITY_HIGH);
    for (const auto& [mesh, id] : s.pending) {
        RTCGeometry geometry = rtcNewGeometry(s.device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* vertices = static_cast<float*>(
            rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.points.size()));
        auto* indices = static_cast<unsigned*>(
            rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), mesh.triangles.size()));
        s.check("allocating a mesh");
        for (std::size_t i = 0; i < mesh.points.size(); ++i) {
            const openvdb::Vec3d p = mesh.points[i] - s.centre;
            for (int c = 0; c < 3; ++c) vertices[3 * i + c] = float(p[c]);
        }
        for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
            for (int c = 0; c < 3; ++c) indices[3 * t + c] = mesh.triangles[t][c];
        }
        rtcCommitGeometry(geometry);
        const unsigned geomId = rtcAttachGeometry(s.scene, geometry);
        rtcReleaseGeometry(geometry);
        if (s.ids.size() <= geomId) s.ids.resize(geomId + 1, -1);
        s.ids[geomId] = id;
    }
    s.pending.clear();
    rtcCommitScene(s.scene);
    s.check("building the BVH");
}

std::optional<RayScene::Hit> RayScene::intersect(
    const openvdb::Vec3d& origin, const openvdb::Vec3d& direction, double tNear, double tFar) const
{
    const Impl& s = *mImpl;
    if (!s.scene || !(tFar > tNear)) return std::nullopt;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rayHit{};
    rayHit.ray = s.ray(origin, direction, tNear, tFar);
    rayHit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(s.scene, &context, &rayHit);
    if (rayHit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
    Hit hit;
    hit.distance = rayHit.ray.tfar;
    // Embree's Ng points to the side from which (v0, v1, v2) turn counter-clockwise: outward
    // for our outward-oriented meshes (checked in RaySceneTest).
    openvdb::Vec3d n(rayHit.hit.Ng_x, rayHit.hit.Ng_y, rayHit.hit.Ng_z);
    const double length = n.length();
    n = length > 0.0 ? n / length : -direction;
    hit.backFace = n.dot(direction) > 0.0;
    hit.normal = hit.backFace ? -n : n;
    hit.id = rayHit.hit.geomID < s.ids.size() ? s.ids[rayHit.hit.geomID] : -1;
    return hit;
}

bool RayScene::occluded(const openvdb::Vec3d& origin, const openvdb::Vec3d& direction, double tNear, double tFar) const
{
    const Impl& s = *mImpl;
    if (!s.scene || !(tFar > tNear)) return false;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray = s.ray(origin, direction, tNear, tFar);
    rtcOccluded1(s.scene, &context, &ray);
    return ray.tfar < 0.0f; // Embree sets tfar to −inf when occluded
}

} // namespace vxf
