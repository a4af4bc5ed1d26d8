#include "core/denoise/stage_task.h"

namespace modestack::denoise {

const char* stage_name(Stage stage)
{
    switch (stage) {
    case Stage::Statistics: return "stats";
    case Stage::Solve: return "solve";
    default: return "write";
    }
}

}  // namespace modestack::denoise
