// The refit-quality measure of a dynamic BLAS: one workgroup per cluster of 64 consecutive triangles writes the
// surface area of the cluster's bounding box. The host sums the clusters once the submission is done; the sum
// grows when a refit's boxes do (triangles that were close at the last build drifting apart).
#version 460
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
#extension GL_GOOGLE_include_directive : require

#include "raybridge_pass_constants.glsl"
layout(push_constant) uniform ClusterBoundsPushConstants { ClusterBoundsConstants pc; };

layout(local_size_x = RB_CLUSTER_TRIANGLES) in;  // rb::kRefitClusterTriangles

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer Words { uint w[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) writeonly buffer Areas { float a[]; };

shared vec3 lo[RB_CLUSTER_TRIANGLES];
shared vec3 hi[RB_CLUSTER_TRIANGLES];

uint loadIndex(uint i) {
  if (pc.indexType == RB_INDEX_NONE) return i;
  if (pc.indexType == RB_INDEX_U32) return Words(pc.indices).w[i];
  uint word = Words(pc.indices).w[i >> 1];
  return (i & 1u) != 0u ? word >> 16 : word & 0xFFFFu;
}

vec3 loadPosition(uint v) {
  uint base = v * (pc.positionStride >> 2);
  Words p = Words(pc.positions);
  switch (pc.positionFormat) {
    case RB_POSITION_RGB32F:
    case RB_POSITION_RGBA32F:
      return vec3(uintBitsToFloat(p.w[base]), uintBitsToFloat(p.w[base + 1u]), uintBitsToFloat(p.w[base + 2u]));
    case RB_POSITION_RG32F: return vec3(uintBitsToFloat(p.w[base]), uintBitsToFloat(p.w[base + 1u]), 0.0);
    case RB_POSITION_RGBA16F: return vec3(unpackHalf2x16(p.w[base]), unpackHalf2x16(p.w[base + 1u]).x);
    case RB_POSITION_RG16F: return vec3(unpackHalf2x16(p.w[base]), 0.0);
    case RB_POSITION_RGBA16_SNORM: return vec3(unpackSnorm2x16(p.w[base]), unpackSnorm2x16(p.w[base + 1u]).x);
    case RB_POSITION_RG16_SNORM: return vec3(unpackSnorm2x16(p.w[base]), 0.0);
    default: return unpackSnorm4x8(p.w[base]).xyz;
  }
}

void main() {
  const uint lane = gl_LocalInvocationID.x;
  const uint cluster = pc.firstCluster + gl_WorkGroupID.x;
  const uint triangle = cluster * uint(RB_CLUSTER_TRIANGLES) + lane;
  vec3 mn = vec3(3.4e38), mx = vec3(-3.4e38);
  if (triangle < pc.triangleCount) {
    for (uint k = 0u; k < 3u; ++k) {
      vec3 p = loadPosition(loadIndex(triangle * 3u + k));
      mn = min(mn, p);
      mx = max(mx, p);
    }
  }
  lo[lane] = mn;
  hi[lane] = mx;
  for (uint stride = 32u; stride > 0u; stride >>= 1) {
    barrier();
    if (lane < stride) {
      lo[lane] = min(lo[lane], lo[lane + stride]);
      hi[lane] = max(hi[lane], hi[lane + stride]);
    }
  }
  barrier();
  if (lane == 0u) {
    vec3 e = max(hi[0] - lo[0], vec3(0.0));
    Areas(pc.clusterAreas).a[gl_WorkGroupID.x] = 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x);
  }
}
