// vxf — the local HTTP server of `vxf view`: its page, and ViewSession's calls as requests.
#pragma once

#include <vxf/view/ViewSession.h>

#include <memory>
#include <string>

namespace vxf::view {

/// Serves the editor page (embedded: the page, its script and three.js, no network needed) and
/// a JSON/binary API over one ViewSession (cpp-httplib). Requests:
///
/// | request | answer |
/// |---|---|
/// | GET /api/info | ViewSession::describe(), and "scene" (the scene renders use, or null) |
/// | GET /api/points?grid=G&budget=N | points: binary little-endian float32, per point x y z then 1 or 3 values; headers X-Vxf-Count, X-Vxf-Channels, X-Vxf-Cell-Voxels, X-Vxf-Cell-Size, X-Vxf-Min, X-Vxf-Max, X-Vxf-Active |
/// | GET /api/slice?grid=G&axis=A&index=I | JSON: axis, index, origin, width, height, channels, values (null where inactive) |
/// | GET /api/mesh?adaptivity=F | binary: uint32 vertex count, uint32 triangle count, float32 positions, uint32 indices |
/// | GET /api/pipeline?output=PATH | ViewSession::pipeline() |
/// | POST /api/apply {"op", "params"} | {"report", "steps"} |
/// | POST /api/undo | {"undone", "steps"} |
/// | POST /api/export {"path", "mode": whole/diff/smoothed, "grid", "smooth"} | {"written"} |
/// | POST /api/render {"width", "height"} | ViewSession::render with the options' scene: {"ran", "seconds"} |
/// | GET /api/image | the last render's PNG |
///
/// Bad requests (unknown grid or operator, malformed JSON, a path outside the served file's
/// folder) are 400 with {"error": message} and change nothing; unknown paths 404.
struct ViewServerOptions
{
    std::string scene;        ///< a scene file for POST /api/render ("": renders refused)
    std::string renderFolder; ///< where renders are written ("": a folder under the system's temp dir, removed at the end)
};

class ViewServer
{
public:
    explicit ViewServer(ViewSession& session, ViewServerOptions options = {});
    ~ViewServer();
    ViewServer(const ViewServer&) = delete;
    ViewServer& operator=(const ViewServer&) = delete;

    /// Bind to @a host:@a port (0: any free port); returns the port. vxf::Error when it cannot.
    int bind(const std::string& host, int port);
    /// Serve until stop() (blocks).
    void listen();
    /// Stop listen() (from another thread or a signal handler's thread).
    void stop();

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace vxf::view
