// Content hashes (vxf/io/ContentHash.h): FNV-1a as published, files hashed by their bytes, which
// is what vxf run's cache keys are made of.
#include <vxf/io/ContentHash.h>

#include <vxf/core/Error.h>

#include "TestSupport.h"

#include <catch2/catch.hpp>

TEST_CASE("FNV-1a gives the published values and a file is fingerprinted by its bytes", "[io][hash]")
{
    CHECK(vxf::fnv1a("") == 0xcbf29ce484222325ull);
    CHECK(vxf::fnv1a("a") == 0xaf63dc4c8601ec8cull);
    CHECK(vxf::fnv1a("foobar") == 0x85944171f73967e8ull);
    CHECK(vxf::hashHex("a") == "af63dc4c8601ec8c");

    vxf::test::TempDir dir;
    vxf::test::spit(dir.path("a.txt"), "the same bytes");
    vxf::test::spit(dir.path("b.txt"), "the same bytes");
    vxf::test::spit(dir.path("c.txt"), "other bytes");
    CHECK(vxf::fileFingerprint(dir.path("a.txt")) == vxf::fileFingerprint(dir.path("b.txt")));
    CHECK(vxf::fileFingerprint(dir.path("a.txt")) != vxf::fileFingerprint(dir.path("c.txt")));
    CHECK(vxf::fileFingerprint(dir.path("a.txt")) == vxf::hashHex("the same bytes"));
    CHECK(vxf::readFileBytes(dir.path("c.txt")) == "other bytes");
    CHECK(vxf::fileFingerprint("builtin:candle") != vxf::fileFingerprint("builtin:sphere"));
    CHECK_THROWS_WITH(vxf::fileFingerprint(dir.path("missing.txt")), Catch::Contains("missing.txt"));
    CHECK(vxf::programFingerprint().size() >= 1);
    CHECK(vxf::programFingerprint() == vxf::programFingerprint());
}
