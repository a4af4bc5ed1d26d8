// The Gram sums of a shot in fixed blocks of kStageBlockRows image rows, merged
// in block order: the one summation order that a whole run and a farm of
// statistics tasks (stage_task.h) share, so both give the same bits.
#pragma once

#include "core/denoise/stage_task.h"
#include "core/lowrank/band.h"
#include "core/lowrank/gram.h"

#include <optional>
#include <vector>

namespace modestack::denoise {

class BlockGram {
public:
    /// `keep_blocks`: keep each finished block (a statistics task) instead of
    /// merging it into the total right away (a whole run: O(F²) memory).
    BlockGram(int frames, bool keep_blocks);
    /// Adds sample rows that all lie in image row `image_row`'s block; image rows
    /// must not go down from call to call.
    void add(int image_row, const lowrank::BandView& rows);
    /// Closes the last block; then total() or blocks() hold the result.
    void finish();
    const lowrank::GramAccumulator& total() const { return m_total; }
    std::vector<lowrank::GramAccumulator>& blocks() { return m_blocks; }

    /// The blocks merged in order into an empty accumulator, as a whole run does.
    static lowrank::GramAccumulator merge(const std::vector<lowrank::GramAccumulator>& blocks, int frames);

private:
    void close_block();

    int m_frames;
    bool m_keep_blocks;
    int m_block = -1;
    std::optional<lowrank::GramAccumulator> m_current;
    lowrank::GramAccumulator m_total;
    std::vector<lowrank::GramAccumulator> m_blocks;
};

}  // namespace modestack::denoise
