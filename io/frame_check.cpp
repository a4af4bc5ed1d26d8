// The chunk table check is detail/exr_chunk_table.h. The decode reads each
// part and MIP level in strips of whole chunks through
// OpenImageIO, in native pixel types, into a buffer of bounded size. A chunk
// whose data does not decode (ZIP's checksum, a leader that names the wrong
// row, a size past the end) fails the read with the library's reason.
// Uncompressed data has no checksum: bytes overwritten there decode.
#include "io/frame_check.h"

#include "io/detail/exr_chunk_table.h"
#include "io/detail/open_image.h"

#include <OpenImageIO/deepdata.h>
#include <fmt/format.h>

#include <algorithm>
#include <vector>

namespace modestack::io {
namespace {

// Bytes decoded per read: one strip of rows (a row of tiles at least).
constexpr std::size_t kStripBytes = 32u << 20;
// A row (of tiles) wider than this is not decoded: no real image has one, and a
// 489-byte file whose header declares 234 million pixels a row made the check
// allocate and zero 2 GB (found by afl).
constexpr std::size_t kLargestRowBytes = 256u << 20;

std::string one_line(std::string text)
{
    std::replace(text.begin(), text.end(), '\n', ' ');
    while (!text.empty() && text.back() == ' ')
        text.pop_back();
    return text.empty() ? std::string("damaged data") : text;
}

// Decodes every row of the current part and level of `input`; the problem, or "".
std::string decode_level(OIIO::ImageInput& input, int part, int level, const std::string& where)
{
    const OIIO::ImageSpec spec = input.spec(part, level);
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
        return {};
    const std::size_t row_bytes = spec.pixel_bytes(true) * static_cast<std::size_t>(spec.width);
    const int unit = std::max(1, spec.tile_height);
    if (!spec.deep && row_bytes * static_cast<std::size_t>(unit) * std::max(1, spec.depth) > kLargestRowBytes)
        return fmt::format("{}rows of {} pixels ({} bytes each): wider than any image this can check", where,
                           spec.width, row_bytes);
    const int units = static_cast<int>(std::max<std::size_t>(1, kStripBytes / (row_bytes * unit + 1)));
    const int strip_rows = std::min(spec.height, unit * units);
    std::vector<unsigned char> buffer;
    if (!spec.deep)
        buffer.resize(row_bytes * static_cast<std::size_t>(strip_rows) * std::max(1, spec.depth));
    const int z_end = spec.z + std::max(1, spec.depth);
    for (int y = spec.y; y < spec.y + spec.height; y += strip_rows) {
        const int y_end = std::min(y + strip_rows, spec.y + spec.height);
        bool ok = false;
        if (spec.deep) {
            OIIO::DeepData deep;
            ok = spec.tile_width ? input.read_native_deep_tiles(part, level, spec.x, spec.x + spec.width, y,
                                                                y_end, spec.z, z_end, 0, spec.nchannels, deep)
                                 : input.read_native_deep_scanlines(part, level, y, y_end, spec.z, 0,
                                                                    spec.nchannels, deep);
        } else if (spec.tile_width) {
            ok = input.read_tiles(part, level, spec.x, spec.x + spec.width, y, y_end, spec.z, z_end, 0,
                                  spec.nchannels, OIIO::TypeUnknown, buffer.data());
        } else {
            ok = input.read_scanlines(part, level, y, y_end, spec.z, 0, spec.nchannels, OIIO::TypeUnknown,
                                      buffer.data());
        }
        if (!ok)
            return fmt::format("cannot decode {}rows {}-{} ({})", where, y - spec.y, y_end - spec.y - 1,
                               one_line(input.geterror()));
    }
    return {};
}

} // namespace

std::string check_chunk_tables(const std::string& file)
{
    return detail::exr_chunk_table_problem(file);
}

std::string check_every_chunk(const std::string& file)
{
    std::string reason;
    auto input = detail::open_image(file, reason);
    if (!input)
        return fmt::format("cannot read image header ({})", one_line(reason));
    const bool several_parts = input->seek_subimage(1, 0);
    for (int part = 0; input->seek_subimage(part, 0); ++part)
        for (int level = 0; input->seek_subimage(part, level); ++level) {
            std::string where = several_parts ? fmt::format("part {}, ", part) : std::string();
            if (level > 0)
                where += fmt::format("MIP level {}, ", level);
            if (std::string problem = decode_level(*input, part, level, where); !problem.empty())
                return problem;
        }
    return {};
}

} // namespace modestack::io
