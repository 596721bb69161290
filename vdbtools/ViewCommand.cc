// `vxf view FILE.vdb [--port P] [--grid NAME] [--scene S.json] [--no-browser]`: the voxel editor in a browser.
#include "CliSupport.h"
#include "Commands.h"

#include <vxf/view/ViewServer.h>
#include <vxf/view/ViewSession.h>

#include <fmt/format.h>

#include <cctype>
#include <chrono>
#include <cstdlib>
#include <iostream>
#include <thread>

namespace vxf::cli {

namespace {

class ViewCommand : public Command
{
public:
    explicit ViewCommand(CLI::App& parent)
    {
        mApp = parent.add_subcommand("view",
            "The voxel editor in a browser: any grid of a .vdb as points (level of detail on the server) or ray-marched as a "
            "volume, the surface as a mesh, "
            "slices with a value readout; select by box, sphere, value range or brushing, then set a colour or a value, shift "
            "hue, scale saturation and value, add noise, add or remove voxels, or paint with a brush on the first visible voxels; "
            "a history of steps to switch off, move or remove, undo and redo; export the whole set (the grids ticked), the "
            "difference, or the difference with smoothed edges. Every edit is the libvxf operator `vxf op` runs, recorded as a "
            "pipeline `vxf graph` replays. "
            "Serves on 127.0.0.1 until Ctrl-C (or SIGTERM, SIGHUP). Only the printed address opens the editor: it carries "
            "the session's secret, and requests from other web pages or other host names are refused.");
        mApp->add_option("input", mInput, "The .vdb to view and edit (never written: exports go beside it)")->required();
        mApp->add_option("--port", mPort, "Port to listen on (0: any free port)")->check(CLI::Range(0, 65535));
        mApp->add_option("--bind", mHost, "Address to listen on (the default serves this machine only)");
        mApp->add_option("--grid", mGrid, "The grid shown first (default: scatter, illumination, direct, density, or the first)");
        mApp->add_option("--scene", mScene,
                "A scene (camera, lights, material) to render the edited set with from the page: the "
                "scatter stage re-runs where an edit changed what it reads, then the render stage")
            ->check(CLI::ExistingFile);
        mApp->add_flag("--no-browser", mNoBrowser, "Do not open a browser; only print the address");
    }

    void run() override
    {
        view::ViewSession session(mInput);
        const nlohmann::json info = session.describe();
        if (!mGrid.empty()) {
            bool found = false;
            for (const auto& g : info["grids"]) found = found || g["name"] == mGrid;
            if (!found) throw UsageError(fmt::format("--grid: no grid '{}' in {}", mGrid, mInput));
        } else if (info["default_grid"].is_string()) {
            mGrid = info["default_grid"].get<std::string>(); // in the address: the page asks for its points at once
        }
        view::ViewServer server(session, {mScene, "", ""});
        const int port = server.bind(mHost, mPort);
        std::string query; // the grid's name, percent-encoded
        for (const unsigned char c : mGrid) {
            query += std::isalnum(c) || c == '.' || c == '_' || c == '-' ? std::string(1, char(c)) : fmt::format("%{:02X}", c);
        }
        // The token in the address, as notebook servers do: the page passes it on with every request.
        const std::string url = fmt::format("http://{}:{}/?token={}{}", mHost, port, server.token(), query.empty() ? "" : "&grid=" + query);
        std::cout << fmt::format("view: {} at {} (Ctrl-C stops)", session.path(), url) << std::endl;
        std::thread serving([&] { server.listen(); });
        if (!mNoBrowser) {
            // xdg-open returns at once; no browser is not an error (the address is printed above).
            const std::string command = fmt::format("xdg-open '{}' >/dev/null 2>&1 &", url);
            if (std::system(command.c_str()) != 0) warn("could not open a browser: open " + url);
        }
        TerminalProgress interrupt; // Ctrl-C sets it
        while (!interrupt.wasInterrupted()) std::this_thread::sleep_for(std::chrono::milliseconds(100));
        server.stop();
        serving.join();
        std::cout << "view: stopped" << std::endl;
    }

private:
    std::string mInput, mHost = "127.0.0.1", mGrid, mScene;
    int mPort = 8765;
    bool mNoBrowser = false;
};

} // namespace

std::unique_ptr<Command> makeViewCommand(CLI::App& parent) { return std::make_unique<ViewCommand>(parent); }

} // namespace vxf::cli
