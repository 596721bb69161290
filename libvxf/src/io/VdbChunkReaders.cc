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
// tests/unit/VdbArchiveReaderTest.cc reads the crafted files through readVoxelSet and expects an error.

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

/// A compressed chunk: its bytes, as long as its length says.
struct CompressedChunk
{
    std::unique_ptr<char[]> bytes;
    std::int64_t length = 0;
};

/// The chunk's signed length, then: a raw chunk (length ≤ 0) must be exactly the node's buffer,
/// read into @a data (or skipped when it is null); a compressed one is skipped when @a data is
/// null, else its length is checked against @a maxLength before its bytes are read and returned
/// to decode. Returns no bytes when nothing is left to decode.
CompressedChunk readChunk(std::istream& is, char* data, size_t numBytes, std::uint64_t maxLength, const char* codec)
{
    CompressedChunk chunk;
    is.read(reinterpret_cast<char*>(&chunk.length), sizeof(chunk.length));
    if (!is.good()) OPENVDB_THROW(RuntimeError, "the stream ends in the length of a " << codec << " chunk");
    if (chunk.length <= 0) {
        // -length overflows for INT64_MIN; compared as unsigned, -(INT64_MIN) is 2^63, never a buffer's size.
        const std::uint64_t declared = std::uint64_t(0) - std::uint64_t(chunk.length);
        if (declared != numBytes) {
            OPENVDB_THROW(
                RuntimeError, "a " << codec << " chunk declares " << declared << " uncompressed bytes where the node holds " << numBytes);
        }
        if (data == nullptr) {
            is.seekg(std::streamoff(numBytes), std::ios_base::cur);
        } else {
            is.read(data, std::streamsize(numBytes));
        }
        return chunk;
    }
    if (data == nullptr) {
        is.seekg(chunk.length, std::ios_base::cur);
        return chunk;
    }
    if (std::uint64_t(chunk.length) > maxLength) {
        OPENVDB_THROW(RuntimeError,
            "a " << codec << " chunk declares " << chunk.length << " compressed bytes for a node of " << numBytes << " (at most "
                 << maxLength << ")");
    }
    chunk.bytes.reset(new char[size_t(chunk.length)]);
    is.read(chunk.bytes.get(), std::streamsize(chunk.length));
    return chunk;
}

} // namespace

void bloscFromStream(std::istream& is, char* data, size_t numBytes)
{
    // Blosc never grows data by more than its header (BLOSC_MAX_OVERHEAD).
    const CompressedChunk chunk = readChunk(is, data, numBytes, std::uint64_t(numBytes) + BLOSC_MAX_OVERHEAD, "Blosc");
    if (!chunk.bytes) return;
    const char* compressed = chunk.bytes.get();
    const std::int64_t length = chunk.length;
    // Blosc's header states both sizes, and its decompressor believes them: the chunk must hold
    // what the header says it holds, and decompress to exactly the node's buffer.
    size_t uncompressed = 0;
    if (length < BLOSC_MIN_HEADER_LENGTH || blosc_cbuffer_validate(compressed, size_t(length), &uncompressed) != 0) {
        OPENVDB_THROW(RuntimeError, "a Blosc chunk of " << length << " bytes is not valid Blosc data");
    }
    size_t headerUncompressed = 0, headerCompressed = 0, blockSize = 0;
    blosc_cbuffer_sizes(compressed, &headerUncompressed, &headerCompressed, &blockSize);
    if (uncompressed != numBytes || headerCompressed != size_t(length)) {
        OPENVDB_THROW(RuntimeError,
            "a Blosc chunk holds " << headerCompressed << " bytes decompressing to " << uncompressed << " where its length is " << length
                                   << " and the node holds " << numBytes);
    }
    const int decompressed = blosc_decompress_ctx(compressed, data, numBytes, /*numinternalthreads=*/1);
    if (decompressed < 0 || size_t(decompressed) != numBytes) {
        OPENVDB_THROW(RuntimeError, "a Blosc chunk decompressed to " << decompressed << " bytes where the node holds " << numBytes);
    }
}

void unzipFromStream(std::istream& is, char* data, size_t numBytes)
{
    // zlib's worst case for the node's bytes bounds what a writer could have produced.
    const CompressedChunk chunk = readChunk(is, data, numBytes, compressBound(uLong(numBytes)), "zip");
    if (!chunk.bytes) return;
    const char* compressed = chunk.bytes.get();
    const std::int64_t length = chunk.length;
    uLongf unzipped = uLongf(numBytes);
    const int status = uncompress(reinterpret_cast<Bytef*>(data), &unzipped, reinterpret_cast<const Bytef*>(compressed), uLong(length));
    if (status != Z_OK || unzipped != numBytes) {
        OPENVDB_THROW(RuntimeError,
            "a zip chunk decompressed to " << unzipped << " bytes where the node holds " << numBytes << (status != Z_OK ? " (zlib: " : "")
                                           << (status != Z_OK ? zError(status) : "") << (status != Z_OK ? ")" : ""));
    }
}

} // namespace io
} // namespace OPENVDB_VERSION_NAME
} // namespace openvdb
