// vxf — a voxel set: named OpenVDB grids sharing one transform, plus provenance metadata.
#pragma once

#include <vxf/core/Error.h>

#include <openvdb/openvdb.h>

#include <string>

namespace vxf {

/// File-level metadata keys (schemas/vxf-metadata.schema.json).
inline constexpr const char* kVersionMetaKey = "vxf:version";
inline constexpr const char* kStageMetaKey = "vxf:stage";
inline constexpr const char* kParamsMetaKey = "vxf:params";

/// The version of vxf this library was built as ("0.1.0").
const char* versionString();

/// Named grids of one scene, in file order, sharing one transform, plus file metadata
/// recording the vxf version and the stage and parameters that made them.
///
/// Grids vxf does not know (made by Houdini, Blender, vdb_tool…) are kept as they are,
/// whatever their type or transform; only grids added with put() must match the set's
/// transform. Lookups are by exact name. Copying a VoxelSet shares the grids.
class VoxelSet
{
public:
    VoxelSet();
    explicit VoxelSet(openvdb::math::Transform::Ptr transform);

    /// The shared transform (index → world): the one given to the constructor or
    /// setTransform(), else that of the first grid put().
    const openvdb::math::Transform& transform() const { return *mTransform; }
    openvdb::math::Transform::Ptr transformPtr() const { return mTransform; }
    void setTransform(openvdb::math::Transform::Ptr transform);

    const openvdb::GridPtrVec& grids() const { return mGrids; }
    bool empty() const { return mGrids.empty(); }

    /// The grid named @a name, or null.
    openvdb::GridBase::Ptr find(const std::string& name) const;

    /// The grid named @a name as a @c GridT; throws vxf::Error naming the grid when it is
    /// missing or of another value type.
    template <typename GridT>
    typename GridT::Ptr get(const std::string& name) const;

    /// Add @a grid, replacing a grid of the same name (keeping its position).
    /// The grid adopts (shares) the set's transform when it has an equivalent one; a grid
    /// with a different transform throws vxf::Error (resample it first).
    void put(openvdb::GridBase::Ptr grid);

    /// Add @a grid exactly as it is, with its own transform (for grids read from a file:
    /// grids vxf does not know pass through untouched). Replaces a grid of the same name.
    void putAsIs(openvdb::GridBase::Ptr grid);

    /// Remove the grid named @a name; returns whether there was one.
    bool remove(const std::string& name);

    /// File-level metadata (vxf:version, vxf:stage, vxf:params and anything else read).
    openvdb::MetaMap& metadata() { return mMetadata; }
    const openvdb::MetaMap& metadata() const { return mMetadata; }

    /// Record that @a stage made this set with @a paramsJson (a JSON object as text),
    /// and stamp the vxf version.
    void setProvenance(const std::string& stage, const std::string& paramsJson);
    std::string stage() const; ///< "" when the file carries no vxf provenance
    std::string paramsJson() const; ///< "" when absent

    /// The file this set was read from ("" when made in memory), for error messages.
    const std::string& path() const { return mPath; }
    void setPath(const std::string& path) { mPath = path; }

private:
    openvdb::math::Transform::Ptr mTransform;
    bool mTransformGiven = false;
    openvdb::GridPtrVec mGrids;
    openvdb::MetaMap mMetadata;
    std::string mPath;
};

template <typename GridT>
typename GridT::Ptr VoxelSet::get(const std::string& name) const
{
    openvdb::GridBase::Ptr grid = find(name);
    if (!grid) throw Error("no grid named '" + name + "' in the voxel set");
    typename GridT::Ptr typed = openvdb::gridPtrCast<GridT>(grid);
    if (!typed) {
        throw Error("grid '" + name + "' holds " + grid->valueType() + " values, expected " +
            openvdb::typeNameAsString<typename GridT::ValueType>());
    }
    return typed;
}

} // namespace vxf
