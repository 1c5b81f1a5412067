#version 460
#extension GL_GOOGLE_include_directive : require
// The depth-aware upsample of a pass traced at half resolution (one sample per 2x2 block, half_resolution.glsl)
// into its full-resolution output. Each pixel weights the samples of its bilinear footprint (the 2x2 samples
// around it on this frame's sample grid) by
//   bilinear weight * exp(-plane distance / tolerance) * max(n . n_sample, 0)^kNormalPower,
// where a sample's surface (depth and normal) is read at the pixel it traced from, the plane distance is that
// point's distance from the pixel's tangent plane and the tolerance kDepthSigma of the view distance (the
// denoiser's depthSigma): a sample across a silhouette or a crease loses its weight, so the foreground does not
// bleed into the background as a plain bilinear upsample would. Where no footprint sample lies on the pixel's
// surface (a feature thinner than the sample spacing), the most similar sample of the 3x3 around the nearest one
// stands in. A pixel a sample was traced for gets that sample exactly (its bilinear weight is 1).
// Body of the variants upsample_depth_aware_ao.comp (R16F open fraction) and upsample_depth_aware_reflection.comp
// (RB_UPSAMPLE_REFLECTION: RGBA16F radiance, a = coverage), rows of shaders/variants.cmake.
#include "raybridge_pass_constants.glsl"
layout(push_constant) uniform UpsamplePushConstants { UpsampleConstants pc; };
#include "half_resolution.glsl"
#include "pass_inputs.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = RB_UPSAMPLE_BINDING_DEPTH) uniform sampler2D gDepth;
layout(set = 0, binding = RB_UPSAMPLE_BINDING_NORMAL) uniform sampler2D gNormal;
layout(set = 0, binding = RB_UPSAMPLE_BINDING_SAMPLES) uniform sampler2D samples;
#ifdef RB_UPSAMPLE_REFLECTION
layout(set = 0, binding = RB_UPSAMPLE_BINDING_ROUGHNESS_METALNESS) uniform sampler2D gRoughnessMetalness;
layout(set = 0, binding = RB_UPSAMPLE_BINDING_OUTPUT, rgba16f) uniform writeonly image2D outImage;
#else
layout(set = 0, binding = RB_UPSAMPLE_BINDING_OUTPUT, r16f) uniform writeonly image2D outImage;
#endif

// Plane-distance tolerance relative to the view distance. Looser than the denoiser's per-pixel 0.005: the samples
// are up to two pixels away, and a curved surface leaves its tangent plane with the square of the distance.
const float kDepthSigma = 0.01;
const float kNormalPower = 16.0;
// Below this total weight (the bilinear weights sum to 1) no footprint sample is on the pixel's surface.
const float kMinWeight = 1e-3;
// The fallback's surface distance: plane distance in tolerances, plus this per unit of (1 - n . n_sample), so a
// normal turned by 90 degrees counts as far as 8 tolerances off the plane.
const float kNormalPenalty = 8.0;

struct Tap {
  vec4 value;
  bool valid;           // holds a value for a surface (see readTap)
  float planeDistance;  // of the sample's surface point from the pixel's tangent plane, in tolerances
  float cosine;         // n . n_sample
};

Tap readTap(uvec2 cell, vec3 p, vec3 n, float tolerance) {
  Tap t;
  t.value = texelFetch(samples, ivec2(cell), 0);
  t.planeDistance = 0.0;
  t.cosine = 0.0;
  ivec2 traced = ivec2(rbHalfResTracedPixel(cell, pc.gbuffer.frameIndex, pc.gbuffer.size));
  float depth = texelFetch(gDepth, traced, 0).r;
#ifdef RB_UPSAMPLE_REFLECTION
  t.valid = t.value.a > 0.0;  // traced (a surface under the roughness threshold), not sky or rough
#else
  t.valid = !rbIsSky(depth);  // a sky sample's 1 says nothing about a surface
#endif
  if (!t.valid) return t;
  vec3 q = rbCameraRelative(uvec2(traced), depth);
  t.planeDistance = abs(dot(q - p, n)) / tolerance;
  t.cosine = dot(n, rbDecodeNormal(texelFetch(gNormal, traced, 0), rbNormalEncoding()));
  return t;
}

// One axis of the bilinear footprint: the samples c0, c1 around full-resolution coordinate x and the weight of c1,
// from the coordinates of the pixels they traced (clamped at the image's far edge, so a clamped sample still
// lands on its own pixel with weight 1).
void footprintAxis(uint x, uint offset, uint cells, uint size, out uint c0, out uint c1, out float f) {
  int below = int(floor((float(x) - float(offset)) * 0.5));
  c0 = uint(clamp(below, 0, int(cells) - 1));
  c1 = uint(clamp(below + 1, 0, int(cells) - 1));
  float x0 = float(min(2u * c0 + offset, size - 1u)), x1 = float(min(2u * c1 + offset, size - 1u));
  f = x1 > x0 ? clamp((float(x) - x0) / (x1 - x0), 0.0, 1.0) : 0.0;
}

void store(ivec2 ip, vec4 value) {
#ifdef RB_UPSAMPLE_REFLECTION
  imageStore(outImage, ip, value);
#else
  imageStore(outImage, ip, vec4(value.r));
#endif
}

void main() {
  uvec2 pixel = gl_GlobalInvocationID.xy;
  if (any(greaterThanEqual(pixel, pc.gbuffer.size))) return;
  ivec2 ip = ivec2(pixel);
  float depth = texelFetch(gDepth, ip, 0).r;
  vec4 normalTexel = texelFetch(gNormal, ip, 0);
  // What the full-resolution pass writes where it traces nothing: AO is open on the sky; reflections have no
  // coverage on the sky and on surfaces rougher than the threshold.
#ifdef RB_UPSAMPLE_REFLECTION
  if (rbIsSky(depth) || rbRoughness(normalTexel, gRoughnessMetalness, ip) > pc.roughnessThreshold) {
    store(ip, vec4(0.0));
    return;
  }
#else
  if (rbIsSky(depth)) {
    store(ip, vec4(1.0));
    return;
  }
#endif
  vec3 p = rbCameraRelative(pixel, depth);
  vec3 n = rbDecodeNormal(normalTexel, rbNormalEncoding());
  float tolerance = length(p) * kDepthSigma + 1e-6;
  uvec2 cells = rbHalfResSize(pc.gbuffer.size);
  uvec2 offset = rbHalfResOffset(pc.gbuffer.frameIndex);
  uvec2 c0, c1;
  vec2 f;
  footprintAxis(pixel.x, offset.x, cells.x, pc.gbuffer.size.x, c0.x, c1.x, f.x);
  footprintAxis(pixel.y, offset.y, cells.y, pc.gbuffer.size.y, c0.y, c1.y, f.y);

  // Sums of differences from the first tap: equal samples give exactly that value, without rounding.
  vec4 first = vec4(0.0), sum = vec4(0.0);
  float weights = 0.0;
  bool haveFirst = false;
  for (int k = 0; k < 4; ++k) {
    bvec2 second = bvec2((k & 1) != 0, (k & 2) != 0);
    float bilinear = (second.x ? f.x : 1.0 - f.x) * (second.y ? f.y : 1.0 - f.y);
    if (bilinear <= 0.0) continue;
    Tap t = readTap(uvec2(second.x ? c1.x : c0.x, second.y ? c1.y : c0.y), p, n, tolerance);
    if (!t.valid) continue;
    if (!haveFirst) {
      first = t.value;
      haveFirst = true;
    }
    float w = bilinear * exp(-t.planeDistance) * pow(max(t.cosine, 0.0), kNormalPower);
    sum += w * (t.value - first);
    weights += w;
  }
  if (weights >= kMinWeight) {
    store(ip, first + sum / weights);
    return;
  }

  // No footprint sample on this surface: the most similar valid sample around the nearest one.
  uvec2 nearest = uvec2(f.x > 0.5 ? c1.x : c0.x, f.y > 0.5 ? c1.y : c0.y);
  float best = 1e30;
  vec4 chosen = vec4(0.0);
  bool found = false;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      ivec2 cell = ivec2(nearest) + ivec2(dx, dy);
      if (any(lessThan(cell, ivec2(0))) || any(greaterThanEqual(cell, ivec2(cells)))) continue;
      Tap t = readTap(uvec2(cell), p, n, tolerance);
      float score = t.planeDistance + kNormalPenalty * (1.0 - t.cosine);
      if (t.valid && score < best) {
        best = score;
        chosen = t.value;
        found = true;
      }
    }
  }
#ifdef RB_UPSAMPLE_REFLECTION
  // A pixel the full-resolution pass would trace takes the most similar covered sample, however far its surface:
  // the engine treats a = 0 as "reflects nothing", which costs the pixel its whole reflected radiance, while a
  // neighbour's reflection is off only by how much the reflection changes between them (and the coverage stays
  // the full-resolution pass's, the set of pixels the Reflection denoiser filters). Only with no covered sample
  // within reach (a smooth speck among rough or sky pixels) is there nothing to take: a = 0.
  store(ip, found ? vec4(chosen.rgb, 1.0) : vec4(0.0));
#else
  // Every sample within reach traced the sky: its 1 (open) is the nearest thing to a value.
  store(ip, found ? chosen : texelFetch(samples, ivec2(nearest), 0));
#endif
}
