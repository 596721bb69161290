#include <vxf/io/VoxelSetFile.h>

#include <vxf/core/GridRoles.h>
#include <vxf/core/GridStats.h>
#include <vxf/core/MemoryBudget.h>
#include <vxf/io/AtomicFile.h>
#include <vxf/io/GridChecksum.h>
#include <vxf/io/InputFile.h>

#include "VdbArchiveReader.h"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <vector>

#include <sys/resource.h>

namespace vxf {

namespace detail {
bool checkedVdbChunkReadersLinked(); // VdbChunkReaders.cc
} // namespace detail

namespace {

/// While a .vdb is read, the process may map at most kReadBudgetBase plus kReadBudgetRatio × the
/// file's size beyond what it has mapped already (RLIMIT_AS, restored afterwards). Every size
/// the file declares is checked against the file before it is used (VdbArchiveReader.h), but a
/// tree still costs more than its bytes on disk: a node is allocated whole from its masks (a
/// Vec3d leaf is 12 KiB of values for 64 bytes of mask). Past the budget an allocation fails at
/// once (std::bad_alloc, reported naming the file). Real files stay far inside it: compression
/// rarely passes 100:1 (a leaf of one value, zipped), and tiles cost nothing.
class ReadBudget
{
public:
    static constexpr std::uintmax_t kReadBudgetBase = std::uintmax_t(1) << 30, kReadBudgetRatio = 1000;

#if defined(__SANITIZE_ADDRESS__)
    // AddressSanitizer maps its own memory and reports an allocation it cannot make as fatal:
    // the limit would turn the reader's errors into aborts. Under it the fuzzer's -rss_limit_mb
    // is the budget.
    explicit ReadBudget(std::uintmax_t) {}
#else
    explicit ReadBudget(std::uintmax_t fileBytes)
    {
        if (::getrlimit(RLIMIT_AS, &mPrevious) != 0) return;
        const std::uintmax_t mapped = mappedMemory();
        if (mapped == 0) return;
        const std::uintmax_t budget = fileBytes > (UINTMAX_MAX - kReadBudgetBase) / kReadBudgetRatio
            ? UINTMAX_MAX / 2
            : kReadBudgetBase + kReadBudgetRatio * fileBytes;
        const std::uintmax_t limit = mapped + std::min(budget, UINTMAX_MAX / 2 - mapped);
        if (mPrevious.rlim_cur != RLIM_INFINITY && mPrevious.rlim_cur <= limit) return; // already tighter
        rlimit tighter = mPrevious;
        tighter.rlim_cur = rlim_t(limit);
        mSet = ::setrlimit(RLIMIT_AS, &tighter) == 0;
    }
    ~ReadBudget()
    {
        if (mSet) ::setrlimit(RLIMIT_AS, &mPrevious);
    }
#endif
    ReadBudget(const ReadBudget&) = delete;
    ReadBudget& operator=(const ReadBudget&) = delete;

#if !defined(__SANITIZE_ADDRESS__)
private:
    rlimit mPrevious{};
    bool mSet = false;
#endif
};

} // namespace

VoxelSet readVoxelSet(const std::string& path) { return readVoxelSet(path, VoxelSetReadOptions{}); }

namespace {

/// The checked archive of the .vdb at @a path (readVdbArchive, within the read's memory
/// budget); every failure a vxf::Error naming the file.
detail::VdbArchive readArchive(const std::string& path, const std::function<bool(const std::string&)>& wanted, bool headersOnly)
{
    detail::initializeVdbReading();
    // The checked chunk readers (VdbChunkReaders.cc) replace OpenVDB's by the dynamic linker;
    // this keeps their object in every binary that reads a .vdb.
    [[maybe_unused]] static const bool checkedChunks = detail::checkedVdbChunkReadersLinked();
    std::error_code ec;
    requireRegularFile(path);
    detail::VdbArchive archive;
    const std::uintmax_t bytes = std::filesystem::file_size(path, ec);
    try {
        // One budgeted read at a time: the limit is the process's, and two readers restoring it
        // out of order would leave one's limit in place.
        static std::mutex budgetMutex;
        const std::lock_guard<std::mutex> lock(budgetMutex);
        const ReadBudget budget(bytes);
        // Through a stream that throws at the first read past its end: OpenVDB's reader loops
        // over the counts a file declares, and from a stream that has failed each read does
        // nothing, so a 5.9 KB file declaring 2^32 root tiles ran 36 s (found by fuzzing,
        // tests/regress/fuzz/vdb_info).
        std::ifstream in(path, std::ios::binary);
        if (!in) throw Error(fmt::format("{}: cannot open: {}", path, std::strerror(errno)));
        in.exceptions(std::ios::failbit | std::ios::badbit);
        archive = detail::readVdbArchive(in, bytes, wanted, headersOnly);
    } catch (const Error&) {
        throw;
    } catch (const std::ios_base::failure&) {
        throw Error(fmt::format("{}: not a readable OpenVDB file (it ends before the data it declares)", path));
    } catch (const openvdb::Exception& e) {
        throw Error(fmt::format("{}: not a readable OpenVDB file ({})", path, e.what()));
    } catch (const std::bad_alloc&) {
        throw Error(fmt::format("{}: not a readable OpenVDB file (it declares more data than a file of {} bytes can hold: "
                                "over {} GiB + {} times its size)",
            path, bytes, ReadBudget::kReadBudgetBase >> 30, ReadBudget::kReadBudgetRatio));
    } catch (const std::exception& e) {
        throw Error(fmt::format("{}: cannot read: {}", path, e.what()));
    }
    return archive;
}

/// VoxelSetReadOptions::finite: @a set's grids that @a finite names hold no NaN or infinite value.
void requireFinite(const VoxelSet& set, const std::string& path, const std::function<bool(const std::string&)>& finite)
{
    for (const auto& grid : set.grids()) {
        if (!finite(grid->getName())) continue;
        const NonFiniteValues bad = nonFiniteValues(*grid);
        if (bad.count == 0) continue;
        throw Error(fmt::format("{}: grid '{}' holds {} NaN or infinite value{} (the first at voxel ({}, {}, {})); the light a stage "
                                "carries must be finite (one such voxel spreads to every voxel downwind)",
            path, grid->getName(), bad.count, bad.count == 1 ? "" : "s", bad.first.x(), bad.first.y(), bad.first.z()));
    }
}

} // namespace

VoxelSet readVoxelSet(const std::string& path, const VoxelSetReadOptions& options)
{
    const detail::VdbArchive archive = readArchive(path, options.wanted, false);
    VoxelSet set;
    openvdb::GridBase::Ptr reference;
    for (const auto& grid : archive.grids) {
        if (findGridRole(grid->getName())) {
            reference = grid;
            break;
        }
    }
    if (!reference && !archive.grids.empty()) reference = archive.grids.front();
    if (reference) set.setTransform(reference->transformPtr());
    for (const auto& grid : archive.grids) {
        if (grid->transform() == set.transform()) grid->setTransform(set.transformPtr());
        set.putAsIs(grid);
    }
    set.metadata() = archive.metadata;
    if (options.skipped) *options.skipped = archive.skipped;
    set.setPath(path);
    // Grids vxf wrote carry a checksum of their data: a byte changed on disk that OpenVDB still
    // reads (7 of 300 byte-flipped copies did, with changed values) is found here.
    std::vector<std::string> damaged;
    for (const auto& grid : set.grids()) {
        const auto written = grid->getMetadata<openvdb::StringMetadata>(kChecksumMetaKey);
        if (!written) continue;
        const std::optional<std::uint64_t> now = gridChecksum(*grid, grid->saveFloatAsHalf());
        if (now && checksumText(*now) != written->value()) damaged.push_back(grid->getName());
    }
    if (!damaged.empty()) {
        std::string names;
        for (const auto& n : damaged) names += (names.empty() ? "'" : ", '") + n + "'";
        const std::string message = fmt::format("{}: grid{} {} damaged: the data does not match the checksum vxf wrote with it", path,
            damaged.size() == 1 ? "" : "s", names + (damaged.size() == 1 ? " is" : " are"));
        if (!options.acceptDamaged) throw Error(message);
        if (options.damaged) *options.damaged = damaged;
    }
    if (options.finite) requireFinite(set, path, options.finite);
    return set;
}

VoxelSet readGrids(const std::string& path, const std::vector<std::string>& names, const VoxelSetReadOptions& options)
{
    VoxelSetReadOptions only = options;
    only.wanted = [&names](const std::string& name) { return std::find(names.begin(), names.end(), name) != names.end(); };
    return readVoxelSet(path, only);
}

void readGridsInto(VoxelSet& set, const std::string& path, const std::vector<std::string>& names, const VoxelSetReadOptions& options)
{
    const VoxelSet read = readGrids(path, names, options);
    for (const openvdb::GridBase::Ptr& grid : read.grids()) set.put(grid);
}

std::uint64_t declaredVoxels(const std::string& path, const std::string& grid)
{
    const detail::VdbArchive archive = readArchive(
        path, [&grid](const std::string& name) { return name == grid; }, true);
    for (const auto& g : archive.grids) {
        if (g->getName() != grid) continue;
        const auto count = g->getMetadata<openvdb::Int64Metadata>(openvdb::GridBase::META_FILE_VOXEL_COUNT);
        return count && count->value() > 0 ? std::uint64_t(count->value()) : 0;
    }
    return 0;
}

std::vector<GridFootprint> declaredFootprints(const std::string& path, const std::set<std::string>& names)
{
    const detail::VdbArchive archive = readArchive(
        path, [&names](const std::string& name) { return names.count(name) > 0; }, true);
    std::vector<GridFootprint> footprints;
    for (const auto& g : archive.grids) {
        if (!names.count(g->getName())) continue;
        const auto bytes = g->getMetadata<openvdb::Int64Metadata>(openvdb::GridBase::META_FILE_MEM_BYTES);
        const auto lo = g->getMetadata<openvdb::Vec3IMetadata>(openvdb::GridBase::META_FILE_BBOX_MIN);
        const auto hi = g->getMetadata<openvdb::Vec3IMetadata>(openvdb::GridBase::META_FILE_BBOX_MAX);
        if (!bytes || bytes->value() <= 0) continue;
        const openvdb::CoordBBox box =
            lo && hi ? openvdb::CoordBBox(openvdb::Coord(lo->value()), openvdb::Coord(hi->value())) : openvdb::CoordBBox();
        footprints.push_back(footprintOf(g->getName(), double(bytes->value()), box, valueBytes(g->valueType())));
    }
    return footprints;
}

std::vector<std::string> voxelGridNames(const std::string& path)
{
    std::vector<std::string> names;
    VoxelSetReadOptions options;
    options.wanted = [&names](const std::string& name) {
        names.push_back(name);
        return false;
    };
    readVoxelSet(path, options);
    return names;
}

namespace {

/// What io::File::write does (a seekable archive into a new file), with the stream's state
/// checked: io::File ignores a failed write, so a full disk or a file size limit left a
/// truncated file that read as written (`ulimit -f 64` gave a 64 KiB "voxel set" and exit 0).
class CheckedArchive : public openvdb::io::Archive
{
public:
    void writeFile(
        const std::string& file, const openvdb::GridCPtrVec& grids, const openvdb::MetaMap& metadata, const std::string& target) const
    {
        std::ofstream out(file, std::ios::binary | std::ios::trunc);
        if (!out) throw Error(fmt::format("{}: cannot write: {}", target, std::strerror(errno)));
        errno = 0;
        Archive::write(out, grids, /*seekable=*/true, metadata);
        out.flush();
        const int failure = errno;
        out.close();
        if (out.fail()) {
            throw Error(fmt::format("{}: cannot write: {}", target, failure ? std::strerror(failure) : "the stream failed"));
        }
    }
};

} // namespace

void writeVoxelSet(const std::string& path, const VoxelSet& set, const VoxelSetWriteOptions& options)
{
    detail::initializeVdbReading();
    openvdb::GridCPtrVec grids;
    for (const auto& grid : set.grids()) {
        // Shallow copy: shares the tree, owns its metadata and save flags.
        openvdb::GridBase::Ptr copy = grid->copyGrid();
        if (const GridRole* role = findGridRole(grid->getName())) {
            if (!copy->getMetadata<openvdb::StringMetadata>(kUnitsMetaKey)) {
                copy->insertMeta(kUnitsMetaKey, openvdb::StringMetadata(role->units));
            }
        }
        copy->setSaveFloatAsHalf(options.half);
        if (const auto checksum = gridChecksum(*copy, options.half)) {
            copy->insertMeta(kChecksumMetaKey, openvdb::StringMetadata(checksumText(*checksum)));
        } else {
            copy->removeMeta(kChecksumMetaKey); // a type without one: none of an earlier write
        }
        grids.push_back(copy);
    }
    openvdb::MetaMap metadata = set.metadata();
    metadata.insertMeta(kVersionMetaKey, openvdb::StringMetadata(versionString()));

    writeAtomically(path, [&](const std::string& tmpPath) {
        try {
            CheckedArchive archive;
            uint32_t compression = openvdb::io::COMPRESS_ACTIVE_MASK;
            if (options.compress) {
                compression |= openvdb::io::Archive::hasBloscCompression() ? openvdb::io::COMPRESS_BLOSC : openvdb::io::COMPRESS_ZIP;
            }
            archive.setCompression(compression);
            archive.writeFile(tmpPath, grids, metadata, path);
        } catch (const openvdb::Exception& e) {
            throw Error(fmt::format("{}: cannot write: {}", path, e.what()));
        }
    });
}

} // namespace vxf
