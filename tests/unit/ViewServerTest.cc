#include <vxf/view/ViewServer.h>

#include "../TestSupport.h"

#include <vxf/io/VoxelSetFile.h>

#include <catch2/catch.hpp>
#include <httplib.h>

#include <thread>

using namespace vxf;

namespace {

/// A server on a free port of 127.0.0.1, serving in a thread until destroyed.
struct RunningServer
{
    view::ViewSession& session;
    view::ViewServer server{session};
    int port = server.bind("127.0.0.1", 0);
    std::thread serving{[this] { server.listen(); }};
    httplib::Client client{"127.0.0.1", port};
    ~RunningServer()
    {
        server.stop();
        serving.join();
    }
};

} // namespace

TEST_CASE("view server: the page, the API, and 4xx with a message for bad requests", "[view]")
{
    test::TempDir dir;
    writeVoxelSet(dir.path("s.vdb"), test::uniformSphere(test::albedoMaterial(4.0, 0.9), 1.0));
    view::ViewSession session(dir.path("s.vdb"));
    RunningServer s{session};

    auto page = s.client.Get("/");
    REQUIRE(page);
    CHECK(page->status == 200);
    CHECK_THAT(page->body, Catch::Contains("importmap") && Catch::Contains("/view.js"));
    auto three = s.client.Get("/three.module.min.js");
    REQUIRE(three);
    CHECK(three->body.size() > 500000); // the vendored library itself, not a link to a CDN
    CHECK_THAT(three->body, Catch::Contains("REVISION"));

    auto info = s.client.Get("/api/info");
    REQUIRE(info);
    const auto grids = nlohmann::json::parse(info->body)["grids"];
    CHECK(grids.size() == 3);

    auto points = s.client.Get("/api/points?grid=direct&budget=500");
    REQUIRE(points);
    CHECK(points->status == 200);
    const std::size_t count = std::stoul(points->get_header_value("X-Vxf-Count"));
    CHECK(count > 0);
    CHECK(count <= 500);
    CHECK(points->body.size() == count * 6 * sizeof(float));

    auto slice = s.client.Get("/api/slice?grid=density&axis=1&index=0");
    REQUIRE(slice);
    CHECK(nlohmann::json::parse(slice->body)["channels"] == 1);

    // Bad requests: a message, nothing changed.
    const auto error = [](const httplib::Result& r) { return nlohmann::json::parse(r->body).value("error", ""); };
    auto unknown = s.client.Get("/api/points?grid=nope");
    CHECK(unknown->status == 400);
    CHECK_THAT(error(unknown), Catch::Contains("no grid 'nope'"));
    auto budget = s.client.Get("/api/points?grid=direct&budget=lots");
    CHECK(budget->status == 400);
    CHECK_THAT(error(budget), Catch::Contains("budget"));
    auto malformed = s.client.Post("/api/apply", "{\"op\": ", "application/json");
    CHECK(malformed->status == 400);
    CHECK_THAT(error(malformed), Catch::Contains("not a JSON object"));
    auto outside = s.client.Post("/api/export", R"({"path": "../../etc/evil.vdb", "mode": "whole"})", "application/json");
    CHECK(outside->status == 400);
    CHECK_THAT(error(outside), Catch::Contains("'..'"));
    auto mode = s.client.Post("/api/export", R"({"path": "x.vdb", "mode": "half"})", "application/json");
    CHECK(mode->status == 400);
    auto missing = s.client.Get("/api/nothing");
    CHECK(missing->status == 404);
    CHECK(session.describe()["steps"].empty());

    // An edit, then undo, through the API.
    auto applied = s.client.Post("/api/apply", R"({"op": "mul", "params": {"grid": "density", "value": 2}})", "application/json");
    REQUIRE(applied);
    CHECK(applied->status == 200);
    CHECK(nlohmann::json::parse(applied->body)["steps"].size() == 1);
    auto undone = s.client.Post("/api/undo", "", "application/json");
    CHECK(nlohmann::json::parse(undone->body)["undone"] == true);
    CHECK(session.describe()["steps"].empty());
}
