#include "Targets.h"

#include <vxf/core/Error.h>
#include <vxf/core/GridStats.h>
#include <vxf/io/MeshFile.h>
#include <vxf/io/VoxelSetFile.h>
#include <vxf/io/VxfText.h>
#include <vxf/pipeline/Operators.h>
#include <vxf/pipeline/Graph.h>
#include <vxf/pipeline/SceneFile.h>

#include <nlohmann/json.hpp>
#include <openvdb/openvdb.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <unistd.h>

namespace vxf::fuzz {

namespace {

namespace fs = std::filesystem;

/// A folder of this process's own for the files the readers take (they read paths, as the
/// command line gives them), removed at exit.
class Scratch
{
public:
    Scratch()
    {
        std::string pattern = (fs::temp_directory_path() / "vxf-fuzz-XXXXXX").string();
        if (!::mkdtemp(pattern.data())) std::abort();
        mDir = pattern;
    }
    ~Scratch()
    {
        std::error_code ignored;
        fs::remove_all(mDir, ignored);
    }

    /// @a data written to the file @a name in the folder; its path.
    std::string write(const std::string& name, const std::uint8_t* data, std::size_t size) const
    {
        const std::string path = (mDir / name).string();
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
        if (!out) std::abort(); // the fuzzer's own failure, not the input's
        return path;
    }

private:
    fs::path mDir;
};

const Scratch& scratch()
{
    static const Scratch folder;
    return folder;
}

/// Run @a read; a vxf::Error is the clear error bad input must give, anything else escapes.
template <typename Read>
int expectingErrors(const Read& read)
{
    try {
        read();
    } catch (const Error&) {
    }
    return 0;
}

} // namespace

int vxfText(const std::uint8_t* data, std::size_t size)
{
    const std::string path = scratch().write("input.vxf", data, size);
    return expectingErrors([&] { readVxfText(path); });
}

int mesh(const std::uint8_t* data, std::size_t size)
{
    if (size == 0) return 0;
    static const char* const kExtensions[] = {"obj", "ply", "off", "stl"};
    const std::string path = scratch().write(std::string("input.") + kExtensions[data[0] % 4], data + 1, size - 1);
    return expectingErrors([&] {
        MeshReport report;
        readMesh(path, {}, &report);
    });
}

int scene(const std::uint8_t* data, std::size_t size)
{
    const std::string text(reinterpret_cast<const char*>(data), size);
    return expectingErrors([&] { parseScene(text, (fs::temp_directory_path() / "scene.json").string()); });
}

int pipeline(const std::uint8_t* data, std::size_t size)
{
    const std::string path = scratch().write("pipeline.json", data, size);
    return expectingErrors([&] { checkGraph(path); });
}

int vdbInfo(const std::uint8_t* data, std::size_t size)
{
    static const bool initialized = (openvdb::initialize(), true);
    (void)initialized;
    const std::string path = scratch().write("input.vdb", data, size);
    return expectingErrors([&] {
        const VoxelSet set = readVoxelSet(path);
        for (auto it = set.metadata().beginMeta(); it != set.metadata().endMeta(); ++it) (void)it->second->str();
        for (const auto& grid : set.grids()) {
            (void)gridStats(*grid);
            for (auto it = grid->beginMeta(); it != grid->endMeta(); ++it) (void)it->second->str();
        }
    });
}

int opParams(const std::uint8_t* data, std::size_t size)
{
    if (size < 2) return 0;
    const auto& all = vxf::operators();
    const ops::Operator& op = all[data[0] % all.size()];
    const std::string rest(reinterpret_cast<const char*>(data + 2), size - 2);
    const std::size_t newline = rest.find('\n');
    return expectingErrors([&] {
        if (!op.params.empty()) ops::parseParamText(op, op.params[data[1] % op.params.size()], rest.substr(0, newline));
        if (newline == std::string::npos) return;
        const nlohmann::json values = nlohmann::json::parse(rest.substr(newline + 1), nullptr, /*allow_exceptions=*/false);
        if (!values.is_discarded()) ops::checkArgs(op, values);
    });
}

const std::vector<NamedTarget>& targets()
{
    static const std::vector<NamedTarget> all = {
        {"vxf_text", vxfText}, {"mesh", mesh}, {"scene", scene}, {"pipeline", pipeline}, {"vdb_info", vdbInfo}, {"op_params", opParams}};
    return all;
}

} // namespace vxf::fuzz
