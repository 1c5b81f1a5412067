// The shadow pass's per-pixel test, the one place that decides whether a G-buffer pixel needs shadow rays: its
// ray generation shader (shadow_raygen.glsl) and its tile classifier (shadow_classify.glsl) both call
// rbShadowPixel, so a tile the classifier skips is one the ray generation shader would have traced nothing for.
// Include after the ShadowConstants push constant block; declares the G-buffer bindings it reads.
#ifndef RAYBRIDGE_SHADOW_PIXEL_GLSL
#define RAYBRIDGE_SHADOW_PIXEL_GLSL

#include "pass_inputs.glsl"

layout(set = 0, binding = RB_BINDING_DEPTH) uniform sampler2D gDepth;
layout(set = 0, binding = RB_BINDING_NORMAL) uniform sampler2D gNormal;
layout(set = 0, binding = RB_BINDING_GEOMETRIC_NORMAL) uniform sampler2D gGeometricNormal;

// What a pixel needs. The untraced kinds have fixed outputs (rbShadowUntracedVisibility; no occluder distance).
#define RB_SHADOW_PIXEL_SKY 0u    // visibility 1: nothing to shadow; lighting ignores sky pixels anyway
#define RB_SHADOW_PIXEL_UNLIT 1u  // visibility 0: the shading normal faces away, or outside the range or cone
#define RB_SHADOW_PIXEL_TRACE 2u  // rays decide

struct ShadowPixel {
  uint kind;            // RB_SHADOW_PIXEL_*
  vec3 origin;          // the rays' origin, off the surface (RB_SHADOW_PIXEL_TRACE only)
  vec3 toLight;         // unit, towards the light's centre (RB_SHADOW_PIXEL_TRACE only)
  float lightDistance;  // to the light's centre; 1e30 for a directional light
};

ShadowPixel rbShadowPixel(uvec2 pixel) {
  ShadowPixel s;
  s.kind = RB_SHADOW_PIXEL_SKY;
  s.origin = vec3(0.0);
  s.toLight = vec3(0.0);
  s.lightDistance = 0.0;
  ivec2 ip = ivec2(pixel);
  float depth = texelFetch(gDepth, ip, 0).r;
  if (rbIsSky(depth)) return s;
  vec3 n = rbDecodeNormal(texelFetch(gNormal, ip, 0), rbNormalEncoding());
  vec3 ng = (pc.gbuffer.flags & RB_GB_GEOMETRIC_NORMAL) != 0u
                ? rbDecodeNormal(texelFetch(gGeometricNormal, ip, 0), rbNormalEncoding())
                : n;
  vec3 facing;
  s.origin = rbRayOrigin(pixel, depth, ng, facing);
  vec3 surface = rbSurfacePoint(pixel, depth);
  uint type = pc.lightType;
  if (type == RB_LIGHT_DIRECTIONAL) {
    s.toLight = normalize(pc.lightDirection);
    s.lightDistance = 1e30;
  } else {
    s.toLight = pc.lightPosition - surface;
    s.lightDistance = length(s.toLight);
    s.toLight /= max(s.lightDistance, 1e-20);
  }
  bool inRange = pc.range <= 0.0 || s.lightDistance <= pc.range;
  bool inCone = type != RB_LIGHT_SPOT || dot(-s.toLight, normalize(pc.spotDirection)) >= pc.cosSpotOuterAngle;
  // The shading normal decides: where it faces away, lighting is zero whatever a ray would find.
  bool lit = dot(n, s.toLight) > 0.0 && dot(facing, s.toLight) > -0.05 && inRange && inCone;
  s.kind = lit ? RB_SHADOW_PIXEL_TRACE : RB_SHADOW_PIXEL_UNLIT;
  return s;
}

float rbShadowUntracedVisibility(uint kind) { return kind == RB_SHADOW_PIXEL_SKY ? 1.0 : 0.0; }

#endif
