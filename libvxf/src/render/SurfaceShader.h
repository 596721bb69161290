// vxf — the surface term at a camera ray's hit (private to render/).
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

} // namespace vxf::detail
