// One notice per kind (see gltf_notices.h).
#include "core/scene/gltf_notices.h"

#include <algorithm>

namespace modestack::scene {

void GltfNotices::add(const std::string& message)
{
    if (std::find(m_messages.begin(), m_messages.end(), message) == m_messages.end())
        m_messages.push_back(message);
}

bool GltfNotices::contains(const std::string& fragment) const
{
    return std::any_of(m_messages.begin(), m_messages.end(), [&](const std::string& message) {
        return message.find(fragment) != std::string::npos;
    });
}

} // namespace modestack::scene
