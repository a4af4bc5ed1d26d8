// The working-memory budget of `denoise --max-memory`: a size, or "auto" for a
// share of what this machine (or the container's memory limit) has, so that a
// shot which fits is read once and kept, while a farm node running several jobs
// still has room for them.
#pragma once

#include "io/sequence_reader.h"

#include <cstdint>
#include <string>
#include <vector>

namespace modestack::app {

/// A quarter of the physical memory, or of the cgroup's memory.max when that is
/// smaller (containers, farm slots); at least 512 MiB.
std::int64_t automatic_memory_budget();

/// "auto" → automatic_memory_budget(); otherwise parse_memory_size(text, option).
std::int64_t parse_memory_budget(const std::string& text, const std::string& option);

/// What OpenEXR holds for the feature guide's layers (opened again as their own
/// sequences): the files of the `frames` frames whose rows it reads.
struct GuideFiles {
    std::vector<const io::SequenceReader*> readers;
    int frames = 0;
};

/// The part of `max_memory_bytes` left for the denoise engine's plan, when the
/// budget is the whole process's: minus what the process holds already (the
/// program and its libraries, about 130 MiB with Debian's OpenImageIO, the
/// opened inputs and guide layers), what the decoder will hold per input file
/// once read (io::SequenceReader::decoder_buffer_bytes: nothing on libdeflate's
/// path) for every input and the guide files read, and `output_bytes`, what the
/// open outputs hold (SequenceSink::open_output_bytes). Throws a usage error
/// naming --max-memory when nothing is left.
std::int64_t engine_memory_budget(std::int64_t max_memory_bytes, const io::SequenceReader& reader,
                                  std::int64_t output_bytes, const GuideFiles& guides = {});

/// Tells the C library to keep freed blocks of up to 32 MiB (glibc's largest
/// mmap threshold) in its heap for reuse instead of returning them to the kernel:
/// the engine allocates the same scratch buffers for every band, and each fresh
/// mapping costs a page fault and a zeroed page per 4 KiB (page zeroing was 7 %
/// of a denoise profile). Peak memory is unchanged.
void reuse_freed_memory();

}  // namespace modestack::app
