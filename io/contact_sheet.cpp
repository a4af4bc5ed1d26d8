#include "io/contact_sheet.h"

#include "core/common/error.h"
#include "io/temporary_file.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <system_error>

namespace modestack::io {
namespace {

std::uint8_t to_byte(float encoded)
{
    if (!std::isfinite(encoded))
        return 0;
    return static_cast<std::uint8_t>(std::lround(std::clamp(encoded, 0.0f, 1.0f) * 255.0f));
}

} // namespace

void write_contact_sheet(const std::string& path, int columns, const std::vector<ContactSheetCell>& cells,
                         const DisplayConverter& display, int gap)
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
    std::vector<float> encoded(static_cast<std::size_t>(cell_width) * cell_height * 3);
    for (std::size_t i = 0; i < cells.size(); ++i) {
        std::copy(cells[i].rgb, cells[i].rgb + encoded.size(), encoded.begin());
        display.apply(encoded.data(), encoded.size() / 3);
        int x0 = gap + static_cast<int>(i % columns) * (cell_width + gap);
        int y0 = gap + static_cast<int>(i / columns) * (cell_height + gap);
        for (int y = 0; y < cell_height; ++y)
            for (int x = 0; x < cell_width; ++x)
                for (int c = 0; c < 3; ++c)
                    pixels[((static_cast<std::size_t>(y0 + y)) * width + x0 + x) * 3 + c] =
                        to_byte(encoded[(static_cast<std::size_t>(y) * cell_width + x) * 3 + c]);
    }
    std::filesystem::path final_path(path);
    remove_stale_temporaries(path);
    std::string temporary = temporary_path_for(path);
    auto output = OIIO::ImageOutput::create("png");
    if (!output)
        throw internal_error("OpenImageIO has no PNG writer");
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", display.encoded_color_space());
    spec.attribute("modestack:display", display.display());
    spec.attribute("modestack:view", display.view());
    spec.attribute("modestack:exposure", fmt::format("{} stops", display.exposure_stops()));
    spec.attribute("modestack:ocio_config", display.config_path());
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
