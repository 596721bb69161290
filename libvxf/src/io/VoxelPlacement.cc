#include <vxf/io/VoxelPlacement.h>

#include <filesystem>
#include <regex>

namespace vxf {

namespace {

std::string creatorOf(const openvdb::MetaMap& meta)
{
    const auto creator = meta.getMetadata<openvdb::StringMetadata>("creator");
    return creator ? creator->value() : std::string();
}

bool anyVxfMetadata(const openvdb::MetaMap& meta)
{
    for (auto it = meta.beginMeta(); it != meta.endMeta(); ++it) {
        if (it->first.rfind("vxf", 0) == 0) return true;
    }
    return false;
}

} // namespace

PlacementChoice resolvePlacement(VoxelPlacement requested, const std::string& path, const openvdb::MetaMap& fileMeta)
{
    if (requested == VoxelPlacement::Centre) return {VoxelPlacement::Centre, "voxel_placement \"centre\""};
    if (requested == VoxelPlacement::Cell) return {VoxelPlacement::Cell, "voxel_placement \"cell\""};
    const std::string creator = creatorOf(fileMeta);
    if (creator.find("Blender") != std::string::npos) return {VoxelPlacement::Cell, "its creator metadata names Blender"};
    if (!creator.empty()) return {VoxelPlacement::Centre, "written by " + creator};
    if (anyVxfMetadata(fileMeta)) return {VoxelPlacement::Centre, "written by vxf"};
    const std::filesystem::path p(path);
    const std::string name = p.filename().string();
    static const std::regex mantaflow(R"(fluid_(data|noise)_-?\d+\.vdb)");
    if (std::regex_match(name, mantaflow)) return {VoxelPlacement::Cell, "a Blender Mantaflow cache file (" + name + ")"};
    static const std::regex bakeBlob(R"(\d+_\d+_file_\d+\.vdb)");
    const std::filesystem::path folder = p.parent_path();
    std::error_code ignored;
    if (std::regex_match(name, bakeBlob) && folder.filename() == "blobs" &&
        std::filesystem::is_directory(folder.parent_path() / "meta", ignored)) {
        return {VoxelPlacement::Cell, "a Blender geometry-nodes bake (blobs/ beside meta/)"};
    }
    return {VoxelPlacement::Centre, "no writer recognised: OpenVDB's convention"};
}

openvdb::math::Transform::Ptr placedTransform(const openvdb::math::Transform& transform, VoxelPlacement placement)
{
    openvdb::math::Transform::Ptr placed = transform.copy();
    if (placement == VoxelPlacement::Cell) placed->preTranslate(openvdb::Vec3d(0.5));
    return placed;
}

} // namespace vxf
