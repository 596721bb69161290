#include <vxf/io/VxfText.h>

#include "VxfTextColumns.h"

#include <vxf/io/AtomicFile.h>
#include <vxf/io/InputFile.h>

#include <openvdb/tools/SignedFloodFill.h>

#include <fmt/format.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string_view>

namespace vxf {

namespace {

using namespace detail;

/// A whitespace-separated token and its 1-based column.
struct Token
{
    std::string_view text;
    std::size_t column;
};

/// Split @a line into tokens, stopping at '#' (comment) and ignoring a trailing '\r'.
void tokenize(std::string_view line, std::vector<Token>& tokens)
{
    tokens.clear();
    std::size_t i = 0;
    const std::size_t n = line.size();
    while (i < n) {
        const char c = line[i];
        if (c == '#') break;
        if (c == ' ' || c == '\t' || c == '\r') {
            ++i;
            continue;
        }
        const std::size_t start = i;
        while (i < n && line[i] != ' ' && line[i] != '\t' && line[i] != '\r' && line[i] != '#') ++i;
        tokens.push_back({line.substr(start, i - start), start + 1});
    }
}

bool isNameStart(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool isNameChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '-' || c == ':'; }

/// Parses and checks one text file, remembering where it is for error messages.
class TextReader
{
public:
    TextReader(const std::string& path)
        : mPath(path)
    {
    }

    [[noreturn]] void fail(std::size_t column, const std::string& what) const { throw InputError(mPath, mLine, column, what); }

    template <typename IntT>
    IntT parseInt(const Token& token, const char* what) const
    {
        std::string_view text = token.text;
        if (!text.empty() && text[0] == '+') text.remove_prefix(1);
        IntT value{};
        const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
        if (ec == std::errc::result_out_of_range) {
            fail(token.column, fmt::format("{} '{}' is out of range", what, token.text));
        }
        if (ec != std::errc() || end != text.data() + text.size() || text.empty()) {
            fail(token.column, fmt::format("expected an integer for {}, found '{}'", what, token.text));
        }
        return value;
    }

    template <typename RealT>
    RealT parseReal(const Token& token, const std::string& what) const
    {
        std::string_view text = token.text;
        if (!text.empty() && text[0] == '+') text.remove_prefix(1);
        RealT value{};
        auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
        if (ec == std::errc::result_out_of_range && end == text.data() + text.size()) {
            // from_chars reports underflow to zero/subnormal as out of range: accept tiny
            // values (strtod rounds them correctly), reject overflow.
            const std::string copy(text);
            const double wide = std::strtod(copy.c_str(), nullptr);
            if (std::isfinite(wide) && std::abs(wide) < 1.0) {
                value = RealT(wide);
                if constexpr (std::is_same_v<RealT, float>) value = std::strtof(copy.c_str(), nullptr);
                ec = std::errc();
            } else {
                fail(token.column,
                    fmt::format(
                        "{} '{}' is too large for a {}", what, token.text, std::is_same_v<RealT, float> ? "32-bit float" : "double"));
            }
        }
        if (ec != std::errc() || end != text.data() + text.size() || text.empty()) {
            fail(token.column, fmt::format("expected a number for {}, found '{}'", what, token.text));
        }
        if (std::isnan(value)) fail(token.column, fmt::format("{} is NaN; NaN is not allowed", what));
        if (std::isinf(value)) fail(token.column, fmt::format("{} is infinite; only finite numbers are allowed", what));
        return value;
    }

    const std::string& path() const { return mPath; }
    std::size_t mLine = 0;

private:
    std::string mPath;
};

template <typename GridT>
typename GridT::Ptr makeGrid(const GridColumn& column, const openvdb::math::Transform::Ptr& xform)
{
    using ValueT = typename GridT::ValueType;
    ValueT background;
    if constexpr (std::is_same_v<ValueT, openvdb::Vec3f>) {
        background = column.background;
    } else if constexpr (std::is_same_v<ValueT, bool>) {
        background = column.background[0] != 0.0f;
    } else {
        background = column.background[0];
    }
    auto grid = GridT::create(background);
    grid->setName(column.name);
    grid->setTransform(xform);
    grid->setGridClass(column.gridClass);
    return grid;
}

/// Per-grid accessor that sets one voxel from the line's tokens.
struct ColumnWriter
{
    GridColumn column;
    openvdb::GridBase::Ptr grid;
    std::unique_ptr<openvdb::BoolGrid::Accessor> boolAcc;
    std::unique_ptr<openvdb::FloatGrid::Accessor> floatAcc;
    std::unique_ptr<openvdb::Vec3SGrid::Accessor> vecAcc;
};

/// What a text VXF's header says, and on which lines.
struct TextHeader
{
    std::optional<openvdb::Vec3i> size;
    double voxelSize = 0.0;
    std::optional<openvdb::Vec3d> minCorner, maxCorner;
    std::size_t sizeLine = 0, minLine = 0, maxLine = 0, countLine = 0;
    std::optional<std::uint64_t> declaredCount;
    std::vector<GridColumn> columns;
    bool sawVersion = false;
};

/// A `grid NAME TYPE [class=…] [background=…]` header line, checked against the grids declared before.
GridColumn parseGridLine(
    const TextReader& reader, const std::vector<Token>& tokens, const std::string& line, const std::vector<GridColumn>& columns)
{
    if (tokens.size() < 3) {
        reader.fail(tokens.size() == 2 ? line.size() + 1 : tokens[0].column,
            "'grid' needs a name and a type: grid NAME bool|float|vec3 [class=level_set|fog_volume] [background=V]");
    }
    GridColumn column;
    column.name = std::string(tokens[1].text);
    bool nameOk = isNameStart(column.name[0]);
    for (char c : column.name) nameOk = nameOk && isNameChar(c);
    if (!nameOk) reader.fail(tokens[1].column, fmt::format("'{}' is not a valid grid name", column.name));
    if (column.name == "active") reader.fail(tokens[1].column, "'active' is the flag column, not a grid name");
    for (const auto& other : columns) {
        if (other.name == column.name) reader.fail(tokens[1].column, fmt::format("grid '{}' declared twice", column.name));
    }
    const std::string_view type = tokens[2].text;
    if (type == "bool")
        column.type = ColumnType::Bool;
    else if (type == "float")
        column.type = ColumnType::Float;
    else if (type == "vec3")
        column.type = ColumnType::Vec3;
    else
        reader.fail(tokens[2].column, fmt::format("unknown grid type '{}' (expected bool, float or vec3)", type));
    for (std::size_t t = 3; t < tokens.size(); ++t) {
        const std::string_view option = tokens[t].text;
        const auto eq = option.find('=');
        const std::string_view key = option.substr(0, eq);
        const std::string_view value = eq == std::string_view::npos ? std::string_view() : option.substr(eq + 1);
        if (key == "class" && eq != std::string_view::npos) {
            if (value == "level_set")
                column.gridClass = openvdb::GRID_LEVEL_SET;
            else if (value == "fog_volume")
                column.gridClass = openvdb::GRID_FOG_VOLUME;
            else if (value == "unknown")
                column.gridClass = openvdb::GRID_UNKNOWN;
            else
                reader.fail(
                    tokens[t].column + 6, fmt::format("unknown grid class '{}' (expected level_set, fog_volume or unknown)", value));
            if (column.gridClass == openvdb::GRID_LEVEL_SET && column.type != ColumnType::Float) {
                reader.fail(tokens[t].column, "class=level_set needs a float grid");
            }
        } else if (key == "background" && eq != std::string_view::npos) {
            std::vector<Token> parts;
            std::size_t start = 0;
            while (true) {
                const auto comma = value.find(',', start);
                parts.push_back({value.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start),
                    tokens[t].column + 11 + start});
                if (comma == std::string_view::npos) break;
                start = comma + 1;
            }
            if (parts.size() != std::size_t(columnWidth(column.type))) {
                reader.fail(tokens[t].column,
                    fmt::format("background of a {} grid takes {} value(s), found {}", columnTypeName(column.type),
                        columnWidth(column.type), parts.size()));
            }
            for (std::size_t p = 0; p < parts.size(); ++p) {
                column.background[int(p)] = reader.parseReal<float>(parts[p], "background");
            }
            if (column.type != ColumnType::Vec3) column.background = openvdb::Vec3f(column.background[0]);
            if (column.type == ColumnType::Bool && column.background[0] != 0.0f && column.background[0] != 1.0f) {
                reader.fail(tokens[t].column, "background of a bool grid must be 0 or 1");
            }
        } else {
            reader.fail(tokens[t].column, fmt::format("unknown grid option '{}' (expected class=… or background=…)", option));
        }
    }
    return column;
}

/// One header line (@a tokens of @a line; its keyword is not a voxel index) into @a header.
void parseHeaderLine(TextHeader& header, const TextReader& reader, const std::vector<Token>& tokens, const std::string& line)
{
    const std::string_view keyword = tokens[0].text;
    auto& [size, voxelSize, minCorner, maxCorner, sizeLine, minLine, maxLine, countLine, declaredCount, columns, sawVersion] = header;
    const auto expectArgs = [&](std::size_t n, const char* form) {
        if (tokens.size() != n + 1) {
            reader.fail(
                tokens.size() > n + 1 ? tokens[n + 1].column : line.size() + 1, fmt::format("'{}' takes {} values: {}", keyword, n, form));
        }
    };
    if (keyword == "vxf") {
        if (sawVersion) reader.fail(tokens[0].column, "'vxf' given twice");
        expectArgs(1, "vxf 1");
        if (reader.parseInt<int>(tokens[1], "the format version") != 1) {
            reader.fail(tokens[1].column, "unsupported text VXF version (this reader knows 1)");
        }
        sawVersion = true;
    } else if (keyword == "size") {
        if (size) reader.fail(tokens[0].column, fmt::format("'size' given twice (first on line {})", sizeLine));
        expectArgs(4, "size W D H voxelsize");
        openvdb::Vec3i s;
        const char* axes[] = {"W (voxels along x)", "D (voxels along y)", "H (voxels along z)"};
        for (int a = 0; a < 3; ++a) {
            const auto v = reader.parseInt<std::int64_t>(tokens[1 + a], axes[a]);
            if (v < 0 || v > (std::int64_t(1) << 30)) {
                reader.fail(tokens[1 + a].column, fmt::format("{} must be in [0, 2^30], found {}", axes[a], v));
            }
            s[a] = int(v);
        }
        voxelSize = reader.parseReal<double>(tokens[4], "voxelsize");
        if (!(voxelSize > 0.0)) reader.fail(tokens[4].column, "voxelsize must be positive");
        size = s;
        sizeLine = reader.mLine;
    } else if (keyword == "min" || keyword == "max") {
        auto& corner = keyword == "min" ? minCorner : maxCorner;
        auto& where = keyword == "min" ? minLine : maxLine;
        if (corner) reader.fail(tokens[0].column, fmt::format("'{}' given twice (first on line {})", keyword, where));
        expectArgs(3, keyword == "min" ? "min x y z" : "max x y z");
        openvdb::Vec3d v;
        for (int a = 0; a < 3; ++a) {
            v[a] = reader.parseReal<double>(tokens[1 + a], fmt::format("{} {}", keyword, "xyz"[a]));
        }
        corner = v;
        where = reader.mLine;
    } else if (keyword == "count") {
        if (declaredCount) reader.fail(tokens[0].column, "'count' given twice");
        expectArgs(1, "count N");
        declaredCount = reader.parseInt<std::uint64_t>(tokens[1], "count");
        countLine = reader.mLine;
    } else if (keyword == "grid") {
        columns.push_back(parseGridLine(reader, tokens, line, columns));
    } else {
        reader.fail(tokens[0].column,
            fmt::format(
                "unknown header line '{}' (expected size, min, max, grid, count or vxf, or a voxel line 'i j k active …')", keyword));
    }
}

/// The header must be complete before the first voxel (or the end of the file), and agree with itself.
void checkHeader(TextHeader& header, const TextReader& reader, bool haveVoxelLine)
{
    auto& [size, voxelSize, minCorner, maxCorner, sizeLine, minLine, maxLine, countLine, declaredCount, columns, sawVersion] = header;
    const std::string& path = reader.path();
    const auto requireHeader = [&](bool present, const char* form) {
        if (!present) {
            reader.fail(haveVoxelLine ? 1 : 0,
                fmt::format("missing header line '{}' {}", form, haveVoxelLine ? "before the first voxel" : "(the file ends without it)"));
        }
    };
    requireHeader(size.has_value(), "size W D H voxelsize");
    requireHeader(minCorner.has_value(), "min x y z");
    requireHeader(maxCorner.has_value(), "max x y z");
    for (int a = 0; a < 3; ++a) {
        // max − min must equal size · voxelsize (to 1/1000 of a voxel, or the printed precision).
        const double expected = (*minCorner)[a] + double((*size)[a]) * voxelSize;
        const double tolerance = std::max(1e-3 * voxelSize, 1e-6 * std::max(std::abs((*minCorner)[a]), std::abs((*maxCorner)[a])));
        if (!(std::abs(expected - (*maxCorner)[a]) <= tolerance)) {
            throw InputError(path, maxLine, 0,
                fmt::format("header disagrees with itself along {}: min {} + size {} × voxelsize {} = {}, but max is {} "
                            "(size on line {}, min on line {})",
                    "xyz"[a], (*minCorner)[a], (*size)[a], voxelSize, expected, (*maxCorner)[a], sizeLine, minLine));
        }
    }
    if (columns.empty()) columns.push_back(GridColumn{"color", ColumnType::Vec3, openvdb::GRID_UNKNOWN, openvdb::Vec3f(0.0f)});
}

/// One writer per declared grid on @a xform; @a valuesPerLine and @a lineForm describe a voxel line.
std::vector<ColumnWriter> columnWriters(
    const std::vector<GridColumn>& columns, const openvdb::math::Transform::Ptr& xform, std::size_t& valuesPerLine, std::string& lineForm)
{
    std::vector<ColumnWriter> writers(columns.size());
    valuesPerLine = 4;
    lineForm = "i j k active";
    for (std::size_t c = 0; c < columns.size(); ++c) {
        ColumnWriter& w = writers[c];
        w.column = columns[c];
        valuesPerLine += std::size_t(columnWidth(w.column.type));
        lineForm += w.column.type == ColumnType::Vec3 ? fmt::format(" {0}.r {0}.g {0}.b", w.column.name) : " " + w.column.name;
        switch (w.column.type) {
        case ColumnType::Bool: {
            auto g = makeGrid<openvdb::BoolGrid>(w.column, xform);
            w.boolAcc = std::make_unique<openvdb::BoolGrid::Accessor>(g->getAccessor());
            w.grid = g;
            break;
        }
        case ColumnType::Float: {
            auto g = makeGrid<openvdb::FloatGrid>(w.column, xform);
            w.floatAcc = std::make_unique<openvdb::FloatGrid::Accessor>(g->getAccessor());
            w.grid = g;
            break;
        }
        case ColumnType::Vec3: {
            auto g = makeGrid<openvdb::Vec3SGrid>(w.column, xform);
            w.vecAcc = std::make_unique<openvdb::Vec3SGrid::Accessor>(g->getAccessor());
            w.grid = g;
            break;
        }
        }
    }
    return writers;
}

/// The line before line @a here of @a path that first gave voxel @a ijk (an error's path: the file is read again).
std::size_t firstLineOfVoxel(const std::string& path, std::size_t here, const openvdb::Coord& ijk)
{
    // Find the first occurrence (error path only: rescan the file).
    std::ifstream again(path, std::ios::binary);
    std::string earlier;
    std::vector<Token> t;
    std::size_t lineNo = 0, firstLine = 0;
    while (std::getline(again, earlier) && ++lineNo < here) {
        tokenize(earlier, t);
        if (t.size() >= 3 && (std::isdigit(static_cast<unsigned char>(t[0].text[0])) || t[0].text[0] == '+')) {
            int v[3];
            bool ok = true;
            for (int a = 0; a < 3; ++a) {
                std::string_view s = t[std::size_t(a)].text;
                if (!s.empty() && s[0] == '+') s.remove_prefix(1);
                ok = ok && std::from_chars(s.data(), s.data() + s.size(), v[a]).ec == std::errc();
            }
            if (ok && openvdb::Coord(v[0], v[1], v[2]) == ijk) {
                firstLine = lineNo;
                break;
            }
        }
    }
    return firstLine;
}

/// Set voxel @a at of every grid from a voxel line's value columns (after `i j k active`).
void setVoxel(
    std::vector<ColumnWriter>& writers, const TextReader& reader, const std::vector<Token>& tokens, const openvdb::Coord& at, bool active)
{
    std::size_t t = 4;
    for (ColumnWriter& w : writers) {
        switch (w.column.type) {
        case ColumnType::Bool: {
            const std::string_view b = tokens[t].text;
            if (b != "0" && b != "1")
                reader.fail(tokens[t].column, fmt::format("expected 0 or 1 for bool grid '{}', found '{}'", w.column.name, b));
            if (active)
                w.boolAcc->setValueOn(at, b == "1");
            else
                w.boolAcc->setValueOff(at, b == "1");
            break;
        }
        case ColumnType::Float: {
            const float v = reader.parseReal<float>(tokens[t], fmt::format("grid '{}'", w.column.name));
            if (active)
                w.floatAcc->setValueOn(at, v);
            else
                w.floatAcc->setValueOff(at, v);
            break;
        }
        case ColumnType::Vec3: {
            openvdb::Vec3f v;
            for (int a = 0; a < 3; ++a) {
                v[a] = reader.parseReal<float>(tokens[t + std::size_t(a)], fmt::format("grid '{}' {}", w.column.name, "rgb"[a]));
            }
            if (active)
                w.vecAcc->setValueOn(at, v);
            else
                w.vecAcc->setValueOff(at, v);
            break;
        }
        }
        t += std::size_t(columnWidth(w.column.type));
    }
}

/// Keep memory near the final grids': collapse the leaves completed so far (files in tree
/// order, as vdb2vxf writes them, complete leaves one after another).
void collapseCompleted(
    std::vector<ColumnWriter>& writers, openvdb::MaskTree& seen, openvdb::tree::ValueAccessor<openvdb::MaskTree>& seenAcc)
{
    for (ColumnWriter& w : writers) {
        if (w.boolAcc) w.boolAcc->clear();
        if (w.floatAcc) w.floatAcc->clear();
        if (w.vecAcc) w.vecAcc->clear();
        w.grid->pruneGrid(0.0f);
    }
    seenAcc.clear();
    seen.prune();
}

/// The grids read, pruned (level sets flood-filled), in a set on @a xform.
VoxelSet collectGrids(std::vector<ColumnWriter>& writers, const openvdb::math::Transform::Ptr& xform)
{
    VoxelSet set(xform);
    for (ColumnWriter& w : writers) {
        w.boolAcc.reset();
        w.floatAcc.reset();
        w.vecAcc.reset();
        if (w.column.gridClass == openvdb::GRID_LEVEL_SET) {
            auto g = openvdb::gridPtrCast<openvdb::FloatGrid>(w.grid);
            openvdb::tools::signedFloodFill(g->tree());
        }
        w.grid->pruneGrid(0.0f);
        set.put(w.grid);
    }
    return set;
}

} // namespace

VoxelSet readVxfText(const std::string& path, Interrupter* interrupter)
{
    InterruptStep step(interrupter, "reading text VXF");
    requireRegularFile(path);
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(fmt::format("{}: cannot open", path));
    std::error_code ec;
    const auto fileSize = std::filesystem::file_size(path, ec);

    TextReader reader(path);
    std::string line;
    std::vector<Token> tokens;
    TextHeader header;
    bool haveVoxelLine = false;
    bool lastLineTerminated = true;

    const auto readLine = [&]() -> bool {
        if (!std::getline(in, line)) return false;
        ++reader.mLine;
        lastLineTerminated = !in.eof();
        return true;
    };

    // Header: keyword lines until the first voxel line.
    while (readLine()) {
        tokenize(line, tokens);
        if (tokens.empty()) continue;
        const char first = tokens[0].text[0];
        if (std::isdigit(static_cast<unsigned char>(first)) || first == '-' || first == '+') {
            haveVoxelLine = true;
            break;
        }
        parseHeaderLine(header, reader, tokens, line);
    }
    checkHeader(header, reader, haveVoxelLine);
    const openvdb::Vec3i size = *header.size;

    // Grids: text voxel (i,j,k) is VDB voxel origin + (i,j,k); its centre is min + voxelsize·(ijk + ½).
    openvdb::Coord origin;
    const auto xform = textTransform(*header.minCorner, header.voxelSize, origin);
    std::size_t valuesPerLine = 4;
    std::string lineForm;
    std::vector<ColumnWriter> writers = columnWriters(header.columns, xform, valuesPerLine, lineForm);

    openvdb::MaskTree seen;
    openvdb::tree::ValueAccessor<openvdb::MaskTree> seenAcc(seen);
    std::uint64_t voxelCount = 0;
    const char* axisNames[] = {"i", "j", "k"};
    const char* axisSizes[] = {"W", "D", "H"};
    while (haveVoxelLine) {
        if (tokens.size() != valuesPerLine) {
            const std::size_t column = tokens.size() > valuesPerLine ? tokens[valuesPerLine].column : line.size() + 1;
            reader.fail(column, fmt::format("expected {} values ({}), found {}", valuesPerLine, lineForm, tokens.size()));
        }
        openvdb::Coord ijk;
        for (int a = 0; a < 3; ++a) {
            const auto v = reader.parseInt<std::int64_t>(tokens[std::size_t(a)], fmt::format("voxel index {}", axisNames[a]).c_str());
            if (v < 0 || v >= size[a]) {
                reader.fail(tokens[std::size_t(a)].column,
                    fmt::format("voxel index {} = {} is outside [0, {}) given by {} on line {}", axisNames[a], v, size[a], axisSizes[a],
                        header.sizeLine));
            }
            ijk[a] = openvdb::Int32(v);
        }
        const std::string_view activeText = tokens[3].text;
        if (activeText != "0" && activeText != "1") {
            reader.fail(tokens[3].column, fmt::format("expected the active flag 0 or 1, found '{}'", activeText));
        }
        const bool active = activeText == "1";
        if (seenAcc.isValueOn(ijk)) {
            reader.fail(1,
                fmt::format("duplicate voxel ({}, {}, {}), first given on line {}", ijk[0], ijk[1], ijk[2],
                    firstLineOfVoxel(path, reader.mLine, ijk)));
        }
        seenAcc.setValueOn(ijk);
        const openvdb::Coord at = ijk + origin; // in the .vdb

        setVoxel(writers, reader, tokens, at, active);
        ++voxelCount;
        if ((voxelCount & 0xFFFF) == 0 && fileSize > 0) {
            checkInterrupt(interrupter, int(100.0 * double(in.tellg()) / double(fileSize)));
        }
        if ((voxelCount & 0xFFFFF) == 0) collapseCompleted(writers, seen, seenAcc);

        // Next voxel line, skipping blank and comment lines.
        haveVoxelLine = false;
        while (readLine()) {
            tokenize(line, tokens);
            if (tokens.empty()) continue;
            const char first = tokens[0].text[0];
            if (!(std::isdigit(static_cast<unsigned char>(first)) || first == '-' || first == '+')) {
                reader.fail(tokens[0].column,
                    fmt::format("expected a voxel line 'i j k active …', found '{}' "
                                "(header lines must come before the voxels)",
                        tokens[0].text));
            }
            haveVoxelLine = true;
            break;
        }
        if (!haveVoxelLine && !lastLineTerminated && !tokens.empty()) {
            reader.fail(0, "the last voxel line has no line end: the file looks truncated");
        }
    }
    if (in.bad()) throw Error(fmt::format("{}: read error", path));
    if (header.declaredCount && *header.declaredCount != voxelCount) {
        reader.fail(0,
            fmt::format("'count' on line {} promises {} voxels but the file has {}{}", header.countLine, *header.declaredCount, voxelCount,
                voxelCount < *header.declaredCount ? ": the file looks truncated" : ""));
    }
    VoxelSet set = collectGrids(writers, xform);
    set.metadata().insertMeta(kTextSizeMetaKey, openvdb::Vec3IMetadata(size));
    set.metadata().insertMeta(kTextMinMetaKey, openvdb::Vec3DMetadata(*header.minCorner));
    set.metadata().insertMeta(kTextMaxMetaKey, openvdb::Vec3DMetadata(*header.maxCorner));
    return set;
}

} // namespace vxf
