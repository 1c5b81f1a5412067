#version 460
#extension GL_GOOGLE_include_directive : require
// Skinning and morphing of every deforming instance in one dispatch: bind pose + morph deltas * weights,
// then linear-blend skinning with this frame's joint matrices (instance-local space). Normals use the
// cofactor of the blended matrix (the inverse transpose up to scale), tangents the matrix itself.
#include "deform_job.glsl"

layout(local_size_x = 64) in;

void main() {
  const uint group = gl_WorkGroupID.y * pc.groupsPerRow + gl_WorkGroupID.x;
  if (group >= pc.groupCount) return;
  DeformJob job = pc.jobs.job[pc.groupJobs.v[group]];
  const uint v = (group - job.firstGroup) * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
  if (v >= job.vertexCount) return;

  vec3 position = vec3(job.bindPositions.v[3 * v], job.bindPositions.v[3 * v + 1], job.bindPositions.v[3 * v + 2]);
  const uint a = 9 * v;
  vec3 normal = vec3(job.bindAttributes.v[a], job.bindAttributes.v[a + 1], job.bindAttributes.v[a + 2]);
  const vec2 uv = vec2(job.bindAttributes.v[a + 3], job.bindAttributes.v[a + 4]);
  vec4 tangent = vec4(job.bindAttributes.v[a + 5], job.bindAttributes.v[a + 6], job.bindAttributes.v[a + 7],
                      job.bindAttributes.v[a + 8]);

  for (uint t = 0; t < job.targetCount; ++t) {
    const float w = pc.morphWeights.v[job.weightOffset + t];
    if (w == 0.0) continue;
    const uint d = (t * job.vertexCount + v) * 6;
    position += w * vec3(job.morphDeltas.v[d], job.morphDeltas.v[d + 1], job.morphDeltas.v[d + 2]);
    normal += w * vec3(job.morphDeltas.v[d + 3], job.morphDeltas.v[d + 4], job.morphDeltas.v[d + 5]);
  }

  if (job.influences > 0) {
    mat4 skin = mat4(0.0);
    for (uint k = 0; k < job.influences; ++k) {
      const float w = job.weights.v[v * job.influences + k];
      if (w == 0.0) continue;
      const uint packed = job.joints.v[v * (job.influences / 2) + k / 2];
      const uint joint = (packed >> (16 * (k & 1))) & 0xFFFFu;
      skin += w * pc.jointMatrices.m[job.jointOffset + joint];
    }
    position = (skin * vec4(position, 1.0)).xyz;
    const mat3 m = mat3(skin);
    const mat3 cofactor = mat3(cross(m[1], m[2]), cross(m[2], m[0]), cross(m[0], m[1]));
    normal = cofactor * normal * sign(dot(m[0], cross(m[1], m[2])));
    tangent.xyz = m * tangent.xyz;
  }
  const float nl = length(normal), tl = length(tangent.xyz);
  normal = nl > 0.0 ? normal / nl : vec3(0.0, 1.0, 0.0);
  if (tl > 0.0) tangent.xyz /= tl;

  job.outPositions.v[3 * v] = position.x;
  job.outPositions.v[3 * v + 1] = position.y;
  job.outPositions.v[3 * v + 2] = position.z;
  job.outAttributes.v[a] = normal.x;
  job.outAttributes.v[a + 1] = normal.y;
  job.outAttributes.v[a + 2] = normal.z;
  job.outAttributes.v[a + 3] = uv.x;
  job.outAttributes.v[a + 4] = uv.y;
  job.outAttributes.v[a + 5] = tangent.x;
  job.outAttributes.v[a + 6] = tangent.y;
  job.outAttributes.v[a + 7] = tangent.z;
  job.outAttributes.v[a + 8] = tangent.w;
}
