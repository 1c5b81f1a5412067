#version 460
#extension GL_GOOGLE_include_directive : require
// Temporal accumulation of an RGB signal with reprojection (as denoise_temporal.comp: the same surface found
// where it was last frame, a running mean over up to `max history` frames), plus the first and second moments of
// its luminance (SVGF, Schied et al. 2017). Writes the accumulated colour with the standard deviation of its
// luminance in .a: the per-frame variance (from the moments, or from the 3x3 neighbourhood while the history is
// short) divided by the frames averaged, so the spatial filter knows how noisy the mean still is and leaves a
// converged or noise-free pixel alone.
#include "denoise_rgb_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_DEPTH) uniform sampler2D gDepth;
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_MOTION) uniform sampler2D gMotion;  // pixels, current - previous
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_SIGNAL) uniform sampler2D signalIn;  // .rgb, this frame's
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_HISTORY_IN) uniform sampler2D historyIn;
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_MOMENTS_IN) uniform sampler2D momentsIn;
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_DISTANCE_IN) uniform sampler2D distanceIn;
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_HISTORY_OUT, rgba16f) uniform writeonly image2D historyOut;
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_MOMENTS_OUT, rg32f) uniform writeonly image2D momentsOut;
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_DISTANCE_OUT, r32f) uniform writeonly image2D distanceOut;
layout(set = 0, binding = RB_RGB_TEMPORAL_BINDING_VALUE_OUT, rgba16f) uniform writeonly image2D valueOut;

void main() {
  uvec2 pixel = gl_GlobalInvocationID.xy;
  if (any(greaterThanEqual(pixel, pc.size))) return;
  ivec2 ip = ivec2(pixel);
  const bool final = (pc.flags & RB_DN_RGB_FINAL) != 0u;
  vec3 value = texelFetch(signalIn, ip, 0).rgb;
  float depth = texelFetch(gDepth, ip, 0).r;
  if (rbDnSky(depth)) {
    imageStore(historyOut, ip, vec4(value, 0.0));
    imageStore(momentsOut, ip, vec4(0.0));
    imageStore(distanceOut, ip, vec4(0.0));
    imageStore(valueOut, ip, vec4(value, final ? 1.0 : 0.0));
    return;
  }
  vec3 rel = rbDnCameraRelative(pixel, depth);
  float dist = length(rel);
  imageStore(distanceOut, ip, vec4(dist));
  vec2 prevPixel;
  vec3 prevRel = rel + pc.cameraDelta;
  if ((pc.flags & RB_DN_MOTION) != 0u) {
    prevPixel = vec2(pixel) + 0.5 - texelFetch(gMotion, ip, 0).xy;
  } else {
    vec4 clip = pc.previousViewProjection * vec4(prevRel, 1.0);
    prevPixel = (clip.xy / clip.w * 0.5 + 0.5) * vec2(pc.size);
  }
  float lum = rbDnLuminance(value);
  vec3 accumulated = value;
  vec2 moments = vec2(lum, lum * lum);
  float frames = 1.0;
  ivec2 pp = ivec2(floor(prevPixel));
  if ((pc.flags & RB_DN_HISTORY) != 0u && all(greaterThanEqual(pp, ivec2(0))) && all(lessThan(pp, ivec2(pc.size)))) {
    float prevDist = texelFetch(distanceIn, pp, 0).r;
    if (prevDist > 0.0 && abs(prevDist - length(prevRel)) <= 0.02 * length(prevRel) + 1e-3) {
      vec4 h = texelFetch(historyIn, pp, 0);
      frames = min(h.a + 1.0, float(pc.maxHistoryFrames));
      float alpha = 1.0 / frames;
      accumulated = mix(h.rgb, value, alpha);
      moments = mix(texelFetch(momentsIn, pp, 0).xy, moments, alpha);
    }
  }
  float variance;  // of one frame's luminance
  if (frames < kRbDnMinTemporalVarianceFrames) {
    // Too few frames for the moments: the spread of the neighbourhood, taken as the least of the four 3x3
    // windows that have this pixel in a corner (Kuwahara's trick). Noise spreads every window, while a
    // noise-free edge or gradient leaves at least one window on its own side nearly flat, so it is not taken
    // for noise. Neighbours on another surface (a depth step) are left out too.
    float lums[25];
    bool same[25];
    for (int y = -2; y <= 2; ++y) {
      for (int x = -2; x <= 2; ++x) {
        int k = (y + 2) * 5 + (x + 2);
        ivec2 q = clamp(ip + ivec2(x, y), ivec2(0), ivec2(pc.size) - 1);
        float qd = texelFetch(gDepth, q, 0).r;
        same[k] = !rbDnSky(qd) && abs(length(rbDnCameraRelative(uvec2(q), qd)) - dist) <= 0.05 * dist;
        lums[k] = rbDnLuminance(texelFetch(signalIn, q, 0).rgb);
      }
    }
    variance = 1e30;
    for (int wy = 0; wy <= 2; wy += 2) {
      for (int wx = 0; wx <= 2; wx += 2) {
        float m1 = 0.0, m2 = 0.0, count = 0.0;
        for (int y = wy; y < wy + 3; ++y) {
          for (int x = wx; x < wx + 3; ++x) {
            int k = y * 5 + x;
            if (!same[k]) continue;
            m1 += lums[k];
            m2 += lums[k] * lums[k];
            count += 1.0;
          }
        }
        // count >= 1: the centre is in every window and always on its own surface.
        m1 /= count;
        variance = min(variance, max(m2 / count - m1 * m1, 0.0) * count / max(count - 1.0, 1.0));
      }
    }
    variance *= kRbDnWindowMinCorrection;
  } else {
    variance = max(moments.y - moments.x * moments.x, 0.0);
  }
  imageStore(historyOut, ip, vec4(accumulated, frames));
  imageStore(momentsOut, ip, vec4(moments, 0.0, 0.0));
  imageStore(valueOut, ip, vec4(accumulated, final ? 1.0 : sqrt(variance / frames)));
}
