// Cancellation and progress (vxf/core/Interrupter.h): a step reports its start and end, a
// cancelled interrupter stops the work with vxf::Interrupted, no interrupter costs nothing.
#include <vxf/core/Interrupter.h>

#include <vxf/core/Error.h>

#include <catch2/catch.hpp>

#include <string>
#include <vector>

namespace {
struct Recording : vxf::Interrupter
{
    std::vector<std::string> events;
    bool cancel = false;
    void start(const char* name) override { events.push_back(std::string("start ") + (name ? name : "")); }
    void end() override { events.push_back("end"); }
    bool wasInterrupted(int percent) override
    {
        events.push_back("at " + std::to_string(percent));
        return cancel;
    }
};
} // namespace

TEST_CASE("a step starts and ends its interrupter, and a cancelled one throws Interrupted", "[core][interrupter]")
{
    Recording recording;
    {
        vxf::InterruptStep step(&recording, "lighting");
        vxf::checkInterrupt(&recording, 40);
    }
    CHECK(recording.events == std::vector<std::string>{"start lighting", "at 40", "end"});

    recording.cancel = true;
    bool ended = false;
    try {
        vxf::InterruptStep step(&recording, "scattering");
        vxf::checkInterrupt(&recording);
    } catch (const vxf::Interrupted&) {
        ended = recording.events.back() == "end"; // the step ended on the way out
    }
    CHECK(ended);

    // No interrupter: nothing to report, never cancelled.
    vxf::InterruptStep none(nullptr, "quiet");
    CHECK_NOTHROW(vxf::checkInterrupt(nullptr, 50));
}
