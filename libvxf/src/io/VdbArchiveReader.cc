#include "VdbArchiveReader.h"

#include <openvdb/io/Archive.h>
#include <openvdb/io/DelayedLoadMetadata.h>
#include <openvdb/io/GridDescriptor.h>
#include <openvdb/io/io.h>

#include <fmt/format.h>

#include <array>
#include <map>
#include <memory>
#include <mutex>

namespace vxf::detail {

void initializeVdbReading()
{
    static std::once_flag once;
    std::call_once(once, [] {
        openvdb::initialize();
        openvdb::Metadata::unregisterType(openvdb::io::DelayedLoadMetadata::staticTypeName());
    });
}

namespace {

/// Reads ahead of OpenVDB over a part of the file and returns to where it started: each length
/// it meets must fit in what is left of the file.
class Lookahead
{
public:
    Lookahead(std::istream& in, std::uint64_t fileBytes)
        : mIn(in)
        , mStart(in.tellg())
        , mEnd(fileBytes)
    {
    }
    ~Lookahead() = default;
    Lookahead(const Lookahead&) = delete;
    Lookahead& operator=(const Lookahead&) = delete;

    template <typename T>
    T value(const char* what)
    {
        need(sizeof(T), what);
        T v{};
        mIn.read(reinterpret_cast<char*>(&v), sizeof(T));
        return v;
    }

    /// openvdb::readString's layout: a 32-bit length, then the bytes.
    std::string string(const char* what)
    {
        const auto length = value<std::uint32_t>(what);
        need(length, what);
        std::string s(length, '\0');
        if (length > 0) mIn.read(s.data(), length);
        return s;
    }

    void skip(std::uint64_t bytes, const char* what)
    {
        need(bytes, what);
        mIn.seekg(std::streamoff(bytes), std::ios_base::cur);
    }

    std::uint64_t position() { return std::uint64_t(std::streamoff(mIn.tellg())); }
    std::uint64_t end() const { return mEnd; }
    void rewind() { mIn.seekg(mStart); }

private:
    void need(std::uint64_t bytes, const char* what)
    {
        const std::uint64_t at = position();
        if (at > mEnd || bytes > mEnd - at) {
            throw openvdb::IoError(fmt::format("{} at byte {} declares {} bytes where the file has {} left", what, at, bytes,
                at > mEnd ? 0 : mEnd - at));
        }
    }

    std::istream& mIn;
    std::streampos mStart;
    std::uint64_t mEnd;
};

/// MetaMap::readMeta's layout: a count, then per item a name, a type name, a 32-bit byte count
/// and the value. TypedMetadata<T>::readValue reads sizeof(T) bytes whatever the count says, so
/// a registered type other than a string must declare exactly its size, or OpenVDB would read
/// the items after it from other bytes than this look-ahead did.
void checkMetaMap(Lookahead& ahead, const char* what)
{
    const auto count = ahead.value<std::uint32_t>(what);
    for (std::uint32_t i = 0; i < count; ++i) {
        const std::string name = ahead.string(what);
        const std::string type = ahead.string(what);
        const auto bytes = ahead.value<std::uint32_t>(what);
        if (type != openvdb::StringMetadata::staticTypeName() && openvdb::Metadata::isRegisteredType(type)) {
            const openvdb::Index32 size = openvdb::Metadata::createMetadata(type)->size();
            if (bytes != size) {
                throw openvdb::IoError(fmt::format("{}: item '{}' of type {} declares {} bytes where the type has {}", what,
                    name, type, bytes, size));
            }
        }
        ahead.skip(bytes, what);
    }
}

/// The voxel grid types vxf reads: their trees hold fixed-size values only.
bool isVoxelGridType(const std::string& type)
{
    static const std::array<std::string, 9> types{openvdb::FloatGrid::gridType(), openvdb::DoubleGrid::gridType(),
        openvdb::Int32Grid::gridType(), openvdb::Int64Grid::gridType(), openvdb::BoolGrid::gridType(),
        openvdb::MaskGrid::gridType(), openvdb::Vec3SGrid::gridType(), openvdb::Vec3DGrid::gridType(),
        openvdb::Vec3IGrid::gridType()};
    for (const auto& t : types) {
        if (t == type) return true;
    }
    return false;
}

/// GridDescriptor's layout, as GridDescriptor::read takes it.
struct DescriptorAhead
{
    std::string name, type;
    std::int64_t endPos = 0;
};

DescriptorAhead checkDescriptor(Lookahead& ahead)
{
    DescriptorAhead d;
    d.name = ahead.string("a grid descriptor's name");
    d.type = ahead.string("a grid descriptor's type");
    (void)ahead.string("a grid descriptor's instance parent");
    (void)ahead.value<std::int64_t>("a grid descriptor's offsets");
    (void)ahead.value<std::int64_t>("a grid descriptor's offsets");
    d.endPos = ahead.value<std::int64_t>("a grid descriptor's offsets");
    // GridDescriptor::write appends this to the type of a grid stored as halves.
    static const std::string halfSuffix = "_HalfFloat";
    if (d.type.size() > halfSuffix.size() && d.type.compare(d.type.size() - halfSuffix.size(), halfSuffix.size(), halfSuffix) == 0) {
        d.type.resize(d.type.size() - halfSuffix.size());
    }
    // A unique name is the grid's name, then '\x1e' and a number when names repeat.
    const std::size_t marker = d.name.find('\x1e');
    if (marker != std::string::npos) d.name.resize(marker);
    return d;
}

/// What Archive::readGrid reads before the tree, for files from version 219 on: the grid's
/// compression flags, its metadata, and its transform, whose first field is the map's type name.
void checkGridHead(Lookahead& ahead, const std::string& grid)
{
    const std::string what = "the metadata of grid '" + grid + "'";
    (void)ahead.value<std::uint32_t>("a grid's compression flags");
    checkMetaMap(ahead, what.c_str());
    (void)ahead.string("a grid's transform type");
}

class CheckedArchiveReader : public openvdb::io::Archive
{
public:
    VdbArchive read(std::istream& in, std::uint64_t fileBytes)
    {
        readHeader(in);
        if (fileVersion() < openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION || fileVersion() > openvdb::OPENVDB_FILE_VERSION) {
            throw openvdb::IoError(fmt::format("file format version {}: vxf reads versions {} (OpenVDB 1.0) to {}", fileVersion(),
                unsigned(openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION), openvdb::OPENVDB_FILE_VERSION));
        }
        // What Stream does: tag the stream with the versions and compression the header gave.
        auto streamMetadata = std::make_shared<openvdb::io::StreamMetadata>();
        openvdb::io::setStreamMetadataPtr(in, streamMetadata, /*transfer=*/false);
        openvdb::io::setVersion(in, libraryVersion(), fileVersion());
        openvdb::io::setDataCompression(in, compression());

        VdbArchive archive;
        {
            Lookahead ahead(in, fileBytes);
            checkMetaMap(ahead, "the file's metadata");
            ahead.rewind();
        }
        archive.metadata.readMeta(in);

        const std::int32_t count = readGridCount(in);
        if (count < 0) throw openvdb::IoError(fmt::format("the file declares {} grids", count));
        std::vector<openvdb::io::GridDescriptor> descriptors;
        NamedGridMap named;
        for (std::int32_t i = 0; i < count; ++i) {
            Lookahead ahead(in, fileBytes);
            const DescriptorAhead d = checkDescriptor(ahead);
            if (!isVoxelGridType(d.type)) {
                const std::uint64_t at = ahead.position();
                if (d.endPos <= 0 || std::uint64_t(d.endPos) < at || std::uint64_t(d.endPos) > fileBytes) {
                    throw openvdb::IoError(fmt::format("grid '{}' is of type {}, not a voxel grid vxf reads, and its "
                                                       "descriptor gives no end to skip it by",
                        d.name, d.type));
                }
                archive.skipped.push_back(fmt::format("{} ({})", d.name, d.type));
                in.seekg(std::streamoff(d.endPos));
                continue;
            }
            checkGridHead(ahead, d.name);
            ahead.rewind();

            openvdb::io::GridDescriptor gd;
            openvdb::GridBase::Ptr grid = gd.read(in);
            if (!grid) throw openvdb::IoError(fmt::format("grid '{}' of type {} could not be created", d.name, d.type));
            Archive::readGrid(grid, gd, in);
            // Delayed-load metadata was read as opaque bytes (initializeVdbReading); it describes
            // this file's layout, so it would be wrong in any file vxf writes.
            grid->removeMeta(openvdb::GridBase::META_FILE_DELAYED_LOAD);
            named[gd.uniqueName()] = grid;
            archive.grids.push_back(grid);
            descriptors.push_back(gd);
        }
        for (const auto& gd : descriptors) connectInstance(gd, named);
        return archive;
    }
};

} // namespace

VdbArchive readVdbArchive(std::istream& in, std::uint64_t fileBytes)
{
    initializeVdbReading();
    return CheckedArchiveReader().read(in, fileBytes);
}

} // namespace vxf::detail
