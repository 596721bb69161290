// `vxf op NAME IN.vdb -o OUT.vdb [--PARAM VALUE …] [--record PIPELINE.json]`, generated from the
// operator registry; `vxf op --markdown` and `vxf op --schema` print the generated documents.
#include "CliSupport.h"
#include "Commands.h"
#include "OperatorOptions.h"

#include <vxf/io/VoxelSetFile.h>
#include <vxf/pipeline/Operators.h>
#include <vxf/pipeline/Graph.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <iostream>
#include <map>

namespace vxf::cli {

namespace {

class OpCommand : public Command
{
public:
    explicit OpCommand(CLI::App& parent)
    {
        mApp = parent.add_subcommand("op",
            "Artist operators on the grids of a voxel set (the thesis's canvas). `vxf op NAME --help` shows one; every "
            "operator keeps sparsity, leaves the file's other grids untouched and records its provenance.");
        mApp->require_subcommand(0, 1);
        mApp->add_flag("--markdown", mMarkdown, "Print the operator table (as in the README) and exit");
        mApp->add_flag("--schema", mSchema, "Print schemas/pipeline.schema.json (generated from the operators) and exit");
        for (const auto& op : operators()) {
            CLI::App* sub = mApp->add_subcommand(op.name, op.summary);
            sub->allow_extras(); // unknown parameters are reported below, naming the operator
            Invocation& call = mCalls[op.name];
            call.app = sub;
            sub->add_option("input", call.input, "Input .vdb")->required();
            sub->add_option("-o,--output", call.output, "Output .vdb (may be the input)")->required()->check(OutputFile);
            sub->add_option("--record", call.record, "Append this command as a node to a pipeline graph (vxf graph)")->check(OutputFile);
            sub->add_flag("--half", call.write.half, "Store floats as 16-bit halves");
            call.params = std::make_unique<OperatorOptions>(*sub, op, false);
        }
    }

    void run() override
    {
        if (mMarkdown) {
            std::cout << operatorTableMarkdown();
            return;
        }
        if (mSchema) {
            std::cout << pipelineSchema().dump(2) << "\n";
            return;
        }
        for (auto& [name, call] : mCalls) {
            if (call.app->parsed()) return runOperator(findOperator(name), call);
        }
        throw UsageError("name an operator (vxf op --help lists them)");
    }

private:
    struct Invocation
    {
        CLI::App* app = nullptr;
        std::string input, output, record;
        std::unique_ptr<OperatorOptions> params; ///< the operator's parameters as options
        VoxelSetWriteOptions write;
    };

    void runOperator(const ops::Operator& op, const Invocation& call)
    {
        const auto start = std::chrono::steady_clock::now();
        if (!call.app->remaining().empty()) {
            std::string known;
            for (const auto& p : op.params) known += (known.empty() ? "" : ", ") + p.name;
            throw UsageError(
                fmt::format("{}: unknown parameter or extra argument '{}' (it takes: {})", op.name, call.app->remaining().front(), known));
        }
        // (-o may be the input: an operator edits a file in place, read whole before it is replaced.)
        refuseOverwrites({{"the input", call.input}}, {{"--record", call.record}});
        refuseOverwrites({}, {{"-o", call.output}, {"--record", call.record}});
        if (!call.record.empty() && sameFile(call.input, call.output)) {
            throw UsageError(fmt::format("{}: --record needs an output file other than the input (a graph replaying it would "
                                         "read its own output)",
                op.name));
        }
        nlohmann::json params = call.params->given();
        const ops::Args args = call.params->args();
        TerminalProgress progress;
        VoxelSet set = readVoxelSet(call.input);
        ops::OpContext context{set, args, &progress};
        const std::string report = op.run(context);
        set.setProvenance("op", nlohmann::json{{"op", op.name}, {"params", args.json()}, {"input", call.input}}.dump());
        writeVoxelSet(call.output, set, call.write);
        if (!call.record.empty()) {
            // File parameters are stored as given, relative to where the command ran: make them absolute.
            for (const char* key : {"with_file", "from_file"}) {
                if (params.contains(key)) params[key] = std::filesystem::absolute(params[key].get<std::string>()).string();
            }
            recordStep(call.record, op.name, params, call.input, call.output);
        }
        std::cout << fmt::format("{}: {} -> {} in {:.3f} s{}\n", op.name, report, call.output, secondsSince(start),
            call.record.empty() ? "" : " (recorded in " + call.record + ")");
    }

    bool mMarkdown = false, mSchema = false;
    std::map<std::string, Invocation> mCalls;
};

class GraphCommand : public Command
{
public:
    explicit GraphCommand(CLI::App& parent)
    {
        mApp = parent.add_subcommand("graph",
            "Run a pipeline graph (schemas/pipeline.schema.json): only the nodes its outputs need, each cached by a hash "
            "of its operator, parameters and inputs, so a second run does no work and a changed parameter recomputes "
            "only what lies downstream.");
        mApp->add_option("pipeline", mPipeline, "Pipeline .json")->required()->check(CLI::ExistingFile);
        mApp->add_option("--cache", mCache, "Cache folder (default: vxf-cache beside the pipeline)");
    }

    void run() override
    {
        const auto start = std::chrono::steady_clock::now();
        const std::string cache = mCache.empty() ? (std::filesystem::path(mPipeline).parent_path() / "vxf-cache").string() : mCache;
        TerminalProgress progress;
        const GraphReport report = runGraph(mPipeline, cache, &progress);
        for (const auto& n : report.nodes) {
            std::cout << fmt::format(
                "  {:<16} {:<7} {:>7.3f} s  {}{}\n", n.node, n.action, n.seconds, n.why, n.report.empty() ? "" : ": " + n.report);
        }
        for (const auto& [node, file] : report.written) std::cout << fmt::format("  wrote {} ({})\n", file, node);
        std::cout << fmt::format("graph {} in {:.2f} s\n", mPipeline, secondsSince(start));
    }

private:
    std::string mPipeline, mCache;
};

} // namespace

std::unique_ptr<Command> makeOpCommand(CLI::App& parent) { return std::make_unique<OpCommand>(parent); }
std::unique_ptr<Command> makeGraphCommand(CLI::App& parent) { return std::make_unique<GraphCommand>(parent); }

} // namespace vxf::cli
