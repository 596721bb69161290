#include "VdbArchiveReader.h"

#include <openvdb/io/Archive.h>
#include <openvdb/io/Compression.h>
#include <openvdb/io/DelayedLoadMetadata.h>
#include <openvdb/io/GridDescriptor.h>
#include <openvdb/io/io.h>

#include <fmt/format.h>

#include <array>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <vector>

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

    /// Throws unless @a bytes are left in the file from here.
    void need(std::uint64_t bytes, const char* what)
    {
        const std::uint64_t at = position();
        if (at > mEnd || bytes > mEnd - at) {
            throw openvdb::IoError(
                fmt::format("{} at byte {} declares {} bytes where the file has {} left", what, at, bytes, at > mEnd ? 0 : mEnd - at));
        }
    }

private:
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
                throw openvdb::IoError(
                    fmt::format("{}: item '{}' of type {} declares {} bytes where the type has {}", what, name, type, bytes, size));
            }
        }
        if (type == openvdb::BoolMetadata::staticTypeName() && bytes == 1) {
            // Read straight into a bool (a grid's is_saved_as_half_float among them): 0 or 1.
            const auto value = ahead.value<std::uint8_t>(what);
            if (value > 1)
                throw openvdb::IoError(fmt::format("{}: item '{}' of type bool holds {}, not 0 or 1", what, name, unsigned(value)));
            continue;
        }
        ahead.skip(bytes, what);
    }
}

/// How a voxel grid type's tree lies in a file: every one is a Tree4<T, 5, 4, 3>, its values
/// of valueBytes each, or halfBytes when stored as halves (0: not a real type, never halved).
struct TreeLayout
{
    std::size_t valueBytes = 0, halfBytes = 0;
};

/// The voxel grid types vxf reads, whose trees hold fixed-size values only; nullptr for others.
const TreeLayout* voxelTreeLayout(const std::string& type)
{
    // Not Vec3i: OpenVDB compares its tiles with the background by a relative error, an integer
    // division that a crafted value turns into SIGFPE (INT_MIN / -1; found by fuzzing).
    static const std::array<std::pair<std::string, TreeLayout>, 8> types{{
        {openvdb::FloatGrid::gridType(), {4, 2}},
        {openvdb::DoubleGrid::gridType(), {8, 2}},
        {openvdb::Int32Grid::gridType(), {4, 0}},
        {openvdb::Int64Grid::gridType(), {8, 0}},
        {openvdb::BoolGrid::gridType(), {1, 0}},
        {openvdb::MaskGrid::gridType(), {1, 0}}, // its tiles and inactive values are bools
        {openvdb::Vec3SGrid::gridType(), {12, 6}},
        {openvdb::Vec3DGrid::gridType(), {24, 6}},
    }};
    for (const auto& [name, layout] : types) {
        if (name == type) return &layout;
    }
    return nullptr;
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

/// A tree's topology as RootNode, InternalNode and LeafNode::readTopology read it (format 222
/// on), followed through to its end before OpenVDB allocates a node of it: a node that throws
/// while it reads is lost with everything below it (RootNode::readTopology holds it by a raw
/// pointer), and a root child whose origin repeats replaces the first without freeing it.
class TopologyAhead
{
public:
    TopologyAhead(Lookahead& ahead, std::istream& in, const TreeLayout& layout, bool fromHalf, std::uint32_t compression)
        : mAhead(ahead)
        , mIn(in)
        , mLayout(layout)
        , mFromHalf(fromHalf)
        , mCompression(compression)
    {
    }

    void check()
    {
        // Every OpenVDB since 1.0 writes one buffer; TreeBase::readTopology warns on stderr at
        // any other count and reads on as if it were one.
        const auto buffers = mAhead.value<std::int32_t>("a tree's buffer count");
        if (buffers != 1) throw openvdb::IoError(fmt::format("a tree declares {} buffers where OpenVDB writes 1", buffers));
        mAhead.skip(mLayout.valueBytes, "a tree's background");
        const auto tiles = mAhead.value<std::uint32_t>("a tree's root tile count");
        const auto children = mAhead.value<std::uint32_t>("a tree's root child count");
        // Every origin on the 4096-voxel lattice of the root's children (so that a node's
        // bounds, origin + 4095, stay within int32: a tile at 2^31 − 1 overflowed in
        // evalActiveBoundingBox), every active flag a bool (0 or 1).
        mAhead.need(std::uint64_t(tiles) * (3 * sizeof(std::int32_t) + mLayout.valueBytes + 1), "a tree's root tiles");
        for (std::uint32_t n = 0; n < tiles; ++n) {
            rootOrigin("a root tile");
            mAhead.skip(mLayout.valueBytes, "a root tile's value");
            const auto active = mAhead.value<std::uint8_t>("a root tile's active flag");
            if (active > 1) throw openvdb::IoError(fmt::format("a root tile's active flag is {}, not 0 or 1", unsigned(active)));
        }
        std::set<std::array<std::int32_t, 3>> origins;
        for (std::uint32_t n = 0; n < children; ++n) {
            const auto origin = rootOrigin("a root child");
            if (!origins.insert(origin).second) {
                throw openvdb::IoError(fmt::format("the root child at ({}, {}, {}) appears twice", origin[0], origin[1], origin[2]));
            }
            internalNode(5);
        }
    }

private:
    std::array<std::int32_t, 3> rootOrigin(const char* what)
    {
        std::array<std::int32_t, 3> origin{};
        for (auto& c : origin) c = mAhead.value<std::int32_t>(what);
        for (const auto c : origin) {
            if (c % 4096 != 0) {
                throw openvdb::IoError(
                    fmt::format("{}'s origin ({}, {}, {}) is not a multiple of 4096 voxels", what, origin[0], origin[1], origin[2]));
            }
        }
        return origin;
    }

    /// InternalNode<ChildT, log2Dim>::readTopology: child mask, value mask, the node's values,
    /// then each child's topology; a leaf's (LeafNode<T, 3>) is its 64-byte mask.
    void internalNode(int log2Dim)
    {
        const std::size_t values = std::size_t(1) << (3 * log2Dim), maskBytes = values / 8;
        std::vector<std::uint64_t> childMask(maskBytes / 8), valueMask(maskBytes / 8);
        readMask(childMask, "a node's child mask");
        readMask(valueMask, "a node's value mask");
        compressedValues(values, count(valueMask), maskBytes);
        const std::uint64_t children = count(childMask);
        for (std::uint64_t c = 0; c < children; ++c) {
            if (log2Dim == 5) {
                internalNode(4);
            } else {
                mAhead.skip(64, "a leaf's value mask");
            }
        }
    }

    void readMask(std::vector<std::uint64_t>& words, const char* what)
    {
        for (auto& w : words) w = mAhead.value<std::uint64_t>(what);
    }

    static std::uint64_t count(const std::vector<std::uint64_t>& words)
    {
        std::uint64_t n = 0;
        for (const auto w : words) n += std::uint64_t(__builtin_popcountll(w));
        return n;
    }

    /// io::readCompressedValues: a flag saying which inactive values and selection mask follow,
    /// then the active values alone (mask compression) or all of them, as one chunk. The chunk
    /// is read by the same checked reader OpenVDB will call (VdbChunkReaders.cc), into scratch.
    void compressedValues(std::size_t values, std::uint64_t active, std::size_t maskBytes)
    {
        enum : std::int8_t { kOneInactive = 2, kMaskOnly = 3, kMaskOneInactive = 4, kMaskTwoInactive = 5, kAllValues = 6 };
        const auto flag = mAhead.value<std::int8_t>("a node's value compression flag");
        if (flag == kOneInactive || flag == kMaskOneInactive || flag == kMaskTwoInactive) {
            mAhead.skip(mLayout.valueBytes * (flag == kMaskTwoInactive ? 2 : 1), "a node's inactive values");
        }
        if (flag == kMaskOnly || flag == kMaskOneInactive || flag == kMaskTwoInactive) mAhead.skip(maskBytes, "a node's selection mask");
        const std::uint64_t count = (mCompression & openvdb::io::COMPRESS_ACTIVE_MASK) && flag != kAllValues ? active : values;
        const bool halves = mFromHalf && mLayout.halfBytes > 0;
        if (halves && count == 0) return; // io::HalfReader reads no chunk for no values
        const std::size_t bytes = std::size_t(count) * (halves ? mLayout.halfBytes : mLayout.valueBytes);
        if (mCompression & (openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ZIP)) {
            mScratch.resize(std::max<std::size_t>(bytes, 1));
            if (mCompression & openvdb::io::COMPRESS_BLOSC) {
                openvdb::io::bloscFromStream(mIn, mScratch.data(), bytes);
            } else {
                openvdb::io::unzipFromStream(mIn, mScratch.data(), bytes);
            }
        } else {
            mAhead.skip(bytes, "a node's values");
        }
    }

    Lookahead& mAhead;
    std::istream& mIn;
    TreeLayout mLayout;
    bool mFromHalf;
    std::uint32_t mCompression;
    std::vector<char> mScratch;
};

class CheckedArchiveReader : public openvdb::io::Archive
{
public:
    VdbArchive read(std::istream& in, std::uint64_t fileBytes, const std::function<bool(const std::string&)>& wanted, bool headersOnly)
    {
        readHeader(in);
        if (fileVersion() < openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION || fileVersion() > openvdb::OPENVDB_FILE_VERSION) {
            throw openvdb::IoError(fmt::format("file format version {}: vxf reads versions {} (OpenVDB 1.0) to {}", fileVersion(),
                unsigned(openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION), openvdb::OPENVDB_FILE_VERSION));
        }
        // What Stream does: tag the stream with the versions and compression the header gave.
        auto fileMetadata = std::make_shared<openvdb::io::StreamMetadata>();
        openvdb::io::setStreamMetadataPtr(in, fileMetadata, /*transfer=*/false);
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
        std::set<std::string> unwanted;
        for (std::int32_t i = 0; i < count; ++i) {
            Lookahead ahead(in, fileBytes);
            const DescriptorAhead d = checkDescriptor(ahead);
            const TreeLayout* layout = voxelTreeLayout(d.type);
            if (layout && wanted && !wanted(d.name)) {
                unwanted.insert(d.name);
                const std::uint64_t at = ahead.position();
                if (d.endPos > 0 && std::uint64_t(d.endPos) >= at && std::uint64_t(d.endPos) <= fileBytes) {
                    in.seekg(std::streamoff(d.endPos));
                    continue;
                }
            }
            if (!layout) {
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
            const auto at = std::uint64_t(std::streamoff(in.tellg()));
            if (headersOnly && d.endPos > 0 && std::uint64_t(d.endPos) >= at && std::uint64_t(d.endPos) <= fileBytes) {
                // Its metadata (checked ahead with the head above), and on past its data.
                readGridCompression(in);
                grid->readMeta(in);
                grid->removeMeta(openvdb::GridBase::META_FILE_DELAYED_LOAD);
                in.seekg(std::streamoff(d.endPos));
                archive.grids.push_back(grid);
                continue;
            }
            readGrid(in, fileBytes, gd, *grid, *layout, fileMetadata);
            // Delayed-load metadata was read as opaque bytes (initializeVdbReading); it describes
            // this file's layout, so it would be wrong in any file vxf writes.
            grid->removeMeta(openvdb::GridBase::META_FILE_DELAYED_LOAD);
            if (gd.isInstance() && unwanted.count(openvdb::io::GridDescriptor::stripSuffix(gd.instanceParentName()))) {
                throw openvdb::IoError(
                    fmt::format("grid '{}' is an instance of '{}', which was not to be read", d.name, gd.instanceParentName()));
            }
            named[gd.uniqueName()] = grid;
            descriptors.push_back(gd);
            if (!unwanted.count(d.name)) archive.grids.push_back(grid);
        }
        for (const auto& gd : descriptors) connectInstance(gd, named);
        return archive;
    }

private:
    /// What Archive::readGrid does (OpenVDB 10's io/Archive.cc), with the tree's topology
    /// followed to its end (TopologyAhead) between the transform and the tree.
    void readGrid(std::istream& in, std::uint64_t fileBytes, const openvdb::io::GridDescriptor& gd, openvdb::GridBase& grid,
        const TreeLayout& layout, openvdb::io::StreamMetadata::Ptr fileMetadata) const
    {
        readGridCompression(in);
        // Per grid, a copy of the file's stream metadata, restored after.
        auto gridMetadata = std::make_shared<openvdb::io::StreamMetadata>(*fileMetadata);
        gridMetadata->setCompression(openvdb::io::getDataCompression(in));
        gridMetadata->setHalfFloat(grid.saveFloatAsHalf());
        openvdb::io::setStreamMetadataPtr(in, gridMetadata, /*transfer=*/false);
        openvdb::io::setGridClass(in, openvdb::GRID_UNKNOWN);
        openvdb::io::setGridBackgroundValuePtr(in, nullptr);
        grid.readMeta(in);
        gridMetadata->gridMetadata() = static_cast<openvdb::MetaMap&>(grid);
        openvdb::io::setGridClass(in, grid.getGridClass());
        grid.readTransform(in);
        if (!gd.isInstance()) {
            {
                Lookahead ahead(in, fileBytes);
                TopologyAhead(ahead, in, layout, grid.saveFloatAsHalf(), openvdb::io::getDataCompression(in)).check();
                ahead.rewind();
            }
            grid.readTopology(in);
            grid.readBuffers(in);
        }
        openvdb::io::setStreamMetadataPtr(in, fileMetadata, /*transfer=*/false);
        openvdb::io::setDataCompression(in, compression());
    }
};

} // namespace

VdbArchive readVdbArchive(
    std::istream& in, std::uint64_t fileBytes, const std::function<bool(const std::string&)>& wanted, bool headersOnly)
{
    initializeVdbReading();
    return CheckedArchiveReader().read(in, fileBytes, wanted, headersOnly);
}

} // namespace vxf::detail
