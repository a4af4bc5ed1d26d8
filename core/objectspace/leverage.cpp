// Leverages of the frames in the rebuild (see leverage.h).
#include "core/objectspace/leverage.h"

#include <cstddef>

namespace modestack::objectspace {

std::vector<double> frame_leverages(const std::vector<std::vector<double>>& temporal_modes, int frames)
{
    std::vector<double> leverages;
    for (int t = 0; t < frames; ++t) {
        double leverage = 0;
        for (const std::vector<double>& mode : temporal_modes)
            leverage += mode[static_cast<std::size_t>(t)] * mode[static_cast<std::size_t>(t)];
        leverages.push_back(leverage);
    }
    return leverages;
}

} // namespace modestack::objectspace
