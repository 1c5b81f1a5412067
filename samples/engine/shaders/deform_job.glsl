// The deformation pass's inputs. Keep in sync with DeformJob / DeformConstants in src/deformer.h (sizes and
// offsets are static_asserted there).
#extension GL_EXT_buffer_reference : require

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer Floats { float v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) writeonly buffer OutFloats { float v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer Uints { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Mat4s { mat4 m[]; };

// One deforming instance; static from loadScene() on.
struct DeformJob {
  Floats bindPositions;   // vertexCount * 3 floats (the mesh's bind pose)
  Floats bindAttributes;  // vertexCount * 9 floats: normal, uv, tangent
  Uints joints;           // vertexCount * influences / 2 uints: two 16-bit joint indices each, low half first
  Floats weights;         // vertexCount * influences floats
  Floats morphDeltas;     // targetCount * vertexCount * 6 floats: position delta, normal delta
  OutFloats outPositions;   // vertexCount * 3 floats
  OutFloats outAttributes;  // vertexCount * 9 floats
  uint vertexCount;
  uint influences;    // 0 (not skinned), 4 or 8
  uint targetCount;   // morph targets
  uint jointOffset;   // first joint matrix in DeformConstants::jointMatrices
  uint weightOffset;  // first morph weight in DeformConstants::morphWeights
  uint firstGroup;    // first workgroup of this job
};

layout(buffer_reference, std430, buffer_reference_align = 8) readonly buffer DeformJobs { DeformJob job[]; };

layout(push_constant) uniform DeformConstants {
  DeformJobs jobs;
  Uints groupJobs;      // per workgroup: its job index
  Mat4s jointMatrices;  // this frame's, per frame slot
  Floats morphWeights;  // this frame's, per frame slot
  uint groupCount;
  uint groupsPerRow;    // workgroups along x; y = ceil(groupCount / groupsPerRow)
} pc;
