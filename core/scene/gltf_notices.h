// What a glTF scene uses that modestack does not render exactly: each kind of
// approximation or unsupported feature is collected once (however many nodes,
// materials or lights it concerns) so that `render --scene FILE.gltf` can print
// one clear line per kind on stderr instead of ignoring it silently.
#pragma once

#include <string>
#include <vector>

namespace modestack::scene {

/// An ordered set of one-line notices, each kept once.
class GltfNotices {
public:
    /// Records `message` unless the same message is already recorded.
    void add(const std::string& message);
    /// The notices in the order they were first recorded.
    const std::vector<std::string>& messages() const { return m_messages; }
    /// True if a notice containing `fragment` was recorded (for tests).
    bool contains(const std::string& fragment) const;

private:
    std::vector<std::string> m_messages;
};

} // namespace modestack::scene
