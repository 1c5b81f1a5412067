#version 460
#extension GL_GOOGLE_include_directive : require
// One iteration of the edge-aware a-trous wavelet filter (Dammertz et al. 2010): a 5x5 B3-spline kernel
// with holes of `step` pixels, whose weights fall off across depth discontinuities (relative view distance),
// normal creases, and differences of the signal itself larger than its local noise (the SVGF luminance term,
// Schied et al. 2017, with the standard deviation of the 3x3 neighbourhood): noise within a surface is
// smoothed, but not silhouettes, and not a shadow or occlusion edge that stands out of the noise.
#include "denoise_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = RB_ATROUS_BINDING_DEPTH) uniform sampler2D gDepth;
layout(set = 0, binding = RB_ATROUS_BINDING_NORMAL) uniform sampler2D gNormal;
layout(set = 0, binding = RB_ATROUS_BINDING_SIGNAL_IN) uniform sampler2D signalIn;  // .r
layout(set = 0, binding = RB_ATROUS_BINDING_SIGNAL_OUT, r16f) uniform writeonly image2D signalOut;

const float kKernel[3] = float[3](3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);

void main() {
  uvec2 pixel = gl_GlobalInvocationID.xy;
  if (any(greaterThanEqual(pixel, pc.size))) return;
  ivec2 ip = ivec2(pixel);
  float centre = texelFetch(signalIn, ip, 0).r;
  float depth = texelFetch(gDepth, ip, 0).r;
  if (rbDnSky(depth)) {
    imageStore(signalOut, ip, vec4(centre));
    return;
  }
  vec3 p = rbDnCameraRelative(pixel, depth);
  vec3 n = rbDnNormal(texelFetch(gNormal, ip, 0));
  int step = int(pc.atrousStep);
  // Local noise level: the standard deviation of the signal over the 3x3 neighbourhood.
  float m1 = 0.0, m2 = 0.0, count = 0.0;
  for (int y = -1; y <= 1; ++y) {
    for (int x = -1; x <= 1; ++x) {
      ivec2 q = clamp(ip + ivec2(x, y), ivec2(0), ivec2(pc.size) - 1);
      float v = texelFetch(signalIn, q, 0).r;
      m1 += v;
      m2 += v * v;
      count += 1.0;
    }
  }
  m1 /= count;
  // With the rays per pixel known, the noise of a fraction of n binary rays is binomial: sqrt(c (1 - c) / n)
  // at the centre value c. It is 0 where every ray agreed (umbra, fully lit, open), so a noise-free edge,
  // even a line two pixels wide, is kept; the neighbourhood's spread would mistake it for noise.
  float samples = pc.signalRaysPerPixel;
  float c = clamp(centre, 0.0, 1.0);
  float noise = samples > 0.0 ? sqrt(c * (1.0 - c) / samples) : sqrt(max(m2 / count - m1 * m1, 0.0));
  float sigmaValue = 4.0 * noise + 1e-3;
  float depthSigma = pc.depthSigma;
  float normalPower = pc.normalPower;
  float sum = 0.0, weights = 0.0;
  for (int dy = -2; dy <= 2; ++dy) {
    for (int dx = -2; dx <= 2; ++dx) {
      ivec2 q = ip + ivec2(dx, dy) * step;
      if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(pc.size)))) continue;
      float qd = texelFetch(gDepth, q, 0).r;
      if (rbDnSky(qd)) continue;
      vec3 qp = rbDnCameraRelative(uvec2(q), qd);
      vec3 qn = rbDnNormal(texelFetch(gNormal, q, 0));
      // Distance of the neighbour from the centre's tangent plane, relative to the view distance: flat
      // surfaces seen at a grazing angle keep their weight, steps in depth lose it.
      float planeDistance = abs(dot(qp - p, n)) / (length(p) * depthSigma * float(step) + 1e-6);
      float qv = texelFetch(signalIn, q, 0).r;
      float w = kKernel[abs(dx)] * kKernel[abs(dy)] * exp(-planeDistance - abs(qv - centre) / sigmaValue) *
                pow(max(dot(n, qn), 0.0), normalPower);
      sum += w * qv;
      weights += w;
    }
  }
  imageStore(signalOut, ip, vec4(weights > 0.0 ? sum / weights : centre));
}
