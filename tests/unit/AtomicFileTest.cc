#include <vxf/io/AtomicFile.h>

#include <vxf/core/Error.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <fstream>

using vxf::test::TempDir;

TEST_CASE("atomic writes leave all or nothing", "[io][atomic]")
{
    TempDir dir;
    const std::string target = dir.path("out.txt");

    vxf::writeAtomically(target, [](const std::string& tmp) { std::ofstream(tmp) << "first"; });
    CHECK(vxf::test::slurp(target) == "first");

    SECTION("a failing writer keeps the old file and leaves no temporary")
    {
        CHECK_THROWS_WITH(vxf::writeAtomically(target,
                              [](const std::string& tmp) {
                                  std::ofstream(tmp) << "half";
                                  throw vxf::Error("disk on fire");
                              }),
            "disk on fire");
        CHECK(vxf::test::slurp(target) == "first");
        CHECK(std::distance(std::filesystem::directory_iterator(dir.root()), {}) == 1);
    }
    SECTION("a failing writer of a new file leaves no file")
    {
        const std::string fresh = dir.path("new.txt");
        CHECK_THROWS(vxf::writeAtomically(fresh, [](const std::string&) { throw vxf::Error("no"); }));
        CHECK_FALSE(std::filesystem::exists(fresh));
    }
    SECTION("a missing directory is named")
    {
        CHECK_THROWS_WITH(vxf::writeAtomically(dir.path("nope/out.txt"), [](const std::string&) {}),
            Catch::Contains("directory") && Catch::Contains("does not exist"));
    }
}
