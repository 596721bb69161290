#include <vxf/core/VoxelSet.h>

#include <algorithm>

namespace vxf {

const char* versionString() { return VXF_VERSION_STRING; }

VoxelSet::VoxelSet()
    : mTransform(openvdb::math::Transform::createLinearTransform(1.0))
{
}

VoxelSet::VoxelSet(openvdb::math::Transform::Ptr transform)
    : mTransform(std::move(transform))
    , mTransformGiven(true)
{
    if (!mTransform) throw Error("voxel set: null transform");
}

void VoxelSet::setTransform(openvdb::math::Transform::Ptr transform)
{
    if (!transform) throw Error("voxel set: null transform");
    mTransform = std::move(transform);
    mTransformGiven = true;
}

openvdb::GridBase::Ptr VoxelSet::find(const std::string& name) const
{
    for (const auto& grid : mGrids) {
        if (grid->getName() == name) return grid;
    }
    return nullptr;
}

void VoxelSet::put(openvdb::GridBase::Ptr grid)
{
    if (!grid) throw Error("voxel set: null grid");
    if (grid->getName().empty()) throw Error("voxel set: grids must be named");
    if (grid->transform() != *mTransform) {
        if (mGrids.empty() && !mTransformGiven) { // the first grid defines the transform
            mTransform = grid->transformPtr();
        } else {
            throw Error("grid '" + grid->getName() + "' does not share the voxel set's transform (voxel size " +
                std::to_string(grid->voxelSize()[0]) + " vs " + std::to_string(mTransform->voxelSize()[0]) + "); resample it first");
        }
    }
    grid->setTransform(mTransform);
    putAsIs(grid);
}

void VoxelSet::putAsIs(openvdb::GridBase::Ptr grid)
{
    if (!grid) throw Error("voxel set: null grid");
    auto same =
        std::find_if(mGrids.begin(), mGrids.end(), [&](const openvdb::GridBase::Ptr& g) { return g->getName() == grid->getName(); });
    if (same != mGrids.end()) {
        *same = grid;
    } else {
        mGrids.push_back(grid);
    }
}

bool VoxelSet::remove(const std::string& name)
{
    auto it = std::remove_if(mGrids.begin(), mGrids.end(), [&](const openvdb::GridBase::Ptr& g) { return g->getName() == name; });
    const bool removed = it != mGrids.end();
    mGrids.erase(it, mGrids.end());
    return removed;
}

void VoxelSet::setProvenance(const std::string& stage, const std::string& paramsJson)
{
    mMetadata.insertMeta(kVersionMetaKey, openvdb::StringMetadata(versionString()));
    mMetadata.insertMeta(kStageMetaKey, openvdb::StringMetadata(stage));
    mMetadata.insertMeta(kParamsMetaKey, openvdb::StringMetadata(paramsJson));
}

std::string VoxelSet::stage() const
{
    auto meta = mMetadata.getMetadata<openvdb::StringMetadata>(kStageMetaKey);
    return meta ? meta->value() : std::string();
}

std::string VoxelSet::paramsJson() const
{
    auto meta = mMetadata.getMetadata<openvdb::StringMetadata>(kParamsMetaKey);
    return meta ? meta->value() : std::string();
}

} // namespace vxf
