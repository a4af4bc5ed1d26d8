#include "io/contact_sheet.h"

#include "core/common/error.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <system_error>
#include <unistd.h>

namespace modestack::io {
namespace {

std::uint8_t to_srgb_byte(float linear, float scale)
{
    double v = std::clamp(static_cast<double>(linear) * scale, 0.0, 1.0);
    if (!std::isfinite(v))
        v = 0.0;
    double encoded = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
    return static_cast<std::uint8_t>(std::lround(encoded * 255.0));
}

} // namespace

void write_contact_sheet(const std::string& path, int columns, const std::vector<ContactSheetCell>& cells,
                         double exposure_stops, int gap)
{
    if (cells.empty() || columns < 1)
        throw usage_error("a contact sheet needs at least one image");
    const int cell_width = cells.front().width, cell_height = cells.front().height;
    for (const auto& cell : cells)
        if (cell.width != cell_width || cell.height != cell_height || cell.rgb == nullptr)
            throw usage_error("the images of a contact sheet must all have the same size");
    const int rows = static_cast<int>((cells.size() + columns - 1) / columns);
    const int width = columns * cell_width + (columns + 1) * gap;
    const int height = rows * cell_height + (rows + 1) * gap;
    std::vector<std::uint8_t> pixels(static_cast<std::size_t>(width) * height * 3, 24);
    const float scale = static_cast<float>(std::exp2(exposure_stops));
    for (std::size_t i = 0; i < cells.size(); ++i) {
        int x0 = gap + static_cast<int>(i % columns) * (cell_width + gap);
        int y0 = gap + static_cast<int>(i / columns) * (cell_height + gap);
        for (int y = 0; y < cell_height; ++y)
            for (int x = 0; x < cell_width; ++x)
                for (int c = 0; c < 3; ++c)
                    pixels[((static_cast<std::size_t>(y0 + y)) * width + x0 + x) * 3 + c] = to_srgb_byte(
                        cells[i].rgb[(static_cast<std::size_t>(y) * cell_width + x) * 3 + c], scale);
    }
    std::filesystem::path final_path(path);
    std::string temporary = (final_path.parent_path() /
                             fmt::format(".{}.{}.modestack-tmp", final_path.filename().string(), getpid()))
                                .string();
    auto output = OIIO::ImageOutput::create("png");
    if (!output)
        throw internal_error("OpenImageIO has no PNG writer");
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", "sRGB");
    if (!output->open(temporary, spec) || !output->write_image(OIIO::TypeDesc::UINT8, pixels.data()) ||
        !output->close()) {
        std::string reason = output->geterror();
        std::error_code ignored;
        std::filesystem::remove(temporary, ignored);
        throw bad_input(path, fmt::format("cannot write the contact sheet ({})", reason));
    }
    std::error_code error;
    std::filesystem::rename(temporary, path, error);
    if (error)
        throw bad_input(path,
                        fmt::format("cannot rename the contact sheet into place ({})", error.message()));
}

} // namespace modestack::io
