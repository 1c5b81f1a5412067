#version 450
#extension GL_GOOGLE_include_directive : require
// 4x4 box blur of the raw GTAO image (one full period of its 4x4 slice-rotation pattern), restricted to
// neighbours close to the pixel's tangent plane so that occlusion does not bleed across silhouettes.
#include "frame_uniforms.glsl"
#include "screen_space.glsl"
#include "ssao_inputs.glsl"

void main() {
  ivec2 pixel;
  if (!ssaoPixel(pixel)) return;
  float depth = texelFetch(depthTex, pixel, 0).r;
  if (depth >= 1.0) {
    imageStore(outAo, pixel, vec4(1.0));
    return;
  }
  ivec2 last = ivec2(frame.viewport.xy) - 1;
  vec3 p = viewFromDepth(pixelUv(pixel), depth);
  vec3 n = normalize(mat3(frame.view) * texelFetch(normalTex, pixel, 0).xyz);
  float tolerance = 0.5 * pc.radius;
  float sum = 0.0, weight = 0.0;
  for (int y = -2; y < 2; ++y)
    for (int x = -2; x < 2; ++x) {
      ivec2 q = clamp(pixel + ivec2(x, y), ivec2(0), last);
      float d = texelFetch(depthTex, q, 0).r;
      if (d >= 1.0) continue;
      vec3 pq = viewFromDepth(pixelUv(q), d);
      if (abs(dot(pq - p, n)) > tolerance) continue;
      sum += texelFetch(rawAo, q, 0).r;
      weight += 1.0;
    }
  imageStore(outAo, pixel, vec4(weight > 0.0 ? sum / weight : texelFetch(rawAo, pixel, 0).r));
}
