// Frame ranges and frame tokens (vxf/core/Frames.h).
#include <vxf/core/Error.h>
#include <vxf/core/Frames.h>

#include <catch2/catch.hpp>

using vxf::expandFrameTokens;
using vxf::parseFrameRange;

namespace {

std::string rangeError(const std::string& spec)
{
    try {
        parseFrameRange(spec);
    } catch (const vxf::UsageError& e) {
        return e.what();
    }
    return "";
}

} // namespace

TEST_CASE("frame ranges as Houdini's and Blender's render commands take them", "[frames]")
{
    CHECK(parseFrameRange("12") == std::vector<int>{12});
    CHECK(parseFrameRange("1-4") == std::vector<int>{1, 2, 3, 4});
    CHECK(parseFrameRange("1-9:3") == std::vector<int>{1, 4, 7});
    CHECK(parseFrameRange("1-240:2").size() == 120);
    CHECK(parseFrameRange("1,5,10-20:5") == std::vector<int>{1, 5, 10, 15, 20});
    CHECK(parseFrameRange("-2-1") == std::vector<int>{-2, -1, 0, 1});
    CHECK(parseFrameRange("3,1-4") == std::vector<int>{3, 1, 2, 4}); // the order given, each frame once
}

TEST_CASE("a bad frame range names the part at fault", "[frames]")
{
    CHECK_THAT(rangeError("240-1"), Catch::Contains("'240-1': the range runs backwards (240 > 1)"));
    CHECK_THAT(rangeError("1-10:0"), Catch::Contains("the step must be at least 1"));
    CHECK_THAT(rangeError("1-x"), Catch::Contains("'x' is not a whole frame number"));
    CHECK_THAT(rangeError("1,,3"), Catch::Contains("an empty item"));
    CHECK_THAT(rangeError(""), Catch::Contains("no frames given"));
    CHECK_THAT(rangeError("5:2"), Catch::Contains("a step needs a range"));
    CHECK_THAT(rangeError("1-99999999999"), Catch::Contains("out of range"));
    CHECK_THAT(rangeError("1.5"), Catch::Contains("not a whole frame number"));
    CHECK_THAT(rangeError("0-9999999"), Catch::Contains("more than 1000000 frames"));
}

TEST_CASE("frame tokens of Houdini and Blender expand to the frame", "[frames]")
{
    CHECK(expandFrameTokens("smoke.$F4.vdb", 7) == "smoke.0007.vdb");
    CHECK(expandFrameTokens("smoke.${F4}.vdb", 7) == "smoke.0007.vdb");
    CHECK(expandFrameTokens("smoke.$F.vdb", 7) == "smoke.7.vdb");
    CHECK(expandFrameTokens("smoke_${F2}_v$F3.vdb", 7) == "smoke_07_v007.vdb");
    // As in Houdini, a name runs on through letters, digits and '_': $F2_v is another variable.
    CHECK_THROWS_WITH(expandFrameTokens("smoke_$F2_v.vdb", 7), Catch::Contains("$F2_v is a variable vxf cannot expand"));
    CHECK(expandFrameTokens("fluid_data_####.vdb", 12) == "fluid_data_0012.vdb");
    CHECK(expandFrameTokens("a##/b#.vdb", 3) == "a03/b3.vdb");
    CHECK(expandFrameTokens("smoke.$F4.vdb", 12345) == "smoke.12345.vdb");
    CHECK(expandFrameTokens("still.vdb", 3) == "still.vdb");
    CHECK(expandFrameTokens("cost$.vdb", 3) == "cost$.vdb");
    CHECK(vxf::hasFrameTokens("s.$F4.vdb"));
    CHECK_FALSE(vxf::hasFrameTokens("s.vdb"));
    CHECK_FALSE(vxf::hasFrameTokens("$HIP/cost$_$FF.vdb")); // other variables: a still path, as it is
    CHECK(vxf::hasFrameTokens("${F}.vdb"));
    CHECK(vxf::hasFrameTokens("a_$F3"));
    CHECK(vxf::paddedFrame(1) == "0001");
    CHECK(vxf::paddedFrame(-3) == "-003");
    CHECK_THROWS_WITH(expandFrameTokens("$HIP/smoke.vdb", 1), Catch::Contains("$HIP is a variable vxf cannot expand"));
    CHECK_THROWS_WITH(expandFrameTokens("smoke.$FF.vdb", 1), Catch::Contains("$FF is a variable vxf cannot expand"));
    CHECK_THROWS_WITH(expandFrameTokens("smoke.${F4.vdb", 1), Catch::Contains("lacks its '}'"));
}
