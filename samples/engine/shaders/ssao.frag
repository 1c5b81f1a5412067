#version 450
#extension GL_GOOGLE_include_directive : require
// Screen-space ambient occlusion (Crytek / LearnOpenGL style). Each pixel places a normal-oriented
// hemisphere kernel around its view-space position; a kernel point counts as occluded when the depth buffer
// holds a surface in front of it (by more than `bias`), weighted by a range check so that foreground objects
// far in front of the pixel do not darken it. Output: R = 1 - occluded fraction (1 = open), ^ power.
// The kernel is rotated per pixel with a 4x4 tiled pattern that the 4x4 blur pass averages out.
#include "frame_uniforms.glsl"
#include "screen_space.glsl"

layout(set = 1, binding = 0) uniform sampler2D depthTex;   // pre-pass depth, nearest
layout(set = 1, binding = 1) uniform sampler2D normalTex;  // pre-pass geometric normal (world), nearest
layout(push_constant) uniform SsaoConstants {
  float radius;  // world (= view) units
  float bias;    // view-depth units
  float power;
  uint kernelSize;
} pc;

layout(location = 0) out float outAo;

const float PI = 3.14159265358979;

float radicalInverse2(uint i) { return float(bitfieldReverse(i)) * 2.3283064365386963e-10; }

float radicalInverse3(uint i) {
  float f = 1.0, r = 0.0;
  while (i > 0u) {
    f /= 3.0;
    r += f * float(i % 3u);
    i /= 3u;
  }
  return r;
}

// Kernel point i of n in tangent space (z along the normal). Directions are cosine-distributed (Halton 2,3,
// so that any kernel size covers the hemisphere evenly and the AO estimates the cosine-weighted definition);
// lengths grow as lerp(0.1, 1, s^2) so that more points test close geometry (LearnOpenGL's schedule).
vec3 kernelPoint(uint i, uint n) {
  float u1 = radicalInverse2(i + 1u), u2 = radicalInverse3(i + 1u);
  float r = sqrt(u1), phi = 2.0 * PI * u2;
  vec3 d = vec3(r * cos(phi), r * sin(phi), sqrt(max(1.0 - u1, 0.0)));
  float s = (float(i) + 0.5) / float(n);
  return d * mix(0.1, 1.0, s * s);
}

// 4x4 Bayer index in [0,16): 16 distinct kernel rotations per 4x4 tile.
float tileRotation(ivec2 p) {
  const float bayer[16] = float[](0, 8, 2, 10, 12, 4, 14, 6, 3, 11, 1, 9, 15, 7, 13, 5);
  return 2.0 * PI * (bayer[(p.y & 3) * 4 + (p.x & 3)] + 0.5) / 16.0;
}

void main() {
  ivec2 pixel = ivec2(gl_FragCoord.xy);
  float depth = texelFetch(depthTex, pixel, 0).r;
  if (depth >= 1.0) {  // background: nothing to occlude
    outAo = 1.0;
    return;
  }
  vec3 p = viewFromDepth(pixelUv(pixel), depth);
  vec3 n = normalize(mat3(frame.view) * texelFetch(normalTex, pixel, 0).xyz);
  vec3 t = normalize(abs(n.x) < 0.9 ? cross(n, vec3(1, 0, 0)) : cross(n, vec3(0, 1, 0)));
  vec3 b = cross(n, t);
  float angle = tileRotation(pixel);
  vec3 tr = cos(angle) * t + sin(angle) * b;
  vec3 br = cross(n, tr);

  uint count = max(pc.kernelSize, 1u);
  float occlusion = 0.0;
  for (uint i = 0u; i < count; ++i) {
    vec3 k = kernelPoint(i, count);
    vec3 s = p + (tr * k.x + br * k.y + n * k.z) * pc.radius;
    vec4 clip = frame.proj * vec4(s, 1.0);
    if (clip.w <= 0.0) continue;
    vec2 uv = clip.xy / clip.w * 0.5 + 0.5;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThanEqual(uv, vec2(1.0)))) continue;  // unknown: open
    float sceneDepth = texelFetch(depthTex, ivec2(uv * frame.viewport.xy), 0).r;
    float sceneZ = viewZFromDepth(sceneDepth);  // the view looks down -Z: larger = closer
    float range = smoothstep(0.0, 1.0, pc.radius / abs(p.z - sceneZ));
    occlusion += (sceneZ >= s.z + pc.bias ? 1.0 : 0.0) * range;
  }
  outAo = pow(clamp(1.0 - occlusion / float(count), 0.0, 1.0), pc.power);
}
