// KHR_lights_punctual lights as the tracer's emitters (it has area lights only).
// Photometric to radiometric: intensity / 683 (candela → W/sr, lux → W/m²). A
// point light becomes a sphere of radius kPointLightRadius whose radiance gives the
// same mean intensity and power (L = I / (683 A / 4), A the tessellated sphere's
// area, ≈ I / (683 π r²)); a spot light a square of side kSpotLightSide
// facing the spot's direction, with the same on-axis intensity (L = I / (683 s²))
// and a cosine lobe instead of the cone; a directional light a square of side 2R
// at distance 2R from the centre of the scene's bounding sphere (radius R), facing
// along the light, with radiance E / (683 Ω), Ω ≈ 0.8 sr its solid angle seen
// from the centre, so that it gives about the light's illuminance there (a closed
// room blocks it). The loader reports each approximation once.
#pragma once

#include "core/scene/gltf_scene.h"

namespace modestack::scene {

/// Radius of the sphere that stands in for a point light (metres).
inline constexpr float kPointLightRadius = 0.05f;
/// Side of the square that stands in for a spot light (metres).
inline constexpr float kSpotLightSide = 0.05f;

/// The emitter for `light` placed by `world` (its node's world transform; the
/// light shines along the node's −z). `scene_center` and `scene_radius` bound the
/// scene's geometry (used by directional lights only).
Mesh gltf_light_mesh(const GltfLight& light, const Mat4& world, Vec3 scene_center, float scene_radius);

} // namespace modestack::scene
