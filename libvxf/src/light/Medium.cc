#include <vxf/light/Medium.h>

#include <fmt/format.h>

namespace vxf {

Medium::Medium(const VoxelSet& set, const Material& material)
    : mDensity(set.get<openvdb::FloatGrid>("density"))
    , mMaterial(material)
{
    for (const char* name : {"sigma_a", "sigma_s"}) {
        if (auto grid = set.find(name)) {
            auto typed = openvdb::gridConstPtrCast<openvdb::Vec3SGrid>(grid);
            if (!typed) throw Error(fmt::format("grid '{}' must hold vec3s values, not {}", name, grid->valueType()));
            if (typed->transform() != mDensity->transform()) {
                throw Error(fmt::format("grid '{}' does not share the transform of 'density'", name));
            }
            (std::string(name) == "sigma_a" ? mSigmaA : mSigmaS) = typed;
        }
    }
    mBounds = mDensity->evalActiveVoxelBoundingBox();
}

Medium::Sampler::Sampler(const Medium& medium)
    : mMedium(medium)
    , mDensity(medium.mDensity->getConstAccessor())
{
    if (medium.mSigmaA) mSigmaA.emplace(medium.mSigmaA->getConstAccessor());
    if (medium.mSigmaS) mSigmaS.emplace(medium.mSigmaS->getConstAccessor());
}

openvdb::Vec3d Medium::Sampler::sigmaS(const openvdb::Vec3d& ijk)
{
    if (mSigmaS) return openvdb::Vec3d(openvdb::tools::BoxSampler::sample(*mSigmaS, ijk));
    return mMedium.mMaterial.sigmaS * double(openvdb::tools::BoxSampler::sample(mDensity, ijk));
}

openvdb::Vec3d Medium::Sampler::sigmaT(const openvdb::Vec3d& ijk)
{
    if (!mSigmaA && !mSigmaS) {
        return mMedium.mMaterial.sigmaT() * double(openvdb::tools::BoxSampler::sample(mDensity, ijk));
    }
    const double d = (mSigmaA && mSigmaS) ? 0.0 : double(openvdb::tools::BoxSampler::sample(mDensity, ijk));
    const openvdb::Vec3d a = mSigmaA ? openvdb::Vec3d(openvdb::tools::BoxSampler::sample(*mSigmaA, ijk)) : mMedium.mMaterial.sigmaA * d;
    const openvdb::Vec3d s = mSigmaS ? openvdb::Vec3d(openvdb::tools::BoxSampler::sample(*mSigmaS, ijk)) : mMedium.mMaterial.sigmaS * d;
    return a + s;
}

} // namespace vxf
