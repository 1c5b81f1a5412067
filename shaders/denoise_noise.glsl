// The scalar denoiser's noise model: how noisy a pixel's (accumulated) value still is, measured from the data,
// and how far the filter may move it. Shared by its temporal and a-trous passes.
#ifndef RAYBRIDGE_DENOISE_NOISE_GLSL
#define RAYBRIDGE_DENOISE_NOISE_GLSL

#include "denoise_common.glsl"

// Binary rays: the neighbourhood's mean enters the pixel's estimate of the ray's probability as this many
// rays' worth. One ray's own 0 or 1 would read as noise-free (p (1 - p) = 0); many rays outweigh it, so an edge
// that every ray agrees on keeps (almost) no noise.
const float kRbDnPriorRays = 1.0;

// Variance of the noise of `mean`, the average of `frames` frames of the signal at `ip`. Each of the four 3x3
// windows that hold the pixel in a corner gives an estimate, and the least is taken (Kuwahara's trick, as the RGB
// path): noise spreads every window, while a noise-free edge, even a one-ray one, leaves a window on its own side.
// With the rays per pixel known (a fraction of binary rays) an estimate is binomial, p (1 - p) / (rays * frames),
// at a probability p from the pixel's own rays plus the window's mean; else the window's variance divided by the
// frames averaged.
float rbDnNoiseVariance(sampler2D signal, ivec2 ip, float mean, float frames) {
  float v[25];
  for (int y = -2; y <= 2; ++y)
    for (int x = -2; x <= 2; ++x) v[(y + 2) * 5 + x + 2] = rbDnSignalValue(texelFetch(signal, clamp(ip + ivec2(x, y), ivec2(0), ivec2(pc.size) - 1), 0).r);
  const float rays = pc.signalRaysPerPixel * frames;
  const float c = clamp(mean, 0.0, 1.0);
  float least = 1e30;
  for (int wy = 0; wy <= 2; wy += 2) {
    for (int wx = 0; wx <= 2; wx += 2) {
      float m1 = 0.0, m2 = 0.0;
      for (int y = 0; y < 3; ++y) {
        for (int x = 0; x < 3; ++x) {
          float q = v[(wy + y) * 5 + wx + x];
          m1 += q;
          m2 += q * q;
        }
      }
      m1 /= 9.0;
      float variance;
      if (rays > 0.0) {
        float p = clamp((c * rays + kRbDnPriorRays * m1) / (rays + kRbDnPriorRays), 0.0, 1.0);
        variance = p * (1.0 - p) / rays;
      } else {
        variance = max(m2 / 9.0 - m1 * m1, 0.0) * (9.0 / 8.0) / frames;
      }
      least = min(least, variance);
    }
  }
  return least;
}

// Which fraction of the history at `pp` (.x mean, .y frames) to keep for the pixel `ip`
// whose raw signal is `signal`: 1 = all, 0 = start afresh from this frame. Compares the mean of the 3x3 surface
// pixels around `ip` this frame with that of the 3x3 history texels around `pp`. The difference's noise: binomial
// at the two means' average probability (at least 0.05 from 0 and 1, so that a converged 0 or 1 does not read as
// noise-free) for the rays per pixel, one when unknown; over 9 pixels, and the history's share of it, each texel's by
// its own frames (a neighbour that just started afresh is as noisy as this frame: counting it as converged would let
// one reset trigger the next).
float rbDnHistoryTrust(sampler2D signal, sampler2D depthImage, ivec2 ip, sampler2D historyIn, ivec2 pp) {
  float c1 = 0.0, cn = 0.0, h1 = 0.0, hn = 0.0, hInverseFrames = 0.0;
  for (int y = -1; y <= 1; ++y) {
    for (int x = -1; x <= 1; ++x) {
      ivec2 q = clamp(ip + ivec2(x, y), ivec2(0), ivec2(pc.size) - 1);
      if (!rbDnSky(texelFetch(depthImage, q, 0).r)) {
        float v = rbDnSignalValue(texelFetch(signal, q, 0).r);
        c1 += v;
        cn += 1.0;
      }
      vec2 h = texelFetch(historyIn, clamp(pp + ivec2(x, y), ivec2(0), ivec2(pc.size) - 1), 0).xy;
      if (h.y > 0.0) {
        h1 += h.x;
        hn += 1.0;
        hInverseFrames += 1.0 / h.y;
      }
    }
  }
  if (cn == 0.0 || hn == 0.0) return 1.0;
  c1 /= cn;
  h1 /= hn;
  // Of one pixel's raw value. Rays unknown: as one binary ray, the most a signal in [0, 1] with that mean can vary
  // (a window's own spread can be 0 by chance: nine equal values of a noisy signal).
  float p = clamp(0.5 * (c1 + h1), 0.05, 0.95);
  float variance = p * (1.0 - p) / max(pc.signalRaysPerPixel, 1.0);
  float differenceVariance = variance / cn + variance * hInverseFrames / (hn * hn);
  return rbDnLagTrust(abs(c1 - h1) * inversesqrt(differenceVariance), kRbDnLagSigmasLow, kRbDnLagSigmasHigh);
}

// The largest shift the filter may give a pixel, in standard deviations of its noise: a larger difference
// between the filtered and the unfiltered value is more than noise explains (an edge, the curve of a penumbra),
// and the shift then falls off as (limit / difference)^4. One: on the effects bench's demo scene (lavapipe, 160x90)
// three let the filter's bias in narrow penumbrae and AO creases through (denoised shadows at 32 rays 0.016 RMSE
// against 0.0066 raw); one halves that, and kDefaultDenoiseConvergedNoise leaves many-ray pixels alone.
const float kRbDnShiftSigmas = 1.0;

// Short-history filtering (RB_DN_SHORT_HISTORY, DenoiseSettings::shortHistoryFilter): a pixel whose history is
// short (after a reset, a teleport, a disocclusion) is filtered towards a quarter of pc.convergedNoise, not the
// whole, with a shift limit of up to two standard deviations, not one: its spatial neighbours stand in for the
// frames it lacks, as in ReBLUR's history fix. Both scale with rbDnYouth, which falls linearly over the first
// kRbDnShortHistoryFrames frames, from (1 - rays / kRbDnShortHistoryRays) at the first: a signal of 32 rays and more
// per frame is filtered as before, and so is every pixel from 16 frames on (a still camera's). Tuned on
// tests/motion_lag_test.cpp's teleport (4 rays, 96x72, lavapipe): AO's changed pixels at 1.04-1.43x a long
// history's error on frames 1 to 5 after the teleport's, 1.8-1.9x without; the effects bench's single-frame AO rows
// lose 4-46% of their error at 1 to 16 rays (half resolution at 16 rays +1.6%). Shadows lose by it (their narrow
// penumbrae take the filter's bias: +10% to +100% on those rows), so it is a setting per signal.
const float kRbDnShortHistoryFrames = 16.0;
const float kRbDnShortHistoryRays = 32.0;
const float kRbDnShortHistoryNoise = 0.25;
const float kRbDnShortHistoryShiftSigmas = 2.0;

// 0 = filter as any pixel, 1 = the short-history filter in full (the first frame of a one-ray signal).
float rbDnYouth(float frames) {
  if ((pc.flags & RB_DN_SHORT_HISTORY) == 0u || pc.signalRaysPerPixel <= 0.0) return 0.0;
  return clamp(1.0 - pc.signalRaysPerPixel / kRbDnShortHistoryRays, 0.0, 1.0) *
         clamp(1.0 - frames / kRbDnShortHistoryFrames, 0.0, 1.0);
}

// The noise under which a pixel of youth `youth` passes unfiltered.
float rbDnGateNoise(float youth) { return pc.convergedNoise * mix(1.0, kRbDnShortHistoryNoise, youth); }

// `anchor` (unfiltered, noise variance `variance`) moved towards `filtered` as far as its noise explains; left
// exactly as it is where the noise's standard deviation is under pc.convergedNoise, with a ramp up to twice that.
// `bias2`: the filter's squared bias around the pixel, estimated by the caller; the shift is scaled by the Wiener
// gain variance / (variance + bias2), so where filtering changes the signal itself (a shadow pattern finer than
// the filter) more than the noise it removes, the pixel stays near its own value. `youth`: rbDnYouth of the
// pixel's history, which lowers that threshold and widens the limit.
float rbDnLimitedShift(float anchor, float variance, float filtered, float bias2, float youth) {
  float sigma = sqrt(max(variance, 0.0));
  float gain = clamp(sigma / rbDnGateNoise(youth) - 1.0, 0.0, 1.0);
  if (gain <= 0.0) return anchor;
  float d = filtered - anchor;
  float limit = mix(kRbDnShiftSigmas, kRbDnShortHistoryShiftSigmas, youth) * sigma;
  float r = abs(d) <= limit ? 1.0 : limit / abs(d);
  float wiener = variance / (variance + max(bias2, 0.0));
  return anchor + gain * wiener * d * (r * r) * (r * r);
}

#endif
