// The scalar denoiser's noise model: how noisy a pixel's (accumulated) value still is, measured from the data,
// and how far the filter may move it. Shared by its temporal and a-trous passes.
#ifndef RAYBRIDGE_DENOISE_NOISE_GLSL
#define RAYBRIDGE_DENOISE_NOISE_GLSL

#include "denoise_common.glsl"

// Binary rays: the neighbourhood's mean enters the pixel's estimate of the ray's probability as this many
// rays' worth. One ray's own 0 or 1 would read as noise-free (p (1 - p) = 0); many rays outweigh it, so an edge
// that every ray agrees on keeps (almost) no noise.
const float kRbDnPriorRays = 1.0;

// Variance of the noise of `mean`, the average of `frames` frames of the signal at `ip`: with the rays per
// pixel known (a fraction of binary rays), binomial, p (1 - p) / (rays * frames), at a probability p taken from
// the pixel's own rays and the 3x3 neighbourhood of this frame's signal; else this frame's 3x3 variance divided
// by the frames averaged.
float rbDnNoiseVariance(sampler2D signal, ivec2 ip, float mean, float frames) {
  float m1 = 0.0, m2 = 0.0;
  for (int y = -1; y <= 1; ++y) {
    for (int x = -1; x <= 1; ++x) {
      float v = texelFetch(signal, clamp(ip + ivec2(x, y), ivec2(0), ivec2(pc.size) - 1), 0).r;
      m1 += v;
      m2 += v * v;
    }
  }
  m1 /= 9.0;
  if (pc.signalRaysPerPixel > 0.0) {
    float rays = pc.signalRaysPerPixel * frames;
    float p = clamp((clamp(mean, 0.0, 1.0) * rays + kRbDnPriorRays * m1) / (rays + kRbDnPriorRays), 0.0, 1.0);
    return p * (1.0 - p) / rays;
  }
  return max(m2 / 9.0 - m1 * m1, 0.0) * (9.0 / 8.0) / frames;
}

// The largest shift the filter may give a pixel, in standard deviations of its noise: a larger difference
// between the filtered and the unfiltered value is more than noise explains (an edge, the curve of a penumbra),
// and the shift then falls off as (limit / difference)^4. Three, not two: the noise is binomial (skewed at few
// rays), and the pixels furthest from the truth are the ones the filter must be free to move.
const float kRbDnShiftSigmas = 3.0;

// `anchor` (unfiltered, noise variance `variance`) moved towards `filtered` as far as its noise explains; left
// exactly as it is where the noise's standard deviation is under pc.convergedNoise, with a ramp up to twice that.
float rbDnLimitedShift(float anchor, float variance, float filtered) {
  float sigma = sqrt(max(variance, 0.0));
  float gain = clamp(sigma / pc.convergedNoise - 1.0, 0.0, 1.0);
  if (gain <= 0.0) return anchor;
  float d = filtered - anchor;
  float limit = kRbDnShiftSigmas * sigma;
  float r = abs(d) <= limit ? 1.0 : limit / abs(d);
  return anchor + gain * d * (r * r) * (r * r);
}

#endif
