#include <vxf/light/Medium.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

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

openvdb::Vec3d Medium::Sampler::sigmaS(const openvdb::Coord& ijk)
{
    if (mSigmaS) return openvdb::Vec3d(mSigmaS->getValue(ijk));
    return mMedium.mMaterial.sigmaS * double(mDensity.getValue(ijk));
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

void recordMaterial(VoxelSet& set, const Material& material)
{
    const auto rgb = [](const openvdb::Vec3d& v) { return nlohmann::json::array({v[0], v[1], v[2]}); };
    const nlohmann::json j = {{"sigma_a", rgb(material.sigmaA)}, {"sigma_s", rgb(material.sigmaS)}};
    set.metadata().insertMeta(kMaterialMetaKey, openvdb::StringMetadata(j.dump()));
}

Material recordedMaterial(const VoxelSet& set)
{
    auto meta = set.metadata().getMetadata<openvdb::StringMetadata>(kMaterialMetaKey);
    if (!meta) throw Error(fmt::format("the voxel set records no material ('{}' metadata); run vxf light first or give --scene", kMaterialMetaKey));
    const auto j = nlohmann::json::parse(meta->value(), nullptr, false);
    Material m;
    try {
        for (int c = 0; c < 3; ++c) {
            m.sigmaA[c] = j.at("sigma_a").at(std::size_t(c)).get<double>();
            m.sigmaS[c] = j.at("sigma_s").at(std::size_t(c)).get<double>();
        }
    } catch (const nlohmann::json::exception&) {
        throw Error(fmt::format("malformed '{}' metadata: {}", kMaterialMetaKey, meta->value()));
    }
    return m;
}

} // namespace vxf
