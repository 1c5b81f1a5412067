// The any-hit shader every pass runs on non-opaque geometry (MeshDesc::nonOpaque; opaque geometry never runs
// it): passes the ray through texels whose alpha is under the material's cutoff.
//   alpha = GpuMaterial::baseColor.a * the base colour texture's alpha at the hit (nearest texel of mip 0,
//           wrapped, after the material's texture transform: the CPU reference reads the same texel)
//   Mask:   the hit counts where alpha >= alphaCutoff
//   Blend:  the hit counts with probability alpha (a per-pixel, per-frame, per-surface random number), so
//           visibility through a layer is 1 - alpha in the mean
//   Opaque: the hit counts (a non-opaque mesh with an opaque material)
// Included by one module per pass (shadow.rahit, ao.rahit, reflect.rahit, primary.rahit) after the pass's push
// constant block; RB_FRAME_INDEX names the frame's noise seed there. With RB_BLEND_INVISIBLE (primary rays),
// Blend surfaces never count: primary rays stand for the G-buffer, which holds no blended surface.
#include "ray_counters.glsl"
#include "raybridge_sampling.glsl"
#include "shading_records.glsl"

hitAttributeEXT vec2 barycentrics;

void main() {
  rbCountAnyHit(gl_LaunchIDEXT.xy);
  ShadingRecord r = records[gl_InstanceID];
  GpuMaterial m = materials[min(r.material, uint(materials.length()) - 1u)];
  if (m.alphaMode == RB_ALPHA_OPAQUE) return;
#ifdef RB_BLEND_INVISIBLE
  if (m.alphaMode == RB_ALPHA_BLEND) ignoreIntersectionEXT;
#endif
  float alpha = m.baseColor.a;
  if (m.baseColorTexture != 0xFFFFFFFFu) {
    vec2 uv = rbMaterialUv(m, rbHitTexcoord(r, uint(gl_PrimitiveID), barycentrics));
    ivec2 size = textureSize(textures[nonuniformEXT(m.baseColorTexture)], 0);
    ivec2 texel = clamp(ivec2(floor(fract(uv) * vec2(size))), ivec2(0), size - 1);
    alpha *= texelFetch(textures[nonuniformEXT(m.baseColorTexture)], texel, 0).a;
  }
  if (m.alphaMode == RB_ALPHA_MASK) {
    if (alpha < m.alphaCutoff) ignoreIntersectionEXT;
    return;
  }
  // Blend. Independent per pixel, frame, ray direction (several rays per pixel) and surface (stacked layers).
  uvec3 d = floatBitsToUint(gl_WorldRayDirectionEXT);
  uint seed = rbPcg(gl_LaunchIDEXT.x + 65521u * gl_LaunchIDEXT.y + rbPcg(RB_FRAME_INDEX ^ 0x5bd1e995u));
  seed = rbPcg(seed ^ rbPcg(d.x ^ rbPcg(d.y ^ rbPcg(d.z))));
  seed = rbPcg(seed ^ rbPcg(uint(gl_InstanceID) * 0x9e3779b9u + uint(gl_PrimitiveID)));
  if (rbToUnit(seed) >= alpha) ignoreIntersectionEXT;
}
