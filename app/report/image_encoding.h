// How the report's HDR images travel inside an HTML page: as 8-bit PNG data:
// URIs that the page decodes on a canvas. Images to look at (noisy, denoised,
// sigma) are log-encoded (a fixed number of stops below the image's bright end
// over 255 levels), so the page can change their exposure; the rank slider's
// coefficient images are quantized linearly with a per-image offset and scale,
// so that the page can add them up. Grey images (R = G = B everywhere) travel
// as one channel. Includes the base64 coding of data: URIs.
#pragma once

#include "app/report/report_data.h"
#include "io/png_encoding.h"

#include <cstdint>
#include <string>
#include <vector>

namespace modestack::app::report {

/// Standard base64 (RFC 4648, with '=' padding).
std::string base64_encode(const std::vector<std::uint8_t>& bytes);
/// Decodes standard base64; throws a usage error on a character outside the alphabet.
std::vector<std::uint8_t> base64_decode(const std::string& text);

/// "data:image/png;base64,..." of `image`.
std::string png_data_uri(const io::Image8& image);

/// A log-encoded image: code q > 0 stands for 2^(low + q / 255 · (high − low)), 0 for
/// anything at or below 2^low (black, zero and negative values).
struct LogImage {
    io::Image8 image;
    double low = 0;   ///< log2 of the darkest value kept
    double high = 0;  ///< log2 of the brightest value kept
};

/// Log-encodes `image` over `stops` stops below its bright end: the 99.9th
/// percentile of its largest channel, times 4 (a few fireflies clip, the rest fit).
LogImage log_encode(const LinearImage& image, double stops = 16.0);
/// The value code `code` stands for in `encoded`.
double log_decode(const LogImage& encoded, int code);

/// A linearly quantized image: value = offset + scale · q.
struct QuantizedImage {
    io::Image8 image;
    double offset = 0;
    double scale = 1;
};

/// Quantizes `image` between its smallest and largest finite value: every value
/// is within scale / 2 of its code's value.
QuantizedImage quantize(const LinearImage& image);

}  // namespace modestack::app::report
