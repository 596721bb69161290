// Checked replacements of OpenVDB 10.0.1's two chunk readers (io/Compression.cc).
//
// Every voxel buffer of a .vdb file is a chunk: a signed 64-bit length, then that many bytes
// (Blosc or zlib data, or, when the length is negative, the raw values). The caller passes a
// buffer sized for the node's values. OpenVDB 10.0.1's bloscFromStream reads a raw chunk of the
// length the file declares into that buffer and compares the length with the buffer's size
// afterwards: a file declaring a longer chunk writes past the heap block (found by fuzzing,
// docs/reliability.md "OpenVDB's reader"). A compressed chunk's declared length sizes an
// allocation before anything is checked, and Blosc trusts the sizes its header claims.
//
// These definitions take the library's place: libopenvdb.so calls both through its procedure
// linkage table (R_X86_64_JUMP_SLOT relocations, checked with readelf), and a definition in the
// executable comes first in the dynamic linker's search, so the library's own tree readers use
// these. Each checks a chunk's declared lengths against the buffer before reading a byte of it.
// tests/unit/VdbReaderTest.cc reads the crafted files through readVoxelSet and expects an error.

#include <openvdb/Exceptions.h>
#include <openvdb/io/Compression.h>

#include <blosc.h>
#include <zlib.h>

#include <cstdint>
#include <istream>
#include <memory>
#include <sstream>

namespace vxf::detail {
/// Referenced by readVoxelSet so that a linker taking objects from the static library keeps
/// this one: the replacements below are found by the dynamic linker, not by name from vxf.
bool checkedVdbChunkReadersLinked() { return true; }
} // namespace vxf::detail

namespace openvdb {
OPENVDB_USE_VERSION_NAMESPACE
namespace OPENVDB_VERSION_NAME {
namespace io {

namespace {

/// The chunk's signed length, read before anything else of the chunk.
std::int64_t readChunkLength(std::istream& is, const char* codec)
{
    std::int64_t length = 0;
    is.read(reinterpret_cast<char*>(&length), sizeof(length));
    if (!is.good()) OPENVDB_THROW(RuntimeError, "the stream ends in the length of a " << codec << " chunk");
    return length;
}

/// A raw chunk (negative length): exactly the buffer's size, read into it or skipped.
void readRawChunk(std::istream& is, char* data, size_t numBytes, std::int64_t length, const char* codec)
{
    // -length overflows for INT64_MIN; compared as unsigned, -(INT64_MIN) is 2^63, never a buffer's size.
    const std::uint64_t declared = std::uint64_t(0) - std::uint64_t(length);
    if (declared != numBytes) {
        OPENVDB_THROW(
            RuntimeError, "a " << codec << " chunk declares " << declared << " uncompressed bytes where the node holds " << numBytes);
    }
    if (data == nullptr) {
        is.seekg(std::streamoff(numBytes), std::ios_base::cur);
    } else {
        is.read(data, std::streamsize(numBytes));
    }
}

/// A compressed chunk's bytes, after its length was checked against @a maxLength.
std::unique_ptr<char[]> readCompressed(std::istream& is, std::int64_t length, std::uint64_t maxLength, size_t numBytes, const char* codec)
{
    if (std::uint64_t(length) > maxLength) {
        OPENVDB_THROW(RuntimeError,
            "a " << codec << " chunk declares " << length << " compressed bytes for a node of " << numBytes << " (at most " << maxLength
                 << ")");
    }
    std::unique_ptr<char[]> bytes(new char[size_t(length)]);
    is.read(bytes.get(), std::streamsize(length));
    return bytes;
}

} // namespace

void bloscFromStream(std::istream& is, char* data, size_t numBytes)
{
    const std::int64_t length = readChunkLength(is, "Blosc");
    if (length <= 0) return readRawChunk(is, data, numBytes, length, "Blosc");
    if (data == nullptr) {
        is.seekg(length, std::ios_base::cur);
        return;
    }
    // Blosc never grows data by more than its header (BLOSC_MAX_OVERHEAD).
    const auto compressed = readCompressed(is, length, std::uint64_t(numBytes) + BLOSC_MAX_OVERHEAD, numBytes, "Blosc");
    // Blosc's header states both sizes, and its decompressor believes them: the chunk must hold
    // what the header says it holds, and decompress to exactly the node's buffer.
    size_t uncompressed = 0;
    if (length < BLOSC_MIN_HEADER_LENGTH || blosc_cbuffer_validate(compressed.get(), size_t(length), &uncompressed) != 0) {
        OPENVDB_THROW(RuntimeError, "a Blosc chunk of " << length << " bytes is not valid Blosc data");
    }
    size_t headerUncompressed = 0, headerCompressed = 0, blockSize = 0;
    blosc_cbuffer_sizes(compressed.get(), &headerUncompressed, &headerCompressed, &blockSize);
    if (uncompressed != numBytes || headerCompressed != size_t(length)) {
        OPENVDB_THROW(RuntimeError,
            "a Blosc chunk holds " << headerCompressed << " bytes decompressing to " << uncompressed << " where its length is " << length
                                   << " and the node holds " << numBytes);
    }
    const int decompressed = blosc_decompress_ctx(compressed.get(), data, numBytes, /*numinternalthreads=*/1);
    if (decompressed < 0 || size_t(decompressed) != numBytes) {
        OPENVDB_THROW(RuntimeError, "a Blosc chunk decompressed to " << decompressed << " bytes where the node holds " << numBytes);
    }
}

void unzipFromStream(std::istream& is, char* data, size_t numBytes)
{
    const std::int64_t length = readChunkLength(is, "zip");
    if (length <= 0) return readRawChunk(is, data, numBytes, length, "zip");
    if (data == nullptr) {
        is.seekg(length, std::ios_base::cur);
        return;
    }
    // zlib's worst case for the node's bytes bounds what a writer could have produced.
    const auto compressed = readCompressed(is, length, compressBound(uLong(numBytes)), numBytes, "zip");
    uLongf unzipped = uLongf(numBytes);
    const int status =
        uncompress(reinterpret_cast<Bytef*>(data), &unzipped, reinterpret_cast<const Bytef*>(compressed.get()), uLong(length));
    if (status != Z_OK || unzipped != numBytes) {
        OPENVDB_THROW(RuntimeError,
            "a zip chunk decompressed to " << unzipped << " bytes where the node holds " << numBytes << (status != Z_OK ? " (zlib: " : "")
                                           << (status != Z_OK ? zError(status) : "") << (status != Z_OK ? ")" : ""));
    }
}

} // namespace io
} // namespace OPENVDB_VERSION_NAME
} // namespace openvdb
