#include <vxf/ops/Fill.h>

#include "Dispatch.h"
#include "Topology.h"

#include <vector>

namespace vxf::ops {

openvdb::Index64 fill(openvdb::GridBase& grid, const FillOptions& options, Interrupter* interrupter)
{
    if (!options.region) throw UsageError("blur_special: needs a region grid (where values are wanted)");
    if (options.region->transform() != grid.transform()) {
        throw UsageError(
            fmt::format("blur_special: region '{}' does not share grid '{}''s transform", options.region->getName(), grid.getName()));
    }
    InterruptStep step(interrupter, "filling");
    return detail::dispatch(grid, "blur_special", [&](auto& g) -> openvdb::Index64 {
        using GridT = std::decay_t<decltype(g)>;
        using ValueT = typename GridT::ValueType;
        // Free voxels: in the region, not fixed.
        openvdb::MaskTree fixed;
        fixed.topologyUnion(g.tree());
        if (options.selection) fixed.topologyDifference(options.selection->tree());
        const openvdb::MaskTree::Ptr regionTopology = detail::activeTopology(*options.region);
        openvdb::MaskTree& free = *regionTopology;
        free.topologyDifference(fixed);
        free.voxelizeActiveTiles();

        const openvdb::Index64 total = free.activeVoxelCount();
        if (total == 0) return 0;
        openvdb::MaskTree known(fixed);
        auto values = g.getAccessor();
        const openvdb::Coord faces[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
        const auto meanOfKnown = [&](const openvdb::MaskTree& k, const openvdb::Coord& c, ValueT& out) {
            ValueT sum = openvdb::zeroVal<ValueT>();
            int n = 0;
            for (const auto& f : faces) {
                const openvdb::Coord q = c + f;
                if (!k.isValueOn(q)) continue;
                sum = sum + values.getValue(q);
                ++n;
            }
            if (n == 0) return false;
            out = sum * (1.0f / float(n));
            return true;
        };

        // Flood, layer by layer from the fixed voxels (breadth first; each layer computed from
        // the layers before it, in a fixed order, so the result is deterministic).
        std::vector<openvdb::Coord> frontier;
        for (auto it = free.cbeginValueOn(); it; ++it) {
            for (const auto& f : faces) {
                if (known.isValueOn(it.getCoord() + f)) {
                    frontier.push_back(it.getCoord());
                    break;
                }
            }
        }
        std::vector<std::pair<openvdb::Coord, ValueT>> layer;
        while (!frontier.empty()) {
            checkInterrupt(interrupter);
            layer.clear();
            for (const auto& c : frontier) {
                ValueT v;
                if (meanOfKnown(known, c, v)) layer.emplace_back(c, v);
            }
            std::vector<openvdb::Coord> next;
            for (const auto& [c, v] : layer) {
                values.setValue(c, v);
                known.setValueOn(c);
                free.setValueOff(c);
            }
            for (const auto& [c, v] : layer) {
                for (const auto& f : faces) {
                    const openvdb::Coord q = c + f;
                    if (free.isValueOn(q)) {
                        free.setValueOff(q); // queued once
                        next.push_back(q);
                    }
                }
            }
            frontier.swap(next);
        }
        // Smooth the filled voxels only (Jacobi: every pass reads the previous one).
        std::vector<openvdb::Coord> filled;
        for (auto it = known.cbeginValueOn(); it; ++it) {
            if (!fixed.isValueOn(it.getCoord())) filled.push_back(it.getCoord());
        }
        std::vector<ValueT> next(filled.size());
        for (int pass = 0; pass < options.smoothing; ++pass) {
            for (std::size_t i = 0; i < filled.size(); ++i) {
                if (!meanOfKnown(known, filled[i], next[i])) next[i] = values.getValue(filled[i]);
            }
            for (std::size_t i = 0; i < filled.size(); ++i) values.setValue(filled[i], next[i]);
        }
        return filled.size();
    });
}

} // namespace vxf::ops
