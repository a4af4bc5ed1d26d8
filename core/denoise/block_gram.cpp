#include "core/denoise/block_gram.h"

#include "core/common/error.h"

namespace modestack::denoise {

BlockGram::BlockGram(int frames, bool keep_blocks) : m_frames(frames), m_keep_blocks(keep_blocks), m_total(frames) {}

void BlockGram::add(int image_row, const lowrank::BandView& rows)
{
    const int block = image_row / kStageBlockRows;
    if (block < m_block)
        throw internal_error("BlockGram::add: rows went back to an earlier block");
    if (block != m_block) {
        close_block();
        m_current.emplace(m_frames);
        m_block = block;
    }
    m_current->add(rows);
}

void BlockGram::close_block()
{
    if (!m_current)
        return;
    if (m_keep_blocks)
        m_blocks.push_back(std::move(*m_current));
    else
        m_total.merge(*m_current);
    m_current.reset();
}

void BlockGram::finish() { close_block(); }

lowrank::GramAccumulator BlockGram::merge(const std::vector<lowrank::GramAccumulator>& blocks, int frames)
{
    lowrank::GramAccumulator total(frames);
    for (const lowrank::GramAccumulator& block : blocks)
        total.merge(block);
    return total;
}

}  // namespace modestack::denoise
