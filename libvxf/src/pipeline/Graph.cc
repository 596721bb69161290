#include <vxf/pipeline/Graph.h>

#include <vxf/core/Error.h>
#include <vxf/io/AtomicFile.h>
#include <vxf/io/ContentHash.h>
#include <vxf/io/InputFile.h>
#include <vxf/io/JsonDocument.h>
#include <vxf/io/VoxelSetFile.h>
#include <vxf/pipeline/Operators.h>

#include <fmt/format.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

namespace vxf {

/// A pipeline graph is a page of JSON; a file past this is not one.
constexpr std::uintmax_t kMaxGraphBytes = std::uintmax_t(64) << 20;

using nlohmann::json;
namespace fs = std::filesystem;

const json& pipelineSchemaJson()
{
    static const json schema = pipelineSchema();
    return schema;
}

namespace {

/// Parameters naming files whose bytes a node's result depends on.
const char* const kFileParams[] = {"with_file", "from_file", "mesh", "scene"};
/// Parameters naming files a node writes (resolved like the others, not fingerprinted).
const char* const kOutputParams[] = {"image", "png"};

class GraphRunner
{
public:
    GraphRunner(const std::string& path, const std::string& cacheDir, Interrupter* interrupter)
        : mPath(path)
        , mFolder(fs::path(path).parent_path())
        , mCache(cacheDir)
        , mInterrupter(interrupter)
    {
        const json document = parseJsonText(readBoundedFile(path, kMaxGraphBytes, "a pipeline graph"), path);
        static const JsonSchema schema(pipelineSchemaJson(), "schemas/pipeline.schema.json");
        schema.check(document, path);
        mNodes = document["nodes"];
        mOutputs = document["outputs"];
        // Resolve file paths, check parameters and inputs up front: no work before a bad node is found.
        for (auto it = mNodes.begin(); it != mNodes.end(); ++it) {
            json& node = it.value();
            if (node.contains("file")) {
                node["file"] = resolve(node["file"].get<std::string>());
                continue;
            }
            const ops::Operator* op = nullptr;
            try {
                op = &findOperator(node["op"].get<std::string>());
            } catch (const UsageError& e) {
                fail(it.key(), e.what());
            }
            if (op->source && node.contains("input")) fail(it.key(), fmt::format("{} builds its voxel set; it takes no input", op->name));
            if (!op->source && !node.contains("input")) fail(it.key(), fmt::format("{} needs an input node", op->name));
            for (const char* link : {"input", "with"}) {
                if (node.contains(link) && !mNodes.contains(node[link].get<std::string>())) {
                    fail(it.key(), fmt::format("{} '{}' is not a node of the graph", link, node[link].get<std::string>()));
                }
            }
            json params = node.value("params", json::object());
            for (const char* key : kFileParams) {
                if (params.contains(key) && params[key].is_string()) params[key] = resolve(params[key].get<std::string>());
            }
            for (const char* key : kOutputParams) {
                if (params.contains(key) && params[key].is_string()) params[key] = resolve(params[key].get<std::string>());
            }
            try {
                node["params"] = ops::checkArgs(*op, params).json();
            } catch (const UsageError& e) {
                fail(it.key(), e.what());
            }
        }
        for (auto it = mOutputs.begin(); it != mOutputs.end(); ++it) {
            if (!mNodes.contains(it.key()))
                throw InputError(mPath, 0, 0, fmt::format("/outputs/{}: no node named '{}'", it.key(), it.key()));
        }
    }

    GraphReport run()
    {
        fs::create_directories(mCache);
        for (auto it = mOutputs.begin(); it != mOutputs.end(); ++it) {
            const std::string file = ensure(it.key());
            const std::string target = resolve(it.value().get<std::string>());
            if (fs::exists(target) && fileFingerprint(target) == fileFingerprint(file)) {
                mReport.written.emplace_back(it.key(), target + " (unchanged)");
                continue;
            }
            writeAtomically(target, [&](const std::string& tmp) { fs::copy_file(file, tmp, fs::copy_options::overwrite_existing); });
            mReport.written.emplace_back(it.key(), target);
        }
        return mReport;
    }

private:
    [[noreturn]] void fail(const std::string& node, const std::string& what) const
    {
        throw InputError(mPath, 0, 0, fmt::format("/nodes/{}: {}", node, what));
    }

    std::string resolve(const std::string& p) const
    {
        if (p.rfind("builtin:", 0) == 0) return p;
        const fs::path path(p);
        return path.is_absolute() ? path.string() : (mFolder / path).lexically_normal().string();
    }

    /// The node's cache hash: its own definition, its input's hash (recursively) and the program.
    std::string hashOf(const std::string& name)
    {
        if (auto found = mHashes.find(name); found != mHashes.end()) return found->second;
        if (!mVisiting.insert(name).second) fail(name, "is part of a cycle");
        const json& node = mNodes[name];
        json key;
        if (node.contains("file")) {
            key = {{"file", fileFingerprint(node["file"].get<std::string>())}};
        } else {
            key = {{"op", node["op"]}, {"params", node["params"]}};
            for (const char* link : {"input", "with"}) {
                if (node.contains(link)) key[link] = hashOf(node[link].get<std::string>());
            }
            for (const char* param : kFileParams) {
                if (node["params"].contains(param)) key[param] = fileFingerprint(node["params"][param].get<std::string>());
            }
        }
        key["program"] = programFingerprint();
        mVisiting.erase(name);
        return mHashes[name] = hashHex(key.dump());
    }

    /// The cached file holding the node's voxel set, computing it (and its inputs) when missing.
    std::string ensure(const std::string& name)
    {
        if (auto done = mFiles.find(name); done != mFiles.end()) return done->second;
        const std::string file = (mCache / (name + "-" + hashOf(name) + ".vdb")).string();
        const json& node = mNodes[name];
        bool outputsExist = true; // a node writing an image reruns when the image is gone
        for (const char* key : kOutputParams) {
            if (node.contains("params") && node["params"].contains(key))
                outputsExist = outputsExist && fs::exists(node["params"][key].get<std::string>());
        }
        if (fs::exists(file) && outputsExist) {
            mReport.nodes.push_back({name, "reused",
                node.contains("file") ? "the file is unchanged" : "its operator, parameters and inputs are unchanged", "", 0.0});
            return mFiles[name] = file;
        }
        const auto start = std::chrono::steady_clock::now();
        std::string report, why;
        if (node.contains("file")) {
            VoxelSet set = readVoxelSet(node["file"].get<std::string>());
            writeVoxelSet(file, set);
            why = "new or changed file";
            report = node["file"].get<std::string>();
        } else {
            VoxelSet set;
            if (node.contains("input")) set = readVoxelSet(ensure(node["input"].get<std::string>()));
            json params = node["params"];
            if (node.contains("with")) params["with_file"] = ensure(node["with"].get<std::string>());
            const ops::Operator& op = findOperator(node["op"].get<std::string>());
            const ops::Args args(op.name, params);
            ops::OpContext context{set, args, mInterrupter};
            try {
                report = op.run(context);
            } catch (const UsageError& e) {
                fail(name, e.what());
            }
            set.setProvenance("op", json{{"op", op.name}, {"params", node["params"]}, {"node", name}}.dump());
            writeVoxelSet(file, set);
            why = "no cached result for its operator, parameters and inputs";
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        mReport.nodes.push_back({name, "ran", why, report, seconds});
        return mFiles[name] = file;
    }

    std::string mPath;
    fs::path mFolder, mCache;
    Interrupter* mInterrupter;
    json mNodes, mOutputs;
    std::map<std::string, std::string> mHashes, mFiles;
    std::set<std::string> mVisiting;
    GraphReport mReport;
};

} // namespace

GraphReport runGraph(const std::string& path, const std::string& cacheDir, Interrupter* interrupter)
{
    return GraphRunner(path, cacheDir, interrupter).run();
}

void checkGraph(const std::string& path) { GraphRunner(path, "", nullptr); }

void recordStep(
    const std::string& graphPath, const std::string& op, const json& params, const std::string& input, const std::string& output)
{
    json graph = {{"nodes", json::object()}, {"outputs", json::object()}};
    if (fs::exists(graphPath)) graph = parseJsonText(readBoundedFile(graphPath, kMaxGraphBytes, "a pipeline graph"), graphPath);
    const fs::path folder = fs::absolute(graphPath).parent_path();
    const auto relative = [&](const std::string& p) {
        const fs::path abs = fs::absolute(p).lexically_normal();
        const fs::path rel = abs.lexically_relative(folder);
        return (!rel.empty() && *rel.begin() != "..") ? rel.string() : abs.string();
    };
    const std::string in = relative(input), out = relative(output);
    json& nodes = graph["nodes"];
    json& outputs = graph["outputs"];
    // The input: the node that last wrote this file, else a source node reading it.
    std::string inputNode;
    for (auto it = outputs.begin(); it != outputs.end(); ++it) {
        if (it.value() == in) inputNode = it.key();
    }
    const auto fresh = [&](const std::string& stem) {
        std::string name = stem;
        for (int i = 2; nodes.contains(name); ++i) name = fmt::format("{}_{}", stem, i);
        return name;
    };
    if (inputNode.empty()) {
        inputNode = fresh(fs::path(in).stem().string().empty() ? "source" : fs::path(in).stem().string());
        nodes[inputNode] = {{"file", in}};
    }
    const std::string name = fresh(op);
    nodes[name] = {{"op", op}, {"input", inputNode}, {"params", params}};
    // The output file now comes from the new node.
    for (auto it = outputs.begin(); it != outputs.end();) {
        if (it.value() == out) {
            it = outputs.erase(it);
        } else {
            ++it;
        }
    }
    outputs[name] = out;
    writeAtomically(graphPath, [&](const std::string& tmp) {
        std::ofstream file(tmp);
        file << graph.dump(2) << "\n";
        if (!file) throw Error(fmt::format("{}: cannot write", graphPath));
    });
}

} // namespace vxf
