// PassThroughRows (frame_stream.h): what a source's read kept of a frame's other
// channels is handed to the sink only for rows it covers, at the right offset.
#include "core/denoise/frame_stream.h"

#include <doctest/doctest.h>

using modestack::denoise::PassThroughRows;

TEST_CASE("pass-through rows: the bytes of covered rows at their offset, null for rows not kept")
{
    PassThroughRows kept;
    CHECK(kept.rows(0, 1, 4) == nullptr);  // nothing kept
    kept.row_begin = 10;
    kept.row_end = 14;
    kept.bytes.resize(4 * 6);  // 4 rows of 6 bytes
    for (std::size_t i = 0; i < kept.bytes.size(); ++i)
        kept.bytes[i] = static_cast<unsigned char>(i);
    CHECK(kept.rows(10, 14, 6) == kept.bytes.data());
    REQUIRE(kept.rows(12, 13, 6) != nullptr);
    CHECK(*kept.rows(12, 13, 6) == 12);  // row 12 starts 2 rows in
    CHECK(kept.rows(9, 12, 6) == nullptr);   // starts above the kept rows
    CHECK(kept.rows(13, 15, 6) == nullptr);  // ends below them
}
