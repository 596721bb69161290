#include <vxf/core/MemoryBudget.h>

#include <vxf/core/Error.h>

#include <catch2/catch.hpp>

#include <vector>

TEST_CASE("memory sizes read as users write them, and anything else is a usage error naming it", "[core][memory]")
{
    CHECK(vxf::parseMemorySize("8G") == (std::uint64_t(8) << 30));
    CHECK(vxf::parseMemorySize("8GiB") == (std::uint64_t(8) << 30));
    CHECK(vxf::parseMemorySize("8gb") == (std::uint64_t(8) << 30));
    CHECK(vxf::parseMemorySize("512M") == (std::uint64_t(512) << 20));
    CHECK(vxf::parseMemorySize("1.5G") == (std::uint64_t(3) << 29));
    CHECK(vxf::parseMemorySize("64K") == 65536);
    CHECK(vxf::parseMemorySize("2T") == (std::uint64_t(2) << 40));
    CHECK(vxf::parseMemorySize("1000") == 1000);
    for (const char* bad : {"", "G", "abc", "-1G", "0", "8X", "8 G", "nan", "1e30T"}) {
        CAPTURE(bad);
        CHECK_THROWS_AS(vxf::parseMemorySize(bad), vxf::UsageError);
        CHECK_THROWS_WITH(vxf::parseMemorySize(bad), Catch::Contains(std::string("'") + bad + "' is not a memory size"));
    }
}

TEST_CASE("the default budget counts what the process already holds: a stage's estimate includes its input", "[core][memory]")
{
    // A stage asks for the budget after it has read its input; the estimate it checks is of the
    // whole process. What is available then is on top of what the process holds.
    constexpr std::uint64_t kHeld = std::uint64_t(512) << 20;
    const std::vector<char> held(kHeld, 1); // every page written
    CHECK(vxf::residentMemory() >= kHeld);
    vxf::setMemoryBudget(0);
    const std::uint64_t budget = vxf::memoryBudget();
    const std::uint64_t available = vxf::availableMemory(); // after: other processes move it by far less than kHeld / 2
    CHECK(budget >= available + kHeld / 2);
    CHECK(held.back() == 1);
    vxf::setMemoryBudget(0);
}

TEST_CASE("a stage's estimate above the budget stops it with the estimate, the budget and where the budget came from", "[core][memory]")
{
    CHECK(vxf::availableMemory() > 0); // Linux: /proc/meminfo
    vxf::setMemoryBudget(0);
    CHECK(vxf::memoryBudget() > 0);
    const vxf::MemoryEstimate estimate = vxf::stageMemory(vxf::kStageFixedBytes, 1e7, 200.0, 1e6, 160.0);
    CHECK(estimate.bytes == Approx(vxf::kStageFixedBytes + 2e9 + 1.6e8));
    CHECK_THAT(estimate.how, Catch::Contains("1e+07 voxels × 200 bytes") && Catch::Contains("1e+06 pixels × 160 bytes"));

    vxf::setMemoryBudget(std::uint64_t(1) << 30);
    CHECK(vxf::memoryBudget() == std::uint64_t(1) << 30);
    CHECK_THROWS_WITH(vxf::requireMemory("light", estimate),
        Catch::StartsWith("light needs about 2.1 GiB at its peak (1e+07 voxels × 200 bytes") &&
            Catch::Contains("more than the memory budget of 1.0 GiB (--max-memory)"));
    CHECK_NOTHROW(vxf::requireMemory("light", vxf::stageMemory(vxf::kStageFixedBytes, 1e6, 200.0)));
    // An estimate past every number (a mesh whose area overflowed) is refused too, never compared as NaN.
    CHECK_THROWS_AS(vxf::requireMemory("voxelize", vxf::MemoryEstimate{std::numeric_limits<double>::infinity(), "x"}), vxf::Error);
    CHECK_THROWS_AS(vxf::requireMemory("voxelize", vxf::MemoryEstimate{std::nan(""), "x"}), vxf::Error);
    vxf::setMemoryBudget(0); // the default again, for the tests after this one
    CHECK_THROWS_WITH(
        vxf::requireMemory("render", vxf::MemoryEstimate{1e30, "x"}), Catch::Contains("the memory this machine has available"));
}
