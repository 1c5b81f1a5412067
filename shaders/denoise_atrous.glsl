#version 460
#extension GL_GOOGLE_include_directive : require
// One iteration of the edge-aware a-trous wavelet filter (Dammertz et al. 2010): a 5x5 B3-spline kernel with
// holes of `step` pixels, whose weights fall off across depth discontinuities (relative view distance), normal
// creases, and differences of the signal larger than its noise (the SVGF term, Schied et al. 2017, with the
// variance measured by the temporal pass and carried through the steps): noise within a surface is smoothed,
// but not silhouettes, and not a shadow or occlusion edge that stands out of the noise. The tolerance follows
// the centre's noise, so a noise-free pixel (umbra, fully lit, open, many rays) takes nothing from its
// neighbours. Body of the variants denoise_atrous.comp (intermediate steps: value and variance out) and
// denoise_atrous_final.comp (RB_DN_ATROUS_FINAL: the output, the temporal value moved at most as far as its
// noise explains, see rbDnLimitedShift), rows of shaders/variants.cmake.
#include "denoise_noise.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = RB_ATROUS_BINDING_DEPTH) uniform sampler2D gDepth;
layout(set = 0, binding = RB_ATROUS_BINDING_NORMAL) uniform sampler2D gNormal;
layout(set = 0, binding = RB_ATROUS_BINDING_SIGNAL_IN) uniform sampler2D signalIn;  // r: value, g: variance
#ifdef RB_DN_ATROUS_FINAL
layout(set = 0, binding = RB_ATROUS_BINDING_TEMPORAL) uniform sampler2D temporalIn;  // r: value, g: variance
layout(set = 0, binding = RB_ATROUS_BINDING_SIGNAL_OUT, r16f) uniform writeonly image2D signalOut;
layout(set = 0, binding = RB_ATROUS_BINDING_HISTORY) uniform sampler2D historyIn;  // y: the pixel's frames
#else
layout(set = 0, binding = RB_ATROUS_BINDING_SIGNAL_OUT, rg16f) uniform writeonly image2D signalOut;
#endif

const float kKernel[3] = float[3](3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);
// The value tolerance in standard deviations of the centre's noise. Wider than SVGF's 4: the final shift limit,
// not this weight, keeps noise-free pixels and edges as they are (measured on the [denoise] tests: 4 left 4-ray AO
// of unknown noise at 0.0325 RMSE, 6 at 0.0311).
const float kValueSigmas = 6.0;
const float kLog2e = 1.4426950408889634;

// The final step's estimate of the filter's squared bias around the pixel: the previous steps' change of each
// pixel of the 3x3 neighbourhood on the same surface (`same`), squared and averaged, less the noise that change
// removed (for pure noise, the change is the noise itself). A pattern the filter flattens changes every pixel
// by more than its noise, with either sign; noise averages out to ~0.
float biasSquared(ivec2 ip, bool same[9]) {
#ifdef RB_DN_ATROUS_FINAL
  float changes = 0.0, noise = 0.0, count = 0.0;
  for (int k = 0; k < 9; ++k) {
    if (!same[k]) continue;
    ivec2 q = ip + ivec2(k % 3 - 1, k / 3 - 1);
    vec2 t = texelFetch(temporalIn, q, 0).rg;
    float d = texelFetch(signalIn, q, 0).r - t.r;
    changes += d * d;
    noise += t.g;
    count += 1.0;
  }
  return count > 0.0 ? max(changes - noise, 0.0) / count : 0.0;
#else
  return 0.0;
#endif
}

// `temporal`: the pixel's temporal value and variance (the final step's anchor; unused before it). `youth`:
// rbDnYouth of the pixel's history.
void store(ivec2 ip, vec2 temporal, float value, float variance, float bias2, float youth) {
#ifdef RB_DN_ATROUS_FINAL
  imageStore(signalOut, ip, vec4(rbDnLimitedShift(temporal.r, temporal.g, value, bias2, youth)));
#else
  imageStore(signalOut, ip, vec4(value, variance, 0.0, 0.0));
#endif
}

void main() {
  uvec2 pixel = gl_GlobalInvocationID.xy;
  if (any(greaterThanEqual(pixel, pc.size))) return;
  ivec2 ip = ivec2(pixel);
#ifdef RB_DN_ATROUS_FINAL
  // A converged pixel keeps its temporal value whatever the filter gives (rbDnLimitedShift's gain is 0, the same
  // expression): skip the filter. Bit-identical to filtering and discarding; it is most of the pixels of a
  // converged signal (lit ground, open sky light, many rays or a full history).
  vec2 temporal = texelFetch(temporalIn, ip, 0).rg;
  const float youth = rbDnYouth(texelFetch(historyIn, ip, 0).y);
  if (sqrt(max(temporal.g, 0.0)) / rbDnGateNoise(youth) - 1.0 <= 0.0) {
    imageStore(signalOut, ip, vec4(temporal.r));
    return;
  }
#else
  vec2 temporal = vec2(0.0);
  const float youth = 0.0;
#endif
  vec2 centre = texelFetch(signalIn, ip, 0).rg;
  float depth = texelFetch(gDepth, ip, 0).r;
  if (rbDnSky(depth)) {
    store(ip, temporal, centre.r, centre.g, 0.0, youth);
    return;
  }
  // Positions in view space, the centre's normal turned into it (viewToWorld is a rotation: its transpose is its
  // inverse): the plane distances are the world-space ones, without a rotation per tap.
  vec3 p = rbDnViewPosition(pixel, depth);
  vec3 n = rbDnNormal(texelFetch(gNormal, ip, 0));
  vec3 nView = n * pc.viewToWorld;
  int step = int(pc.atrousStep);
  float tolerance = length(p) * pc.depthSigma * float(step) + 1e-6;
  float invSigma = 1.0 / (kValueSigmas * sqrt(max(centre.g, 0.0)) + 1e-4);
  float sum = 0.0, weights = 0.0, variances = 0.0;
  bool same[9];  // the 3x3 neighbourhood (step 1) on the centre's surface: the final step's bias estimate
  for (int k = 0; k < 9; ++k) same[k] = false;
  for (int dy = -2; dy <= 2; ++dy) {
    for (int dx = -2; dx <= 2; ++dx) {
      ivec2 q = ip + ivec2(dx, dy) * step;
      if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(pc.size)))) continue;
      float qd = texelFetch(gDepth, q, 0).r;
      if (rbDnSky(qd)) continue;
      vec3 qp = rbDnViewPosition(uvec2(q), qd);
      vec3 qn = rbDnNormal(texelFetch(gNormal, q, 0));
      vec2 qv = texelFetch(signalIn, q, 0).rg;
      // Distance of the neighbour from the centre's tangent plane, relative to the view distance: flat
      // surfaces seen at a grazing angle keep their weight, steps in depth lose it.
      float planeDistance = abs(dot(qp - p, nView)) / tolerance;
      if (step == 1 && abs(dx) <= 1 && abs(dy) <= 1) same[(dy + 1) * 3 + dx + 1] = planeDistance < 1.0;
      // exp(-planeDistance - valueDistance) * cos^normalPower as one exp2 (one transcendental fewer per tap).
      float cosine = dot(n, qn);
      float w = cosine > 0.0 ? kKernel[abs(dx)] * kKernel[abs(dy)] *
                                   exp2(pc.normalPower * log2(cosine) -
                                        kLog2e * (planeDistance + abs(qv.r - centre.r) * invSigma))
                             : 0.0;
      sum += w * (qv.r - centre.r);  // differences: equal values give the centre exactly, without rounding
      variances += w * w * max(qv.g, 0.0);
      weights += w;
    }
  }
  // The centre is always a tap of its own (weight 9/64 > 0).
#ifdef RB_DN_ATROUS_FINAL
  if (step != 1) {
    // The 3x3 neighbourhood's surface test at this step's tolerance scaled back to one pixel.
    for (int k = 0; k < 9; ++k) {
      ivec2 q = clamp(ip + ivec2(k % 3 - 1, k / 3 - 1), ivec2(0), ivec2(pc.size) - 1);
      float qd = texelFetch(gDepth, q, 0).r;
      same[k] = !rbDnSky(qd) && abs(dot(rbDnViewPosition(uvec2(q), qd) - p, nView)) * float(step) < tolerance;
    }
  }
#endif
  store(ip, temporal, centre.r + sum / weights, variances / (weights * weights), biasSquared(ip, same), youth);
}
