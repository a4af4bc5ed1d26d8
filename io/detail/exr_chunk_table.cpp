// Reads an OpenEXR file's chunk offset tables (one 64-bit offset per chunk,
// part after part, right after the headers) and the leader of the chunk that
// starts last, and compares them with the file's size. OpenEXR's Core API gives
// each part's chunk count and storage; the rest is read here, since the Core
// API reads a table only chunk by chunk.
#include "io/detail/exr_chunk_table.h"

#include "io/detail/exr_core.h"
#include "io/detail/exr_headers.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <vector>

namespace modestack::io::detail {
namespace {

// OpenEXR stores integers little-endian.
std::uint64_t little_endian(const unsigned char* bytes, int count)
{
    std::uint64_t value = 0;
    for (int i = count - 1; i >= 0; --i)
        value = value << 8 | bytes[i];
    return value;
}

// Larger than any frame file (1 TiB).
constexpr std::uint64_t kPlausibleFileBytes = std::uint64_t(1) << 40;

struct PartChunks {
    int count = 0;
    exr_storage_t storage = EXR_STORAGE_SCANLINE;
};

// Where the chunk starting at `offset` ends: after its leader (part number in a
// multi-part file; y, or tile x, y and levels; sizes) and its data. -1 when
// the leader itself is not all in the file; `problem` is set when it holds a
// negative size.
std::int64_t chunk_end(std::ifstream& in, std::int64_t offset, const PartChunks& part, bool multipart,
                       std::string& problem)
{
    const bool tiled = part.storage == EXR_STORAGE_TILED || part.storage == EXR_STORAGE_DEEP_TILED;
    const bool deep = part.storage == EXR_STORAGE_DEEP_SCANLINE || part.storage == EXR_STORAGE_DEEP_TILED;
    const int coordinates = (multipart ? 4 : 0) + (tiled ? 16 : 4);
    // Flat: one 32-bit packed size. Deep: 64-bit sample table size, packed size, unpacked size.
    const int sizes = deep ? 24 : 4;
    unsigned char leader[44] = {};
    in.clear();
    in.seekg(offset);
    if (!in.read(reinterpret_cast<char*>(leader), coordinates + sizes))
        return -1;
    const unsigned char* size_bytes = leader + coordinates;
    std::int64_t data_bytes = 0;
    if (deep) {
        auto table = static_cast<std::int64_t>(little_endian(size_bytes, 8));
        auto packed = static_cast<std::int64_t>(little_endian(size_bytes + 8, 8));
        if (table < 0 || packed < 0 || table > (INT64_MAX >> 2) || packed > (INT64_MAX >> 2))
            problem = "damaged chunk: its leader gives a negative or impossible size";
        data_bytes = table + packed;
    } else {
        data_bytes = static_cast<std::int32_t>(little_endian(size_bytes, 4));
        if (data_bytes < 0)
            problem = "damaged chunk: its leader gives a negative size";
    }
    return offset + coordinates + sizes + data_bytes;
}

} // namespace

std::string exr_chunk_table_problem(const std::string& file)
{
    const ExrHeaders headers = walk_exr_headers(file);
    if (!headers.is_exr)
        return {};
    if (!headers.problem.empty())
        return headers.problem;
    const std::int64_t file_size = headers.file_size;
    if (headers.tables_offset < 0)
        return fmt::format("truncated: the file ends inside its header ({} bytes)", file_size);

    CoreReadContext input(file);
    if (!input.context)
        return fmt::format("cannot read the header ({})", last_core_message());
    int part_count = 0;
    if (exr_get_count(input.context, &part_count) != EXR_ERR_SUCCESS || part_count < 1)
        return fmt::format("cannot read the header ({})", last_core_message());
    std::vector<PartChunks> parts(static_cast<std::size_t>(part_count));
    std::int64_t total = 0;
    for (int p = 0; p < part_count; ++p) {
        std::int32_t count = 0;
        if (exr_get_chunk_count(input.context, p, &count) != EXR_ERR_SUCCESS ||
            exr_get_storage(input.context, p, &parts[p].storage) != EXR_ERR_SUCCESS || count < 0)
            return fmt::format("cannot read the header of part {} ({})", p, last_core_message());
        parts[p].count = count;
        total += count;
    }

    const std::int64_t tables_end = headers.tables_offset + 8 * total;
    if (tables_end > file_size)
        return fmt::format(
            "truncated: the file ends inside its chunk offset table ({} bytes, the table ends at "
            "byte {})",
            file_size, tables_end);
    std::vector<unsigned char> table(static_cast<std::size_t>(8 * total));
    std::ifstream in(file, std::ios::binary);
    in.seekg(headers.tables_offset);
    if (!in.read(reinterpret_cast<char*>(table.data()), static_cast<std::streamsize>(table.size())))
        return "cannot read the chunk offset table";

    std::int64_t unwritten = 0, past_end = 0, into_header = 0, last_start = -1;
    std::uint64_t last_past_end = 0;
    std::size_t last_part = 0;
    std::size_t part = 0;
    std::int64_t first_of_part = 0;
    for (std::int64_t chunk = 0; chunk < total; ++chunk) {
        while (chunk >= first_of_part + parts[part].count)
            first_of_part += parts[part++].count;
        const std::uint64_t offset = little_endian(&table[static_cast<std::size_t>(8 * chunk)], 8);
        if (offset == 0)
            ++unwritten;
        else if (offset >= static_cast<std::uint64_t>(file_size)) {
            ++past_end;
            last_past_end = std::max(last_past_end, offset);
        } else if (offset < static_cast<std::uint64_t>(tables_end))
            ++into_header;
        else if (static_cast<std::int64_t>(offset) > last_start) {
            last_start = static_cast<std::int64_t>(offset);
            last_part = part;
        }
    }
    // A file cut short lost its last chunks, whose offsets are still plausible;
    // an overwritten table holds anything (0xff... say).
    if (past_end && last_past_end < kPlausibleFileBytes)
        return fmt::format("truncated: {} of {} chunks start past the end of the file ({} bytes)", past_end,
                           total, file_size);
    if (past_end)
        return fmt::format(
            "damaged chunk offset table: {} of {} chunks point past the end of the file ({} bytes)", past_end,
            total, file_size);
    if (unwritten)
        return fmt::format(
            "incomplete: {} of {} chunks were never written (their offsets are 0; the writer stopped "
            "early)",
            unwritten, total);
    if (into_header)
        return fmt::format("damaged chunk offset table: {} of {} chunks point into the header", into_header,
                           total);
    if (last_start < 0)
        return {};
    std::string problem;
    const std::int64_t end = chunk_end(in, last_start, parts[last_part], headers.multipart, problem);
    if (!problem.empty())
        return problem;
    if (end < 0 || end > file_size)
        return fmt::format("truncated: the last chunk (at byte {}) runs past the end of the file ({} bytes)",
                           last_start, file_size);
    return {};
}

} // namespace modestack::io::detail
