// A glTF material as the tracer's Lambertian one: albedo = base colour factor ×
// the average colour of the base colour texture (if any), emission =
// emissiveFactor × KHR_materials_emissive_strength (× the emissive texture's
// average). What cannot be rendered that way (metal, roughness, normal maps,
// transparency, textures as detail) is reported once in the notices.
#pragma once

#include "core/scene/gltf_notices.h"
#include "core/scene/scene.h"

namespace tinygltf {
class Model;
}

namespace modestack::scene {

/// Material `index` of `model` (−1: glTF's default material, white).
Material gltf_material(const tinygltf::Model& model, int index, GltfNotices& notices);

/// The average linear colour of an 8- or 16-bit sRGB-encoded RGB(A) image, or
/// white when the image has no decoded pixels. `bits` is 8 or 16.
Vec3 average_srgb_colour(const unsigned char* pixels, int width, int height, int components, int bits);

} // namespace modestack::scene
