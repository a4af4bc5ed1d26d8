// A PNG contact sheet for looking at a run at a glance: rows of frames, columns
// of versions (noisy | denoised | refined | reference), each scene-linear RGB
// image shown through the OCIO config's display/view (io/color_management.h)
// after an exposure, clipped to [0, 1]. This is a preview, not a grade.
#pragma once

#include "io/color_management.h"

#include <string>
#include <vector>

namespace modestack::io {

/// One image of the sheet: width × height pixels of scene-linear RGB, interleaved, y = 0 at the top.
struct ContactSheetCell {
    int width = 0;
    int height = 0;
    const float* rgb = nullptr;
};

/// Writes `cells` (row-major, `columns` per row, all the same size) as an 8-bit
/// PNG at `path`, atomically, with a `gap`-pixel dark border between cells.
/// Each value goes through `display` (its exposure, then its display/view);
/// the PNG records the display's encoding (oiio:ColorSpace) and the display,
/// view and config (modestack:* text). Throws Error (bad input) naming `path`
/// when it cannot be written, and a usage error when the cells are empty or
/// differ in size.
void write_contact_sheet(const std::string& path, int columns, const std::vector<ContactSheetCell>& cells,
                         const DisplayConverter& display, int gap = 4);

} // namespace modestack::io
