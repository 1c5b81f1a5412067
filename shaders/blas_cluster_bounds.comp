// The refit-quality measure of a dynamic BLAS: one workgroup per cluster of 64 consecutive triangles writes the
// surface area of the cluster's bounding box. The host sums the clusters once the submission is done; the sum
// grows when a refit's boxes do (triangles that were close at the last build drifting apart).
#version 460
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

layout(local_size_x = 64) in;  // kRefitClusterTriangles

// Mirrors rb::ClusterBoundsConstants (sdk/src/cluster_bounds.h).
layout(push_constant) uniform ClusterBoundsConstants {
  uvec2 positions;      // device address of vertex 0's position
  uvec2 indices;        // device address of the first index (4-byte aligned); unused when indexType is 2
  uvec2 clusterAreas;   // device address of this dispatch's first output float
  uint positionStride;  // bytes, a multiple of 4
  uint positionFormat;  // kPosition* below
  uint indexType;       // 0 u32, 1 u16, 2 none
  uint triangleCount;   // of the whole mesh
  uint firstCluster;    // of this dispatch (dispatches are split at the workgroup count limit)
  uint pad;
} pc;

// Position formats (rb::ClusterPositionFormat).
const uint kPositionRgb32f = 0u, kPositionRg32f = 1u, kPositionRgba32f = 2u, kPositionRgba16f = 3u;
const uint kPositionRg16f = 4u, kPositionRgba16Snorm = 5u, kPositionRg16Snorm = 6u, kPositionRgba8Snorm = 7u;

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer Words { uint w[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) writeonly buffer Areas { float a[]; };

shared vec3 lo[64];
shared vec3 hi[64];

uint loadIndex(uint i) {
  if (pc.indexType == 2u) return i;
  if (pc.indexType == 0u) return Words(pc.indices).w[i];
  uint word = Words(pc.indices).w[i >> 1];
  return (i & 1u) != 0u ? word >> 16 : word & 0xFFFFu;
}

vec3 loadPosition(uint v) {
  uint base = v * (pc.positionStride >> 2);
  Words p = Words(pc.positions);
  switch (pc.positionFormat) {
    case kPositionRgb32f:
    case kPositionRgba32f:
      return vec3(uintBitsToFloat(p.w[base]), uintBitsToFloat(p.w[base + 1u]), uintBitsToFloat(p.w[base + 2u]));
    case kPositionRg32f: return vec3(uintBitsToFloat(p.w[base]), uintBitsToFloat(p.w[base + 1u]), 0.0);
    case kPositionRgba16f: return vec3(unpackHalf2x16(p.w[base]), unpackHalf2x16(p.w[base + 1u]).x);
    case kPositionRg16f: return vec3(unpackHalf2x16(p.w[base]), 0.0);
    case kPositionRgba16Snorm: return vec3(unpackSnorm2x16(p.w[base]), unpackSnorm2x16(p.w[base + 1u]).x);
    case kPositionRg16Snorm: return vec3(unpackSnorm2x16(p.w[base]), 0.0);
    default: return unpackSnorm4x8(p.w[base]).xyz;
  }
}

void main() {
  const uint lane = gl_LocalInvocationID.x;
  const uint cluster = pc.firstCluster + gl_WorkGroupID.x;
  const uint triangle = cluster * 64u + lane;
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
