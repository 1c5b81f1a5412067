#version 460
#extension GL_GOOGLE_include_directive : require
// One iteration of the edge-aware a-trous wavelet filter for an RGB signal (SVGF, Schied et al. 2017): the
// 5x5 B3-spline kernel with holes of `step` pixels of denoise_atrous.comp, with the same depth and normal
// weights, and a colour weight whose tolerance is the signal's own noise: .a carries the colour's standard
// deviation (from the temporal pass), blurred over 3x3 for the weight and carried through each iteration as the
// standard deviation of the weighted mean. Where it is ~0 (converged, noise-free) only neighbours of nearly
// the same colour count, so the pixel stays nearly as it is. The colour difference is the RGB distance, not
// SVGF's luminance difference: pools of differently coloured light of similar brightness stay apart.
#include "denoise_rgb_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = RB_RGB_ATROUS_BINDING_DEPTH) uniform sampler2D gDepth;
layout(set = 0, binding = RB_RGB_ATROUS_BINDING_NORMAL) uniform sampler2D gNormal;
layout(set = 0, binding = RB_RGB_ATROUS_BINDING_SIGNAL_IN) uniform sampler2D signalIn;  // rgb, a: its deviation
layout(set = 0, binding = RB_RGB_ATROUS_BINDING_SIGNAL_OUT, rgba16f) uniform writeonly image2D signalOut;

const float kKernel[3] = float[3](3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);
const float kGauss3[2] = float[2](1.0 / 2.0, 1.0 / 4.0);
// The colour tolerance in standard deviations (SVGF's luminance one is 4; the difference of two colours is
// measured here, as a distance in RGB, which is larger).
const float kColourSigma = 2.5;

void main() {
  uvec2 pixel = gl_GlobalInvocationID.xy;
  if (any(greaterThanEqual(pixel, pc.size))) return;
  ivec2 ip = ivec2(pixel);
  const bool final = (pc.flags & RB_DN_RGB_FINAL) != 0u;
  vec4 centre = texelFetch(signalIn, ip, 0);
  float depth = texelFetch(gDepth, ip, 0).r;
  if (rbDnSky(depth)) {
    imageStore(signalOut, ip, vec4(centre.rgb, final ? 1.0 : centre.a));
    return;
  }
  vec3 p = rbDnCameraRelative(pixel, depth);
  vec3 n = rbDnNormal(texelFetch(gNormal, ip, 0));
  int step = int(pc.atrousStep);
  // The variance the weight uses: blurred over 3x3, so a pixel whose few frames happened to agree still takes
  // its neighbours' noise level.
  float variance = 0.0;
  for (int y = -1; y <= 1; ++y) {
    for (int x = -1; x <= 1; ++x) {
      ivec2 q = clamp(ip + ivec2(x, y), ivec2(0), ivec2(pc.size) - 1);
      float s = texelFetch(signalIn, q, 0).a;
      variance += kGauss3[abs(x)] * kGauss3[abs(y)] * s * s;
    }
  }
  // The floor keeps a noise-free pixel's weight finite: a difference of 0.1% of its colour weighs 1/e.
  float floorSigma = 1e-3 * length(centre.rgb) + 1e-6;
  float depthSigma = pc.depthSigma;
  float normalPower = pc.normalPower;
  vec3 sum = vec3(0.0);
  float weights = 0.0, varianceSum = 0.0;
  for (int dy = -2; dy <= 2; ++dy) {
    for (int dx = -2; dx <= 2; ++dx) {
      ivec2 q = ip + ivec2(dx, dy) * step;
      if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(pc.size)))) continue;
      float qd = texelFetch(gDepth, q, 0).r;
      if (rbDnSky(qd)) continue;
      vec3 qp = rbDnCameraRelative(uvec2(q), qd);
      vec3 qn = rbDnNormal(texelFetch(gNormal, q, 0));
      float planeDistance = abs(dot(qp - p, n)) / (length(p) * depthSigma * float(step) + 1e-6);
      vec4 qv = texelFetch(signalIn, q, 0);
      // The tolerance takes both pixels' noise: with the centre's alone a rare bright sample (high variance)
      // would spread into its neighbours while they (low variance) took none of it back, and its energy
      // would be lost; a shared tolerance keeps the filter's mean (the colour of a rarely chosen light).
      float sigma = kColourSigma * sqrt(0.5 * (variance + qv.a * qv.a)) + floorSigma;
      float w = kKernel[abs(dx)] * kKernel[abs(dy)] * exp(-planeDistance - length(qv.rgb - centre.rgb) / sigma) *
                pow(max(dot(n, qn), 0.0), normalPower);
      sum += w * qv.rgb;
      varianceSum += w * w * qv.a * qv.a;
      weights += w;
    }
  }
  // The centre's own weight is > 0, so weights > 0.
  vec3 filtered = sum / weights;
  float deviation = sqrt(varianceSum) / weights;
  imageStore(signalOut, ip, vec4(filtered, final ? 1.0 : deviation));
}
