// glTF materials as Lambertian ones (see gltf_materials.h).
#include "core/scene/gltf_materials.h"

#include <fmt/format.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace modestack::scene {
namespace {

// The highest albedo kept: the tracer needs albedo < 1 for its paths to end.
constexpr float kMaxAlbedo = 0.99f;

double srgb_to_linear(double v)
{
    return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

// The average colour of texture `texture_index`, or white (with a notice) when its
// image could not be decoded.
Vec3 texture_average(const tinygltf::Model& model, int texture_index, const char* use, GltfNotices& notices)
{
    notices.add(fmt::format("{} textures are replaced by their average colour (no texture lookups)", use));
    if (texture_index < 0 || static_cast<std::size_t>(texture_index) >= model.textures.size())
        return {1, 1, 1};
    int source = model.textures[texture_index].source;
    if (source < 0 || static_cast<std::size_t>(source) >= model.images.size() ||
        model.images[source].image.empty()) {
        notices.add(fmt::format("a {} texture has no decoded image: its factor alone is used", use));
        return {1, 1, 1};
    }
    const tinygltf::Image& image = model.images[source];
    return average_srgb_colour(image.image.data(), image.width, image.height, image.component, image.bits);
}

Vec3 factor3(const std::vector<double>& factor, Vec3 fallback)
{
    if (factor.size() < 3)
        return fallback;
    return {static_cast<float>(factor[0]), static_cast<float>(factor[1]), static_cast<float>(factor[2])};
}

} // namespace

Vec3 average_srgb_colour(const unsigned char* pixels, int width, int height, int components, int bits)
{
    if (!pixels || width <= 0 || height <= 0 || components <= 0 || (bits != 8 && bits != 16))
        return {1, 1, 1};
    double sum[3] = {0, 0, 0};
    std::size_t count = static_cast<std::size_t>(width) * height;
    std::size_t bytes = bits / 8;
    for (std::size_t p = 0; p < count; ++p)
        for (int c = 0; c < 3; ++c) {
            int channel = components >= 3 ? c : 0; // grey images: one channel for R, G, B
            const unsigned char* value = pixels + (p * components + channel) * bytes;
            double v;
            if (bytes == 1) {
                v = *value / 255.0;
            } else {
                std::uint16_t raw;
                std::memcpy(&raw, value, 2);
                v = raw / 65535.0;
            }
            sum[c] += srgb_to_linear(v);
        }
    return {static_cast<float>(sum[0] / count), static_cast<float>(sum[1] / count),
            static_cast<float>(sum[2] / count)};
}

Material gltf_material(const tinygltf::Model& model, int index, GltfNotices& notices)
{
    Material material;
    if (index < 0 || static_cast<std::size_t>(index) >= model.materials.size()) {
        material.albedo = {kMaxAlbedo, kMaxAlbedo, kMaxAlbedo}; // glTF's default material is white
        return material;
    }
    const tinygltf::Material& source = model.materials[index];
    const auto& pbr = source.pbrMetallicRoughness;
    Vec3 albedo = factor3(pbr.baseColorFactor, {1, 1, 1});
    if (pbr.baseColorTexture.index >= 0)
        albedo = albedo * texture_average(model, pbr.baseColorTexture.index, "base colour", notices);
    if (albedo.x > kMaxAlbedo || albedo.y > kMaxAlbedo || albedo.z > kMaxAlbedo)
        notices.add(fmt::format("base colours above {} are clamped to {} (the tracer needs albedo < 1)",
                                kMaxAlbedo, kMaxAlbedo));
    material.albedo = {std::clamp(albedo.x, 0.0f, kMaxAlbedo), std::clamp(albedo.y, 0.0f, kMaxAlbedo),
                       std::clamp(albedo.z, 0.0f, kMaxAlbedo)};

    Vec3 emission = factor3(source.emissiveFactor, {0, 0, 0});
    auto strength = source.extensions.find("KHR_materials_emissive_strength");
    if (strength != source.extensions.end() && strength->second.Has("emissiveStrength"))
        emission =
            emission * static_cast<float>(strength->second.Get("emissiveStrength").GetNumberAsDouble());
    if (source.emissiveTexture.index >= 0 && max_component(emission) > 0)
        emission = emission * texture_average(model, source.emissiveTexture.index, "emissive", notices);
    material.emission = {std::max(emission.x, 0.0f), std::max(emission.y, 0.0f), std::max(emission.z, 0.0f)};
    if (material.is_emissive() && source.doubleSided)
        notices.add("double-sided emissive materials emit from their front side only");

    if (pbr.metallicFactor > 0 || pbr.metallicRoughnessTexture.index >= 0 || pbr.roughnessFactor < 1 ||
        source.normalTexture.index >= 0 || source.occlusionTexture.index >= 0)
        notices.add(
            "materials are rendered as diffuse (Lambertian): metallic, roughness, normal and occlusion "
            "maps are ignored");
    if (source.alphaMode != "OPAQUE" || (pbr.baseColorFactor.size() == 4 && pbr.baseColorFactor[3] < 1))
        notices.add("transparency (alphaMode BLEND/MASK, base colour alpha) is ignored: surfaces are opaque");
    return material;
}

} // namespace modestack::scene
