#version 450
#extension GL_GOOGLE_include_directive : require
// Ground-truth-based ambient occlusion (GTAO: Jimenez et al. 2016, "Practical Realtime Strategies for
// Accurate Indirect Occlusion"). Per pixel, `sliceCount` planes through the view vector, evenly spaced in
// screen angle with a per-pixel rotation; in each, the depth buffer is searched along both screen directions
// for the highest horizon within `radius` (world units, faded out over its last kFalloff part; the elevation
// is measured above the tangent plane, see below), and the
// cosine-weighted visible arc between the two horizons is integrated analytically against the normal
// projected into the slice. The result is normalised by the same integral with no occluder, so an open
// surface is exactly 1 whatever the slice count or rotation (a ratio estimator of the cosine-weighted
// visibility). Output: visibility^power, 1 = open, background 1. The slice rotation repeats over 4x4 pixels,
// which ssao_blur.comp averages out.
#include "frame_uniforms.glsl"
#include "screen_space.glsl"
#include "ssao_inputs.glsl"

const float PI = 3.14159265358979;
const float HALF_PI = 1.57079632679490;
// Occluders between (1 - kFalloff) * radius and radius count less and less: no hard edge where a distance
// crosses the radius.
const float kFalloff = 0.2;
// The search reaches at most this fraction of the render height from the pixel, however close the camera:
// bounds the cost (and the cache misses) of a radius that covers the screen.
const float kMaxScreenRadius = 0.25;

// 4x4 Bayer index in [0,16), and a second 4x4 pattern (the Bayer matrix transposed and shifted) that is
// uncorrelated with it: slice rotation and step jitter per pixel.
float bayer4(ivec2 p) {
  const float bayer[16] = float[](0, 8, 2, 10, 12, 4, 14, 6, 3, 11, 1, 9, 15, 7, 13, 5);
  return (bayer[(p.y & 3) * 4 + (p.x & 3)] + 0.5) / 16.0;
}

// Integral of cos(theta - gamma) |sin(theta)| dtheta over [0, h] (h >= 0) or [h, 0] (h <= 0), GTAO paper eq. 10:
// one side of the visible arc of a slice whose projected normal is at angle gamma from v.
float arcIntegral(float h, float gamma) {
  return 0.25 * (-cos(2.0 * h - gamma) + cos(gamma) + 2.0 * h * sin(gamma));
}

void main() {
  ivec2 pixel;
  if (!ssaoPixel(pixel)) return;
  float depth = texelFetch(depthTex, pixel, 0).r;
  if (depth >= 1.0) {  // background: nothing to occlude
    imageStore(outAo, pixel, vec4(1.0));
    return;
  }
  vec3 p = viewFromDepth(pixelUv(pixel), depth);
  vec3 v = normalize(-p);
  vec3 n = normalize(mat3(frame.view) * texelFetch(normalTex, pixel, 0).xyz);
  vec3 origin = p + n * pc.bias;

  // The radius projected at the pixel's depth, in pixels (proj[1][1] maps view y / -z to NDC).
  float pixelRadius =
      min(pc.radius * abs(frame.proj[1][1]) * 0.5 * frame.viewport.y / -p.z, kMaxScreenRadius * frame.viewport.y);
  ivec2 last = ivec2(frame.viewport.xy) - 1;
  float falloffStart = (1.0 - kFalloff) * pc.radius;
  float rotation = bayer4(pixel), jitter = bayer4(ivec2(pixel.y + 1, pixel.x + 2));

  float visible = 0.0, open = 0.0;
  for (uint s = 0u; s < pc.sliceCount; ++s) {
    float phi = (float(s) + rotation) * PI / float(pc.sliceCount);
    vec2 dir = vec2(cos(phi), sin(phi));  // screen (pixel) space
    // The slice plane: the view vector and the view-space direction of `dir` at the pixel's depth.
    vec3 along = viewFromDepth(pixelUv(pixel) + dir * frame.viewport.zw, depth) - p;
    vec3 d = normalize(along - dot(along, v) * v);
    vec3 axis = cross(d, v);
    vec3 projected = n - axis * dot(n, axis);
    float projectedLength = length(projected);
    if (projectedLength < 1e-4) continue;  // the normal is perpendicular to the slice: no weight
    float gamma = sign(dot(projected, d)) * acos(clamp(dot(projected, v) / projectedLength, -1.0, 1.0));

    // Highest horizon per side, as the sine of its elevation above the tangent plane. The elevation comes from
    // the tap's height above that plane (along n), not from its angle to v: a tap rounded to a texel centre
    // lies a little off the slice, and on ground seen at a grazing angle its angle to v would rise above the
    // tangent line although it lies in the plane. Its height stays 0 (-bias), so flat ground stays open. For
    // a tap in the slice this is exactly the in-slice elevation: the height over the distance is its sine
    // times the projected normal's length.
    float horizonSin[2] = float[](0.0, 0.0);
    for (int side = 0; side < 2; ++side) {
      float sideSign = side == 0 ? 1.0 : -1.0;
      for (uint i = 0u; i < pc.stepsPerSide; ++i) {
        // Even spacing, jittered per pixel: a quadratic one (more taps near the pixel) misses more of the far
        // horizon with few taps (a concave corner came out up to 0.04 too open). At least one pixel out.
        float t = (float(i) + jitter) / float(pc.stepsPerSide);
        ivec2 q = ivec2(round(vec2(pixel) + sideSign * dir * max(t * pixelRadius, 1.0)));
        if (any(lessThan(q, ivec2(0))) || any(greaterThan(q, last))) break;  // off screen: unknown, open
        float qDepth = texelFetch(depthTex, q, 0).r;
        if (qDepth >= 1.0) continue;
        vec3 delta = viewFromDepth(pixelUv(q), qDepth) - origin;
        float distance = length(delta);
        if (distance < 1e-6) continue;
        float weight = clamp((pc.radius - distance) / (pc.radius - falloffStart), 0.0, 1.0);
        horizonSin[side] = max(horizonSin[side], weight * dot(delta, n) / (distance * projectedLength));
      }
    }
    // Horizon angles from v (positive towards d): the tangent line raised by the elevations. A horizon never
    // crosses v (it would hide the pixel from the camera).
    float h0 = max(gamma + HALF_PI - asin(min(horizonSin[0], 1.0)), 0.0);
    float h1 = min(gamma - HALF_PI + asin(min(horizonSin[1], 1.0)), 0.0);
    visible += projectedLength * (arcIntegral(h0, gamma) + arcIntegral(h1, gamma));
    open += projectedLength * (cos(gamma) + gamma * sin(gamma));  // both arcs at the tangent plane
  }
  float visibility = open > 0.0 ? clamp(visible / open, 0.0, 1.0) : 1.0;
  // pow(0, 0) is undefined in GLSL: power 0 means no darkening.
  imageStore(outAo, pixel, vec4(pc.power > 0.0 ? pow(visibility, pc.power) : 1.0));
}
