// The engine's materials and textures as the SDK's rays see them: one table, shared by every pass. Reflection
// hits shade with it; primary, shadow, AO and reflection rays alpha-test non-opaque geometry (MeshDesc::nonOpaque)
// with it in their any-hit shaders. Instances pick their entry with Instance::material, through the TLAS's shading
// records (TlasBuildOptions::writeShadingRecords).
//
// Alpha testing, per ray type (the base colour factor's alpha times the base colour texture's alpha; the
// texture is read at the nearest texel of mip 0, wrapped):
//   AlphaMode::Mask   every ray passes through where alpha < alphaCutoff.
//   AlphaMode::Blend  shadow, AO and reflection rays pass through with probability 1 - alpha (a per-pixel,
//                     per-frame random number): unbiased in the mean, noisy per frame (denoise or accumulate).
//                     The engine draws blended surfaces in a forward pass, so the G-buffer never holds them,
//                     and primary rays (PrimaryRayPass), which stand for the G-buffer, pass through them.
//   AlphaMode::Opaque every hit counts.
// Only meshes registered with MeshDesc::nonOpaque = true run the any-hit shader; opaque meshes keep the opaque
// fast path, whatever their material says. Register the meshes of Mask and Blend materials as non-opaque.
//
// Lifetime: setMaterials() and destruction hand the previous buffer and texture set to the Context's deferred
// release, so frames in flight that recorded a pass with the table stay valid. Destroy it before its Context.
//
// Thread safety: externally synchronised, like the Context it was created from.
#pragma once

#include <raybridge/context.h>
#include <raybridge/result.h>

#include <memory>
#include <span>

namespace rb {

inline constexpr uint32_t kNoTexture = 0xFFFFFFFFu;

enum class AlphaMode : uint32_t {
  Opaque = 0,  // default: the surface stops every ray (glTF OPAQUE)
  Mask,        // cut out where alpha < alphaCutoff (glTF MASK)
  Blend,       // stochastic: a ray passes with probability 1 - alpha (glTF BLEND)
};

inline constexpr float kDefaultAlphaCutoff = 0.5f;  // glTF's default
inline constexpr uint32_t kMaxMaterialTextures = 4096;

// A surface material (glTF metallic-roughness).
struct Material {
  float baseColor[4] = {1.0f, 1.0f, 1.0f, 1.0f};  // linear RGBA factor; alpha multiplies the texture's alpha
  float metallic = 0.0f;
  float roughness = 1.0f;                          // perceptual
  float emissive[3] = {0.0f, 0.0f, 0.0f};          // linear radiance
  uint32_t baseColorTexture = kNoTexture;          // index into the textures of setMaterials (sRGB view: decoded)
  uint32_t metallicRoughnessTexture = kNoTexture;  // glTF layout: G = roughness, B = metallic
  uint32_t emissiveTexture = kNoTexture;           // multiplies `emissive` (sRGB view: decoded)
  AlphaMode alphaMode = AlphaMode::Opaque;         // default Opaque
  float alphaCutoff = 0.0f;  // Mask only; 0 = kDefaultAlphaCutoff (to cut nothing, use AlphaMode::Opaque)
  // Which texture coordinates the base colour texture reads: 0 = TEXCOORD_0, MeshDesc::texcoordAddress, the
  // one stream the SDK reads (1 is rejected by setMaterials until meshes can give a second one).
  uint32_t texcoordSet = 0;
  // Row-major 2x3 matrix applied to the base colour texture's coordinates (KHR_texture_transform):
  // uv' = (t[0] u + t[1] v + t[2], t[3] u + t[4] v + t[5]). All zero = identity.
  float textureTransform[6] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
};

// What the passes bind of a MaterialTable's current table (MaterialTable::info()), in the SDK's own layouts (not
// part of the API): the material buffer and the bindless texture set.
struct MaterialTableInfo {
  VkBuffer materials = VK_NULL_HANDLE;  // GPU materials, readable by ray tracing shaders
  VkDeviceSize materialBytes = 0;
  VkDescriptorSet textures = VK_NULL_HANDLE;  // the texture set every pass binds as its texture set
  uint32_t materialCount = 0;
};

class MaterialTable {
 public:
  // Starts with one default Material (white, opaque) and no textures.
  static Result<std::unique_ptr<MaterialTable>> create(Context& context);
  // Retires its buffer and texture set to the context, without waiting.
  ~MaterialTable();

  // Replaces the table: the engine's materials (at least one; instances index them) and texture views (2D,
  // sampled, in SHADER_READ_ONLY_OPTIMAL while used; at most kMaxMaterialTextures). Passes recorded
  // afterwards see the new table; the previous one is released once frames in flight are done with it.
  Status setMaterials(std::span<const Material> materials, std::span<const VkImageView> textures);
  uint32_t materialCount() const;
  // The current table, valid until the next setMaterials() (the replaced one lives on for the frames in flight).
  MaterialTableInfo info() const;

  struct Impl;

 private:
  explicit MaterialTable(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rb
