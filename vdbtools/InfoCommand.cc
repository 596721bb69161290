// `vxf info FILE`: like `vdb_print -l`, plus the vxf roles, stage and provenance.
#include "CliSupport.h"
#include "Commands.h"

#include <vxf/core/GridRoles.h>
#include <vxf/core/GridStats.h>
#include <vxf/io/VoxelPlacement.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <iostream>

namespace vxf::cli {

namespace {

nlohmann::json describe(const VoxelSet& set)
{
    nlohmann::json info;
    nlohmann::json metadata = nlohmann::json::object();
    for (auto it = set.metadata().beginMeta(); it != set.metadata().endMeta(); ++it) {
        const std::string& key = it->first;
        if (key == kParamsMetaKey) {
            metadata[key] = nlohmann::json::parse(it->second->str(), nullptr, /*allow_exceptions=*/false);
            if (metadata[key].is_discarded()) metadata[key] = it->second->str();
        } else {
            metadata[key] = it->second->str();
        }
    }
    info["metadata"] = metadata;
    info["grids"] = nlohmann::json::array();
    for (const auto& grid : set.grids()) {
        const GridStats s = gridStats(*grid);
        const GridRole* role = findGridRole(grid->getName());
        nlohmann::json g = {
            {"name", grid->getName()},
            {"value_type", grid->valueType()},
            {"class", openvdb::GridBase::gridClassToString(grid->getGridClass())},
            {"role", role ? role->name : ""},
            {"active_voxels", s.activeVoxels},
            {"leaf_nodes", s.leafNodes},
            {"active_tiles", s.activeTiles},
            {"memory_bytes", s.memoryBytes},
            {"voxel_size", grid->voxelSize()[0]},
            {"shares_transform", grid->transform() == set.transform()},
        };
        if (!s.activeBBox.empty()) {
            g["bbox_min"] = {s.activeBBox.min().x(), s.activeBBox.min().y(), s.activeBBox.min().z()};
            g["bbox_max"] = {s.activeBBox.max().x(), s.activeBBox.max().y(), s.activeBBox.max().z()};
        }
        // Storage: what the file holds (a grid saved as half float reads back as float).
        g["storage"] = grid->isType<openvdb::FloatGrid>() || grid->isType<openvdb::Vec3SGrid>()
            ? (grid->saveFloatAsHalf() ? "half" : "float")
            : grid->valueType();
        const ValueRange range = valueRange(*grid);
        if (range.channels > 0) {
            const auto values = [&](const openvdb::Vec3d& v) {
                return range.channels == 1 ? nlohmann::json(v[0]) : nlohmann::json{v[0], v[1], v[2]};
            };
            g["min"] = values(range.min);
            g["max"] = values(range.max);
            g["mean"] = values(range.mean);
        }
        if (range.nonFinite > 0) g["non_finite_voxels"] = range.nonFinite;
        // Every metadata item of the grid, as its writer left it (Houdini's, Blender's, OpenVDB's own).
        nlohmann::json gridMeta = nlohmann::json::object();
        for (auto it = grid->beginMeta(); it != grid->endMeta(); ++it) gridMeta[it->first] = it->second->str();
        g["metadata"] = gridMeta;
        info["grids"].push_back(g);
    }
    return info;
}

class InfoCommand : public Command
{
public:
    explicit InfoCommand(CLI::App& parent)
    {
        mApp = parent.add_subcommand("info", "List the grids of .vdb files with their vxf roles, stage and provenance.");
        mApp->add_option("files", mFiles, ".vdb files")->required();
        mApp->add_flag("--json", mJson, "Print JSON instead of a table");
        mApp->add_flag("--force", mForce,
            "List a file whose grids no longer match the checksums vxf wrote with them, with a warning "
            "naming the damaged grids, instead of refusing it");
    }

    void run() override
    {
        for (const auto& path : mFiles) {
            std::vector<std::string> damaged, skipped;
            const VoxelSet set = readVoxelSet(path, VoxelSetReadOptions{mForce, &damaged, &skipped, nullptr, nullptr});
            for (const auto& name : damaged) warn(fmt::format("{}: grid '{}' is damaged (its checksum does not match)", path, name));
            for (const auto& grid : skipped) warn(fmt::format("{}: grid {} skipped: not a voxel grid vxf reads", path, grid));
            nlohmann::json info = describe(set);
            if (!skipped.empty()) info["skipped_grids"] = skipped;
            // Where a scene's volume object would put these voxels by default (voxel_placement auto).
            const PlacementChoice placement = resolvePlacement(VoxelPlacement::Auto, path, set.metadata());
            info["voxel_placement"] = {
                {"placement", placement.placement == VoxelPlacement::Cell ? "cell" : "centre"}, {"why", placement.why}};
            if (mJson) {
                std::cout << info.dump(2) << "\n";
                continue;
            }
            const std::string stage = set.stage();
            std::cout << fmt::format(
                "{}: {} grids{}\n", path, set.grids().size(), stage.empty() ? " (no vxf provenance)" : fmt::format(", stage '{}'", stage));
            for (const auto& [key, value] : info["metadata"].items()) {
                std::cout << fmt::format("  {:<14} {}\n", key, value.is_string() ? value.get<std::string>() : value.dump());
            }
            std::cout << fmt::format("  {:<16} {:<6} {:<6} {:<11} {:<15} {:>12} {:>8} {:>6}  {:<34} {:>10}  {:<36} {}\n", "grid", "type",
                "stored", "class", "role", "active", "leaves", "tiles", "active bbox (index)", "memory", "min / mean / max (active)",
                "units");
            for (const auto& g : info["grids"]) {
                std::string bbox = "empty";
                if (g.contains("bbox_min")) {
                    bbox = fmt::format("[{},{},{}]..[{},{},{}]", g["bbox_min"][0].get<int>(), g["bbox_min"][1].get<int>(),
                        g["bbox_min"][2].get<int>(), g["bbox_max"][0].get<int>(), g["bbox_max"][1].get<int>(), g["bbox_max"][2].get<int>());
                }
                const std::string role = g["role"].get<std::string>();
                std::string range = "-";
                if (g.contains("min")) {
                    // Grey for one channel; the largest channel's for a vector (its mean the channels' mean).
                    const auto grey = [](const nlohmann::json& v, bool largest) {
                        if (v.is_number()) return v.get<double>();
                        const double a = v[0].get<double>(), b = v[1].get<double>(), c = v[2].get<double>();
                        return largest ? std::max({a, b, c}) : (a + b + c) / 3.0;
                    };
                    range = fmt::format("{:.4g} / {:.4g} / {:.4g}",
                        g["min"].is_number() ? g["min"].get<double>()
                                             : std::min({g["min"][0].get<double>(), g["min"][1].get<double>(), g["min"][2].get<double>()}),
                        grey(g["mean"], false), grey(g["max"], true));
                }
                if (g.contains("non_finite_voxels")) range += fmt::format(" ({} non-finite)", g["non_finite_voxels"].get<std::uint64_t>());
                std::cout << fmt::format("  {:<16} {:<6} {:<6} {:<11} {:<15} {:>12} {:>8} {:>6}  {:<34} {:>10}  {:<36} {}{}\n",
                    g["name"].get<std::string>(), g["value_type"].get<std::string>(), g["storage"].get<std::string>(),
                    g["class"].get<std::string>(), role.empty() ? "(passed through)" : role, g["active_voxels"].get<std::uint64_t>(),
                    g["leaf_nodes"].get<std::uint64_t>(), g["active_tiles"].get<std::uint64_t>(), bbox,
                    formatBytes(g["memory_bytes"].get<std::uint64_t>()), range, g["metadata"].value(kUnitsMetaKey, std::string()),
                    g["shares_transform"].get<bool>() ? "" : "  (own transform)");
            }
            std::cout << fmt::format("  voxel size {:.6g}, transform {}; voxels placed by {} as a volume object ({})\n",
                set.transform().voxelSize()[0], set.transform().baseMap()->type(),
                placement.placement == VoxelPlacement::Cell ? "cell (Blender, Cycles)" : "centre (OpenVDB, Houdini)", placement.why);
        }
    }

private:
    std::vector<std::string> mFiles;
    bool mJson = false, mForce = false;
};

} // namespace

std::unique_ptr<Command> makeInfoCommand(CLI::App& parent) { return std::make_unique<InfoCommand>(parent); }

} // namespace vxf::cli
