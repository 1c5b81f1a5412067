// The per-instance shading records (TlasInfo::shadingRecords), the material table and the bindless texture set
// (MaterialTable), as the any-hit shaders and the reflection hits read them, with the vertex fetch helpers.
#ifndef RAYBRIDGE_SHADING_RECORDS_GLSL
#define RAYBRIDGE_SHADING_RECORDS_GLSL

#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
#extension GL_EXT_nonuniform_qualifier : require

#include "raybridge_shader_interface.glsl"

// Mirrors rb::ShadingRecord (sdk/src/accel/as_service_impl.h): where an instance's vertex data is.
struct ShadingRecord {
  uvec2 positions;
  uvec2 indices;
  uvec2 normals;    // 0 = none
  uvec2 texcoords;  // 0 = none
  uint positionStride;
  uint normalStride;
  uint texcoordStride;
  uint indexType;  // 0 u32, 1 u16, 2 none
  uint material;
  uint positionFormat;  // VkFormat; 106 = R32G32B32_SFLOAT
  uint pad0;
  uint pad1;
};

// Mirrors rb::GpuMaterial (sdk/src/trace/material_table_impl.h). Defaults are resolved on the host.
struct GpuMaterial {
  vec4 baseColor;
  float metallic;
  float roughness;
  uint baseColorTexture;  // 0xFFFFFFFF = none
  uint metallicRoughnessTexture;
  vec3 emissive;
  uint emissiveTexture;  // 0xFFFFFFFF = none
  vec3 uvTransformRow0;  // uv' = (dot(row0, (u, v, 1)), dot(row1, (u, v, 1))), for the base colour texture
  uint alphaMode;        // RB_ALPHA_*
  vec3 uvTransformRow1;
  float alphaCutoff;  // Mask: alpha below it is cut out
};

layout(set = 0, binding = RB_BINDING_SHADING_RECORDS, std430) readonly buffer ShadingRecords {
  ShadingRecord records[];
};
layout(set = 0, binding = RB_BINDING_MATERIALS, std430) readonly buffer Materials {
  GpuMaterial materials[];
};
layout(set = RB_SET_TEXTURES, binding = 0) uniform sampler2D textures[];

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer FloatRef { float v; };
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer UintRef { uint v; };

uvec2 rbAddressOffset(uvec2 a, uint offset) {
  uint lo = a.x + offset;
  return uvec2(lo, a.y + (lo < a.x ? 1u : 0u));
}
bool rbIsNull(uvec2 a) { return a.x == 0u && a.y == 0u; }

float rbLoadFloat(uvec2 base, uint offset) { return FloatRef(rbAddressOffset(base, offset)).v; }

vec3 rbLoadVec3(uvec2 base, uint offset) {
  return vec3(rbLoadFloat(base, offset), rbLoadFloat(base, offset + 4u), rbLoadFloat(base, offset + 8u));
}

uint rbLoadIndex(ShadingRecord r, uint i) {
  if (r.indexType == 2u) return i;
  if (r.indexType == 0u) return UintRef(rbAddressOffset(r.indices, 4u * i)).v;
  // 16-bit: read the aligned word that holds it.
  uint byteOffset = 2u * i + (r.indices.x & 3u);
  uvec2 aligned = uvec2(r.indices.x & ~3u, r.indices.y);
  uint word = UintRef(rbAddressOffset(aligned, byteOffset & ~3u)).v;
  return (byteOffset & 2u) != 0u ? word >> 16 : word & 0xFFFFu;
}

// The interpolated texture coordinate of a hit (TEXCOORD_0; (0, 0) when the mesh has none).
vec2 rbHitTexcoord(ShadingRecord r, uint primitive, vec2 barycentrics) {
  if (rbIsNull(r.texcoords)) return vec2(0.0);
  vec3 bary = vec3(1.0 - barycentrics.x - barycentrics.y, barycentrics.x, barycentrics.y);
  uint s = r.texcoordStride;
  uint i0 = rbLoadIndex(r, 3u * primitive);
  uint i1 = rbLoadIndex(r, 3u * primitive + 1u);
  uint i2 = rbLoadIndex(r, 3u * primitive + 2u);
  return bary.x * vec2(rbLoadFloat(r.texcoords, i0 * s), rbLoadFloat(r.texcoords, i0 * s + 4u)) +
         bary.y * vec2(rbLoadFloat(r.texcoords, i1 * s), rbLoadFloat(r.texcoords, i1 * s + 4u)) +
         bary.z * vec2(rbLoadFloat(r.texcoords, i2 * s), rbLoadFloat(r.texcoords, i2 * s + 4u));
}

// The material's texture transform applied to a texture coordinate.
vec2 rbMaterialUv(GpuMaterial m, vec2 uv) {
  vec3 h = vec3(uv, 1.0);
  return vec2(dot(m.uvTransformRow0, h), dot(m.uvTransformRow1, h));
}

#endif
