// Shared by the RGB denoiser's compute shaders. The noise tracked is that of the colour as a whole: the variance
// is the sum of the three channels' (the trace of the covariance), so a pixel flickering between a red and a
// blue light of equal luminance counts as noisy, and a colour edge as an edge.
#ifndef RAYBRIDGE_DENOISE_RGB_COMMON_GLSL
#define RAYBRIDGE_DENOISE_RGB_COMMON_GLSL

#include "denoise_common.glsl"
#include "denoise_rgb_interface.glsl"

// The guide image (RG32UI), written once per frame by the temporal pass so that each a-trous tap reads one
// 8-byte texel instead of depth and normal, and rebuilds no position through the inverse projection:
// x = the float bits of the view distance (0 = sky), y = the normal, octahedral, packSnorm2x16.
uvec2 rbDnPackGuide(float viewDistance, vec3 n) {
  return uvec2(floatBitsToUint(viewDistance), packSnorm2x16(rbEncodeOctahedral(n)));
}
float rbDnGuideDistance(uvec2 g) { return uintBitsToFloat(g.x); }
vec3 rbDnGuideNormal(uvec2 g) { return rbDecodeOctahedral(unpackSnorm2x16(g.y)); }

// SVGF's threshold: with fewer frames the variance comes from the neighbourhood instead.
const float kRbDnMinTemporalVarianceFrames = 4.0;

// A pixel of the signal that the reflection pass did not trace because its tile had converged (RB_DN_KEPT_MARKS,
// rgb_converged.comp): .a = -1, .rgb its reprojected history mean. It keeps its history unchanged.
bool rbDnRgbKeptMark(float a) { return (pc.flags & RB_DN_KEPT_MARKS) != 0u && a < -0.5; }
// A pixel traced this frame whose converged tile's refresh found a change (rgb_converged_check.comp): .a = 2.
// Its history is stale: it starts afresh, as a disoccluded pixel does.
bool rbDnRgbStaleMark(float a) { return (pc.flags & RB_DN_KEPT_MARKS) != 0u && a > 1.5; }

// The surface history (RG16F): .x the view distance, .y the standard deviation of one frame's colour, kept as a
// deviation, not a variance, because a variance of HDR values overflows a half float; read back as the variance.
float rbDnRgbSurfaceVariance(vec4 surface) { return surface.y * surface.y; }
vec4 rbDnRgbSurfaceTexel(float dist, float variance) { return vec4(dist, sqrt(max(variance, 0.0)), 0.0, 0.0); }

// Where the surface at `pixel` (camera-relative position `rel`) was in the latest history, read over the bilinear
// footprint of the texels that hold the same surface (rbDnBilinearSameSurface). Returns whether any did: then `h` is
// the history (rgb mean, a frames) and `v` the variance of one frame's colour there; none where the engine's reactive
// mask is set (rbDnReactive). The temporal pass's test, shared with the converged reflection tiles, which must find
// the history it finds. `pp`: the nearest history texel (the anti-lag window's centre).
bool rbDnRgbFindHistory(uvec2 pixel, vec3 rel, sampler2D motion, sampler2D reactive, sampler2D historyIn,
                        sampler2D surfaceIn, out vec4 h, out float v, out ivec2 pp) {
  h = vec4(0.0);
  v = 0.0;
  vec3 prevRel;
  vec2 prevPixel = rbDnPreviousPixel(pixel, rel, motion, prevRel);
  pp = ivec2(floor(prevPixel));
  if ((pc.flags & RB_DN_HISTORY) == 0u || rbDnReactive(pixel, reactive)) return false;
  ivec2 base;
  vec4 w;
  float weights = rbDnBilinearSameSurface(prevPixel, length(prevRel), surfaceIn, base, w);
  for (int k = 0; k < 4; ++k) {
    if (w[k] <= 0.0) continue;
    ivec2 q = base + ivec2(k & 1, k >> 1);
    h += w[k] * texelFetch(historyIn, q, 0);
    v += w[k] * rbDnRgbSurfaceVariance(texelFetch(surfaceIn, q, 0));
  }
  if (weights <= 1e-3) return false;
  h /= weights;
  v /= weights;
  return true;
}
bool rbDnRgbFindHistory(uvec2 pixel, vec3 rel, sampler2D motion, sampler2D reactive, sampler2D historyIn,
                        sampler2D surfaceIn, out vec4 h, out float v) {
  ivec2 pp;
  return rbDnRgbFindHistory(pixel, rel, motion, reactive, historyIn, surfaceIn, h, v, pp);
}

// Anti-lag of the RGB signals (RB_DN_ANTI_LAG; as rbDnHistoryTrust for scalar ones): which fraction of the history
// (rbDnRgbFindHistory, whose nearest texel is `pp`) the pixel at `ip` keeps. The mean colour of the 3x3 pixels around
// it this frame (surface pixels; reflections: those with coverage) against that of the 3x3 history texels around
// `pp` (those with history): the distance of the two in units of its noise. The noise: one frame's variance (below)
// over the 9 pixels, plus the history's share, each texel's by its own frames (a neighbour that just started afresh
// is as noisy as this frame), plus a 1% floor of the colour, so that a noise-free signal tolerates half-float
// rounding and a sub-pixel shift of its texture. A moved object seen in a reflection, or a light that switched on,
// differs by many sigmas; noise by about one.
// RGB signals are heavy-tailed (a light sampled with a small probability, a reflected highlight): a rare bright
// sample moves a 3x3 mean by more sigmas than binary noise does, and trimming the history on it keeps that sample at
// a large weight (a colour bias). Hence the pooled variance below, and thresholds a little above the scalar ones
// (red+blue light test, 1 ray, 16 frames: blue 1.036 of exact, as without anti-lag; 1.086 with one pixel's variance
// and 5 / 10); the ramp is short, as the scalar one, for the same reason.
const float kRbDnRgbLagSigmasLow = 3.5;
const float kRbDnRgbLagSigmasHigh = 4.0;

float rbDnRgbHistoryTrust(ivec2 ip, ivec2 pp, sampler2D depthImage, sampler2D signal, sampler2D historyIn,
                          sampler2D surfaceIn) {
  const bool reflection = (pc.flags & RB_DN_RGB_REFLECTION) != 0u;
  vec3 c1 = vec3(0.0), h1 = vec3(0.0), gx = vec3(0.0), gy = vec3(0.0);
  float c2 = 0.0, cn = 0.0, hn = 0.0, hInverseFrames = 0.0, pooled = 0.0;
  for (int y = -1; y <= 1; ++y) {
    for (int x = -1; x <= 1; ++x) {
      ivec2 q = clamp(ip + ivec2(x, y), ivec2(0), ivec2(pc.size) - 1);
      vec4 qv = texelFetch(signal, q, 0);
      if (!rbDnSky(texelFetch(depthImage, q, 0).r) && (!reflection || qv.a >= 0.5 || rbDnRgbKeptMark(qv.a))) {
        c1 += qv.rgb;
        c2 += dot(qv.rgb, qv.rgb);
        gx += float(x) * qv.rgb;
        gy += float(y) * qv.rgb;
        cn += 1.0;
      }
      ivec2 hq = clamp(pp + ivec2(x, y), ivec2(0), ivec2(pc.size) - 1);
      vec4 h = texelFetch(historyIn, hq, 0);
      if (h.a > 0.5) {
        h1 += h.rgb;
        hn += 1.0;
        hInverseFrames += 1.0 / h.a;
        pooled += rbDnRgbSurfaceVariance(texelFetch(surfaceIn, hq, 0));
      }
    }
  }
  if (cn == 0.0 || hn == 0.0) return 1.0;
  c1 /= cn;
  h1 /= hn;
  // One frame's variance: the history's, pooled over the 3x3 texels (one pixel's recurrence starts at 0 and, on
  // heavy-tailed samples, reads low until a rare one comes), at least this frame's window spread about its plane:
  // less its mean and two slopes, as spatialVariance, 6 degrees of freedom left, with all 9 pixels on the surface
  // (the plain spread read a lamp's steep falloff as noise and its jump went unseen: lamp jump, 4 rays, changed
  // pixels 0.21 at the event against 0.10).
  float spread = cn == 9.0 ? max(c2 - 9.0 * dot(c1, c1) - dot(gx, gx) / 6.0 - dot(gy, gy) / 6.0, 0.0) / 6.0 : 0.0;
  float variance = max(pooled / hn, spread);
  vec3 floorNoise = 0.01 * (abs(c1) + abs(h1)) + 1e-4;
  float noise = variance / cn + variance * hInverseFrames / (hn * hn) + dot(floorNoise, floorNoise);
  vec3 d = c1 - h1;
  // dot(d, d) / noise: a chi-square of 3 degrees (the trace variance spreads over the channels); its root as z.
  return rbDnLagTrust(sqrt(dot(d, d) / noise), kRbDnRgbLagSigmasLow, kRbDnRgbLagSigmasHigh);
}

#endif
