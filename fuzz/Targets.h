// vxf — fuzz targets: each reads arbitrary bytes as one kind of input vxf takes from other
// people and other tools, through the same libvxf functions the command line calls.
//
// A target returns normally for every input: a clear vxf::Error (what bad input must give) is
// the expected outcome and is swallowed; anything else — another exception, a crash, a
// sanitizer report, a hang, an allocation past the fuzzer's limit — is a finding. Built two ways
// (fuzz/CMakeLists.txt): with libFuzzer under ASan and UBSan (-DVXF_FUZZ=ON, clang, scripts/fuzz),
// and as vxf_fuzz_replay in every test build, which runs each target over its corpus and the
// inputs its findings left in tests/regress/fuzz (ctest), so the targets keep building and
// fixed inputs stay fixed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace vxf::fuzz {

using Target = int (*)(const std::uint8_t* data, std::size_t size);

/// The text VXF reader (readVxfText), the bytes as a .vxf file.
int vxfText(const std::uint8_t* data, std::size_t size);
/// The mesh reader and its repairs (readMesh): the first byte picks .obj, .ply, .off or .stl,
/// the rest is the file.
int mesh(const std::uint8_t* data, std::size_t size);
/// The scene loader (parseScene): JSON syntax, the schema, the semantic checks.
int scene(const std::uint8_t* data, std::size_t size);
/// The pipeline loader (checkGraph): JSON syntax, the schema, operators, inputs, parameters.
int pipeline(const std::uint8_t* data, std::size_t size);
/// `vxf info` on the bytes as a .vdb: readVoxelSet, then every grid's statistics and metadata.
int vdbInfo(const std::uint8_t* data, std::size_t size);
/// The operator parameter parser: the first byte picks an operator, the second one of its
/// parameters; the text up to the first newline is parsed as that parameter's command-line
/// value (parseParamText), the rest as a JSON object of parameters (checkArgs).
int opParams(const std::uint8_t* data, std::size_t size);

struct NamedTarget
{
    std::string name;
    Target run;
};

/// Every target, by the name scripts/fuzz and the corpus folders use.
const std::vector<NamedTarget>& targets();

} // namespace vxf::fuzz
