// The fixed parts of the --report page: its style sheet and its script. The
// script reads the page's JSON data block, decodes the embedded PNGs on
// canvases, tonemaps the log-encoded HDR images with the exposure control,
// keeps the zoom and pan of the side-by-side panels in step, and rebuilds the
// rank slider's preview Σ_{j<n} c_j pt(t, j) from the quantized coefficient
// images as the slider moves. Plain JavaScript, no library.
#pragma once

namespace modestack::app::report {

/// The page's CSS.
const char* page_style();
/// The page's JavaScript. Sets window.reportReady = true once every image is
/// drawn, and window.reportFailure to a message (also logged) if that fails.
const char* page_script();

}  // namespace modestack::app::report
