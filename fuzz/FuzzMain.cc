// vxf — libFuzzer's entry point for one target (VXF_FUZZ_TARGET names it; fuzz/CMakeLists.txt).
#include "Targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) { return vxf::fuzz::VXF_FUZZ_TARGET(data, size); }
