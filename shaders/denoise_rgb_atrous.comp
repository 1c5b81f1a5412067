#version 460
#extension GL_GOOGLE_include_directive : require
// One iteration of the edge-aware a-trous wavelet filter for an RGB signal (SVGF, Schied et al. 2017): a 3x3
// B-spline kernel with holes of `step` pixels whose weights fall off across depth discontinuities and normal
// creases (as denoise_atrous.comp) and across colour differences larger than the signal's own noise: .a
// carries the colour's standard deviation (from the temporal pass), averaged over the taps on the same surface
// for the weight and carried through each iteration as the standard deviation of the weighted mean. Where it is
// ~0 (converged, noise-free) only neighbours of nearly the same colour count, so the pixel stays nearly as it
// is. The colour difference is the RGB distance, not SVGF's luminance difference: pools of differently
// coloured light of similar brightness stay apart.
//
// Cost: 3x3 taps (SVGF's 5x5 reads 2.8 times as many) of two texels each (the guide image holds distance and
// normal); more iterations give the reach instead. Positions come from the view distance along a ray direction
// that is linear in the pixel coordinates, so no tap goes through the inverse projection.
#include "denoise_rgb_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = RB_RGB_ATROUS_BINDING_GUIDE) uniform usampler2D guide;
layout(set = 0, binding = RB_RGB_ATROUS_BINDING_SIGNAL_IN) uniform sampler2D signalIn;  // rgb, a: its deviation
layout(set = 0, binding = RB_RGB_ATROUS_BINDING_SIGNAL_OUT, rgba16f) uniform writeonly image2D signalOut;

const float kKernel[2] = float[2](1.0 / 2.0, 1.0 / 4.0);
// The colour tolerance in standard deviations (SVGF's luminance one is 4; an RGB distance is larger).
const float kColourSigma = 2.5;
const float kLog2e = 1.4426950408889634;
// A pixel whose taps all carry a deviation under this fraction of its colour skips the filter (below).
const float kConvergedDeviation = 1e-4;

void main() {
  uvec2 pixel = gl_GlobalInvocationID.xy;
  if (any(greaterThanEqual(pixel, pc.size))) return;
  ivec2 ip = ivec2(pixel);
  const bool final = (pc.flags & RB_DN_RGB_FINAL) != 0u;
  vec4 centre = texelFetch(signalIn, ip, 0);
  uvec2 g = texelFetch(guide, ip, 0).xy;
  float dist = rbDnGuideDistance(g);
  if (dist <= 0.0) {  // sky, or no reflection there (coverage 0 in the output)
    float coverage = (pc.flags & RB_DN_RGB_REFLECTION) != 0u ? 0.0 : 1.0;
    imageStore(signalOut, ip, vec4(centre.rgb, final ? coverage : centre.a));
    return;
  }
  int step = int(pc.atrousStep);
  // The taps' values first. Where every one of them (the centre too) is noise-free, the pixel stays as it is
  // whatever the geometry: each tap's colour tolerance is then at most kColourSigma * 1e-4 plus the floor below
  // (0.1% of the centre's colour), and a tap at colour distance d moves the centre by at most its weight times
  // d exp(-d / sigma) <= sigma / e, so all 8 (3/4 of the kernel, against the centre's 1/4) by at most 0.14% of
  // its colour: the half-float rounding of the output. Skipping them saves the guide reads and the weights; it is
  // most of a converged signal (mirrors, which the temporal pass gives no noise; a uniform sky reflected).
  // Only the taps' deviations are kept across the loops (9 registers, not 36): their colours are fetched again,
  // from the cache, where the weights need them. Fewer live registers keep more threads in flight to hide the
  // fetches' latency.
  float deviations[9];
  float noisiest = 0.0;
  for (int k = 0; k < 9; ++k) {
    ivec2 q = ip + ivec2(k % 3 - 1, k / 3 - 1) * step;
    bool inside = all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(pc.size)));
    deviations[k] = k == 4 ? centre.a : (inside ? texelFetch(signalIn, q, 0).a : -1.0);  // -1: outside
    noisiest = max(noisiest, deviations[k]);
  }
  if (noisiest <= kConvergedDeviation * length(centre.rgb)) {
    imageStore(signalOut, ip, vec4(centre.rgb, final ? 1.0 : centre.a));
    return;
  }

  vec3 n = rbDnGuideNormal(g);
  // Camera-relative points at one depth are linear in the pixel coordinates (before the perspective division,
  // which only scales them): the direction towards any pixel from the centre's and two differences.
  const float anyDepth = 0.5;
  vec3 a0 = rbDnCameraRelative(pixel, anyDepth);
  vec3 ax = rbDnCameraRelative(pixel + uvec2(1, 0), anyDepth) - a0;
  vec3 ay = rbDnCameraRelative(pixel + uvec2(0, 1), anyDepth) - a0;
  vec3 p = normalize(a0) * dist;
  float tolerance = length(p) * pc.depthSigma * float(step) + 1e-6;

  // The taps' geometric weights: the centre's noise level for the colour weight is the mean variance of the
  // taps on the same surface (a weighted sum here), so a pixel whose few frames happened to agree still takes
  // its neighbours' noise level, and the other side of an edge lends none.
  float geometric[9];
  float tapVariances = 0.0, varianceWeights = 0.0;
  for (int k = 0; k < 9; ++k) {
    ivec2 o = ivec2(k % 3 - 1, k / 3 - 1);
    ivec2 q = ip + o * step;
    geometric[k] = 0.0;
    if (deviations[k] < 0.0) continue;
    uvec2 qg = texelFetch(guide, q, 0).xy;
    float qdist = rbDnGuideDistance(qg);
    if (qdist <= 0.0) continue;
    vec3 qp = normalize(a0 + float(o.x * step) * ax + float(o.y * step) * ay) * qdist;
    float planeDistance = abs(dot(qp - p, n)) / tolerance;
    // exp(-planeDistance) * cos^normalPower as one exp2 (one transcendental fewer per tap).
    float cosine = dot(n, rbDnGuideNormal(qg));
    float w = cosine > 0.0 ? kKernel[abs(o.x)] * kKernel[abs(o.y)] *
                                 exp2(pc.normalPower * log2(cosine) - kLog2e * planeDistance)
                           : 0.0;
    geometric[k] = w;
    tapVariances += w * deviations[k] * deviations[k];
    varianceWeights += w;
  }
  // The floor keeps a noise-free pixel's weight finite: a difference of 0.1% of its colour weighs 1/e.
  float floorSigma = 1e-3 * length(centre.rgb) + 1e-6;
  vec3 sum = vec3(0.0);
  float weights = 0.0, varianceSum = 0.0;
  for (int k = 0; k < 9; ++k) {
    if (geometric[k] == 0.0) continue;
    vec4 qv = k == 4 ? centre : texelFetch(signalIn, ip + ivec2(k % 3 - 1, k / 3 - 1) * step, 0);
    // The tolerance is the smaller of the two pixels' noise, the centre's taken without this tap: a pixel
    // mixes with a neighbour only when both are that noisy. A bright, noisy pixel (a light's hot spot, a rare
    // sample) then neither spreads into quiet neighbours nor is averaged away while they take none of it back,
    // which would lose its energy (the colour of a rarely chosen light).
    float others = varianceWeights - geometric[k];
    // max(0): the difference can round below zero (it did on the H200, whose fused multiply-adds round otherwise
    // than lavapipe: the square root then made every pixel NaN).
    float centreVariance =
        others > 1e-6 ? max((tapVariances - geometric[k] * qv.a * qv.a) / others, 0.0) : centre.a * centre.a;
    float sigma = kColourSigma * sqrt(min(centreVariance, qv.a * qv.a)) + floorSigma;
    float w = geometric[k] * exp(-length(qv.rgb - centre.rgb) / sigma);
    sum += w * (qv.rgb - centre.rgb);
    varianceSum += w * w * qv.a * qv.a;
    weights += w;
  }
  // Summed as differences from the centre: where every tap that counts has the centre's colour the result is the
  // centre exactly (a weighted mean of the values rounds, and the rounding of half floats, lavapipe's at least,
  // then drifts a converged colour down by an ulp every step).
  vec3 filtered = centre.rgb + sum / weights;
  float deviation = sqrt(varianceSum) / weights;
  imageStore(signalOut, ip, vec4(filtered, final ? 1.0 : deviation));
}
