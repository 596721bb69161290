// vxf — progress reporting and cancellation for long operations.
#pragma once

#include <vxf/core/Error.h>

#include <openvdb/util/NullInterrupter.h>

namespace vxf {

/// libvxf reports progress and polls for cancellation through OpenVDB's interrupter
/// interface, so the same object can be handed to OpenVDB tools: `start(name)` opens a
/// step, `wasInterrupted(percent)` reports progress (thread-safe), `end()` closes it.
using Interrupter = openvdb::util::NullInterrupter;

/// Throw vxf::Interrupted when @a interrupter (may be null) asks to stop.
inline void checkInterrupt(Interrupter* interrupter, int percent = -1)
{
    if (interrupter && interrupter->wasInterrupted(percent)) throw Interrupted();
}

/// RAII step: calls start(name) now and end() on scope exit.
class InterruptStep
{
public:
    InterruptStep(Interrupter* interrupter, const char* name)
        : mInterrupter(interrupter)
    {
        if (mInterrupter) mInterrupter->start(name);
    }
    ~InterruptStep()
    {
        if (mInterrupter) mInterrupter->end();
    }
    InterruptStep(const InterruptStep&) = delete;
    InterruptStep& operator=(const InterruptStep&) = delete;

private:
    Interrupter* mInterrupter;
};

} // namespace vxf
