// A PNG contact sheet for looking at a run at a glance: rows of frames, columns
// of versions (noisy | denoised | refined | reference), each linear RGB image
// shown with a simple exposure and the sRGB transfer curve, clipped to [0, 1].
// Colour management (OCIO) comes later; this is a preview, not a grade.
#pragma once

#include <string>
#include <vector>

namespace modestack::io {

/// One image of the sheet: width × height pixels of linear RGB, interleaved, y = 0 at the top.
struct ContactSheetCell {
    int width = 0;
    int height = 0;
    const float* rgb = nullptr;
};

/// Writes `cells` (row-major, `columns` per row, all the same size) as an 8-bit
/// sRGB PNG at `path`, atomically, with a `gap`-pixel dark border between cells.
/// Each value is multiplied by 2^exposure_stops before the transfer curve.
/// Throws Error (bad input) naming `path` when it cannot be written, and a usage
/// error when the cells are empty or differ in size.
void write_contact_sheet(const std::string& path, int columns, const std::vector<ContactSheetCell>& cells,
                         double exposure_stops = 0.0, int gap = 4);

} // namespace modestack::io
