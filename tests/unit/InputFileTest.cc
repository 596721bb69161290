// What every reader requires of its input (vxf/io/InputFile.h): a regular file, named in the
// error, and bounded in size where a whole file is read at once.
#include <vxf/io/InputFile.h>

#include <vxf/core/Error.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <filesystem>

#include <sys/stat.h>

TEST_CASE("only a regular file is read: folders, FIFOs, missing files and link loops are named", "[io][input]")
{
    vxf::test::TempDir dir;
    vxf::test::spit(dir.path("scene.json"), "{}");
    CHECK_NOTHROW(vxf::requireRegularFile(dir.path("scene.json")));
    CHECK_THROWS_WITH(vxf::requireRegularFile(dir.path("none.json")), Catch::Contains("none.json") && Catch::Contains("no such file"));
    CHECK_THROWS_WITH(vxf::requireRegularFile(dir.root().string()), Catch::Contains("is a folder, not a file"));
    REQUIRE(::mkfifo(dir.path("pipe").c_str(), 0600) == 0);
    CHECK_THROWS_WITH(vxf::requireRegularFile(dir.path("pipe")), Catch::Contains("not a regular file"));
    std::filesystem::create_symlink(dir.path("loop"), dir.path("loop"));
    CHECK_THROWS_WITH(vxf::requireRegularFile(dir.path("loop")), Catch::Contains("a loop of symbolic links"));
}

TEST_CASE("a bounded read returns the bytes and refuses a file over the bound, naming both", "[io][input]")
{
    vxf::test::TempDir dir;
    vxf::test::spit(dir.path("small.json"), "{\"a\": 1}");
    CHECK(vxf::readBoundedFile(dir.path("small.json"), 1 << 20, "a scene") == "{\"a\": 1}");
    vxf::test::spit(dir.path("big.json"), std::string(3 << 20, ' '));
    try {
        vxf::readBoundedFile(dir.path("big.json"), 2 << 20, "a scene");
        FAIL("a 3 MiB file read under a 2 MiB bound");
    } catch (const vxf::InputError& e) {
        CHECK(e.path() == dir.path("big.json"));
        CHECK(std::string(e.what()).find("a scene may have at most 2 MiB") != std::string::npos);
    }
}
