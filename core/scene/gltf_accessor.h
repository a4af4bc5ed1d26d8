// Reading glTF accessors into plain arrays, with every check a damaged file needs:
// accessor, buffer view and buffer indices in range, the element type expected,
// and the data inside its buffer view and buffer (a short .bin fails here, with
// the accessor named, not with a crash). Sparse accessors are applied.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace tinygltf {
class Model;
}

namespace modestack::scene {

/// Accessor `index` as `components` floats per element (FLOAT, or normalised
/// integers converted as glTF says). `what` names its use in errors ("positions of
/// mesh 'floor'"). Throws a bad-input error naming `file` on any inconsistency.
std::vector<float> read_float_accessor(const tinygltf::Model& model, int index, int components,
                                       const std::string& file, const std::string& what);

/// Index accessor `index` (unsigned byte, short or int scalars); every index must be
/// below `vertex_count`. Throws a bad-input error naming `file` otherwise.
std::vector<std::uint32_t> read_index_accessor(const tinygltf::Model& model, int index,
                                               std::size_t vertex_count, const std::string& file,
                                               const std::string& what);

} // namespace modestack::scene
