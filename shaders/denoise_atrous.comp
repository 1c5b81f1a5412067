#version 460
#extension GL_GOOGLE_include_directive : require
// One iteration of the edge-aware a-trous wavelet filter (Dammertz et al. 2010): a 5x5 B3-spline kernel
// with holes of `step` pixels, whose weights fall off across depth discontinuities (relative view distance)
// and normal creases, so the filter smooths noise within a surface but not across silhouettes.
#include "denoise_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D gDepth;
layout(set = 0, binding = 1) uniform sampler2D gNormal;
layout(set = 0, binding = 2) uniform sampler2D signalIn;  // .r
layout(set = 0, binding = 3, r16f) uniform writeonly image2D signalOut;

const float kKernel[3] = float[3](3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);

void main() {
  uvec2 pixel = gl_GlobalInvocationID.xy;
  if (any(greaterThanEqual(pixel, pc.size.xy))) return;
  ivec2 ip = ivec2(pixel);
  float centre = texelFetch(signalIn, ip, 0).r;
  float depth = texelFetch(gDepth, ip, 0).r;
  if (rbDnSky(depth)) {
    imageStore(signalOut, ip, vec4(centre));
    return;
  }
  vec3 p = rbDnCameraRelative(pixel, depth);
  vec3 n = rbDnNormal(texelFetch(gNormal, ip, 0));
  int step = int(pc.size.w);
  float depthSigma = pc.cameraDelta.w;
  float normalPower = pc.params.x;
  float sum = 0.0, weights = 0.0;
  for (int dy = -2; dy <= 2; ++dy) {
    for (int dx = -2; dx <= 2; ++dx) {
      ivec2 q = ip + ivec2(dx, dy) * step;
      if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(pc.size.xy)))) continue;
      float qd = texelFetch(gDepth, q, 0).r;
      if (rbDnSky(qd)) continue;
      vec3 qp = rbDnCameraRelative(uvec2(q), qd);
      vec3 qn = rbDnNormal(texelFetch(gNormal, q, 0));
      // Distance of the neighbour from the centre's tangent plane, relative to the view distance: flat
      // surfaces seen at a grazing angle keep their weight, steps in depth lose it.
      float planeDistance = abs(dot(qp - p, n)) / (length(p) * depthSigma * float(step) + 1e-6);
      float w = kKernel[abs(dx)] * kKernel[abs(dy)] * exp(-planeDistance) * pow(max(dot(n, qn), 0.0), normalPower);
      sum += w * texelFetch(signalIn, q, 0).r;
      weights += w;
    }
  }
  imageStore(signalOut, ip, vec4(weights > 0.0 ? sum / weights : centre));
}
