#include "app/run_composite.h"

#include "app/command.h"
#include "io/frame_output.h"

#include <memory>

namespace modestack::app {

const std::vector<std::string> kPassLayers{"DiffCol", "DiffDir", "DiffInd", "Emit"};

std::vector<float> read_frame(const io::SequenceReader& reader, int frame_index)
{
    std::vector<float> values(static_cast<std::size_t>(reader.width()) * reader.height() *
                              reader.selected_channel_count());
    reader.read_selected(frame_index, 0, reader.height(), values.data());
    return values;
}

std::vector<float> composite(const std::vector<float>& passes, const float* indirect)
{
    std::size_t pixels = passes.size() / 12;
    std::vector<float> beauty(pixels * 3);
    for (std::size_t p = 0; p < pixels; ++p)
        for (int c = 0; c < 3; ++c) {
            const float* pass = passes.data() + p * 12;
            float diffuse_indirect = indirect ? indirect[p * 3 + c] : pass[6 + c];
            beauty[p * 3 + c] = pass[c] * (pass[3 + c] + diffuse_indirect) + pass[9 + c];
        }
    return beauty;
}

void write_final(const io::FrameSequence& refined, const io::FrameSequence& final_sequence,
                 Progress& progress)
{
    io::SequenceReader beauty(refined, {"Combined"});
    io::SequenceReader passes(refined, kPassLayers);
    std::vector<io::HeaderAttribute> attributes{
        io::HeaderAttribute::of_text("modestack:version", MODESTACK_VERSION),
        io::HeaderAttribute::of_text("modestack:command", command_line()),
        io::HeaderAttribute::of_text("modestack:composite",
                                     "Combined = DiffCol * (DiffDir + DiffInd) + Emit"),
    };
    std::vector<std::unique_ptr<io::FrameOutput>> outputs;
    std::vector<unsigned char> native;
    progress.begin("compositing the final beauty", beauty.frame_count());
    for (int i = 0; i < beauty.frame_count(); ++i) {
        std::vector<float> rgb = composite(read_frame(passes, i), nullptr);
        beauty.read_native(i, 0, beauty.height(), native);
        outputs.push_back(std::make_unique<io::FrameOutput>(final_sequence.files[i], beauty, i,
                                                            std::vector<std::string>{}, attributes));
        outputs.back()->write_replaced_rows(0, beauty.height(), native, rgb.data(), nullptr);
        progress.advance();
    }
    for (auto& output : outputs)
        output->commit();
    progress.end();
}

}  // namespace modestack::app
