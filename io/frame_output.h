// The output side: one EXR frame written under a temporary name in its target
// directory and renamed to its final name only by commit(), so a crash, a
// full disk or an interrupt never leaves a final-named file that is incomplete.
// A denoise output copies its input frame's header (channels, pixel types,
// windows, attributes) and, by default, its parts (a multi-part input gives a
// multi-part output, each added channel in the part of its layer); its
// compression, the type of what it writes anew and which input channels it
// keeps follow an OutputFormat (output_format.h). A render output is described
// from scratch.
#pragma once

#include "io/exr_codec.h"
#include "io/output_format.h"

#include <memory>
#include <string>
#include <vector>

namespace modestack::io {

class SequenceReader;
namespace detail {
struct OpenFrame;
}

/// One header attribute added to an output (provenance: modestack:*).
struct HeaderAttribute {
    enum class Kind { Text, Integer, Real };
    std::string name;
    Kind kind = Kind::Text;
    std::string text;
    long long integer = 0;
    double real = 0.0;

    static HeaderAttribute of_text(std::string name, std::string value);
    static HeaderAttribute of_integer(std::string name, long long value);
    static HeaderAttribute of_real(std::string name, double value);
};

/// How an output copied from a multi-part input is laid out.
enum class PartLayout {
    AsInput,    ///< the input's parts, names, headers; added channels in their layer's part
    SinglePart, ///< one part holding every channel under its layer-prefixed name (--single-part)
};

/// A new image described from scratch (used by the renderer).
struct NewImageDescription {
    int width = 0;
    int height = 0;
    std::vector<std::string> channel_names;
    std::vector<std::string> channel_types;  ///< "half" or "float", one per channel
    std::string compression = "zip";
};

/// An output frame under construction.
class FrameOutput {
public:
    /// An output that copies frame `frame_index` of `reader` (every channel,
    /// pixel type, window and attribute), with `extra_channels` appended in the
    /// pixel type of the first selected channel (an input channel of the same
    /// name is dropped: they replace it), plus `attributes`; `format`
    /// changes the compression (by default the input's when lossless, else
    /// ZIP), the type of the replaced and appended channels, and may keep only
    /// those. Tiled inputs (and tiled parts) are written as scanline files;
    /// `codec` encodes a ZIP/ZIPS copy of a single-part ZIP/ZIPS scanline
    /// input; a multi-part input is copied part by part with OpenEXR's library
    /// (detail/multipart_writer.h) unless `parts` flattens it. `reader` must
    /// outlive this object.
    FrameOutput(const std::string& path, const SequenceReader& reader, int frame_index,
                const std::vector<std::string>& extra_channels,
                const std::vector<HeaderAttribute>& attributes, ExrCodec codec = ExrCodec::Libdeflate,
                PartLayout parts = PartLayout::AsInput, const OutputFormat& format = {});
    /// An output for a new image (always written with OpenImageIO).
    FrameOutput(const std::string& path, const NewImageDescription& image,
                const std::vector<HeaderAttribute>& attributes);
    /// Removes the temporary file unless commit() succeeded.
    ~FrameOutput();
    FrameOutput(const FrameOutput&) = delete;
    FrameOutput& operator=(const FrameOutput&) = delete;

    /// Writes rows [row_begin, row_end) (in increasing order, band after band)
    /// of a copied frame: `input_native` holds those rows of every input channel
    /// in native types (SequenceReader::read_native), `replaced` the new values
    /// of the selected channels and `extra` the appended channels, both float,
    /// interleaved [row][x][channel]. `input_native` may be empty when
    /// needs_input_rows() is false.
    void write_replaced_rows(int row_begin, int row_end, const std::vector<unsigned char>& input_native,
                             const float* replaced, const float* extra);
    /// The same with the native rows as a pointer (nullptr when needs_input_rows() is false).
    void write_replaced_rows(int row_begin, int row_end, const unsigned char* input_native, const float* replaced,
                             const float* extra);
    /// Whether a copied frame has channels that are passed through (not replaced),
    /// i.e. whether write_replaced_rows needs the input's native rows.
    bool needs_input_rows() const;
    /// Writes rows of a new image from float data, all channels interleaved.
    void write_float_rows(int row_begin, int row_end, const float* pixels);
    /// Closes the file and renames it to its final name. Throws Error on failure.
    void commit();

    const std::string& path() const { return m_path; }

private:
    void open(const void* spec);
    // Store the replaced and extra values of `pixels` pixels in the output pixels at `out`.
    void place_halves(size_t pixels, const float* replaced, const float* extra, unsigned char* out) const;
    void place_values(size_t pixels, const float* replaced, const float* extra, unsigned char* out) const;
    void fail(const std::string& what);

    std::string m_path;
    std::string m_temporary_path;
    struct State;
    std::unique_ptr<State> m_state;
    bool m_committed = false;
};

/// Bytes an output made by FrameOutput's copying constructor with these
/// arguments holds while it is open: the chunk being filled when libdeflate
/// writes it, else OpenEXR's three chunks of scanlines (in the input's chunk
/// height). What --max-memory counts per output file.
std::int64_t copy_buffer_bytes(const SequenceReader& reader, int frame_index,
                               const std::vector<std::string>& extra_channels, ExrCodec codec,
                               PartLayout parts = PartLayout::AsInput, const OutputFormat& format = {});

/// Checks before any work: no output is also an input; each output directory
/// exists (it is created if missing) and is writable. Throws Error otherwise.
void check_outputs(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs);

}  // namespace modestack::io
