#version 450
#extension GL_GOOGLE_include_directive : require
// Forward PBR lighting: GGX specular + Lambert diffuse for the sun, constant-sky ambient, with optional
// external sun visibility / AO / reflection images replacing the engine's own terms (the reflection only
// where its alpha says it covers the pixel). Also used (depth LESS) to capture the reflection probe, with
// frame.probe.x = 0 and no screen-space inputs, and for BLEND draws after the opaque lighting: output alpha =
// the surface's, blended over the target (src alpha, one minus src alpha). The screen-space inputs describe
// the opaque surface behind a blended one, so BLEND draws ignore them: shadow map (or unshadowed), no AO
// image, the engine's own environment term.
#include "common.glsl"
#include "surface.glsl"
#include "shadow_sampling.glsl"
#define LOCAL_LIGHT_SET 2
#define LOCAL_LIGHT_BINDING 5
#include "local_lights.glsl"

layout(set = 2, binding = 0) uniform sampler2DShadow shadowMap;
layout(set = 2, binding = 1) uniform sampler2D externalVisibility;
layout(set = 2, binding = 2) uniform sampler2D externalAo;
layout(set = 2, binding = 3) uniform sampler2D externalReflection;
// Reflection probe (engine-captured cubemap with mips); a 1x1 black cube when no probe is in use.
layout(set = 2, binding = 4) uniform samplerCube probeCube;
// Bindings 5-7: local_lights.glsl. External KHR-light irradiance E (LightingInputs::localLightIrradiance).
layout(set = 2, binding = 8) uniform sampler2D externalLocalIrradiance;

layout(location = 0) out vec4 outColor;
// mesh.vert's clip positions for the pre-pass's motion vectors: declared so that the shared vertex shader's outputs
// have a consumer here too (the lighting pass does not read them).
layout(location = 4) in vec4 inCurrentClip;
layout(location = 5) in vec4 inPreviousClip;

const float PI = 3.14159265358979;

float luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

// GGX specular (D * Vis * F) and the Lambert diffuse of one light direction, as the sun's.
void brdf(Surface s, vec3 f0, vec3 l, out vec3 specular, out vec3 diffuse) {
  vec3 h = normalize(l + s.v);
  float nDotL = max(dot(s.n, l), 0.0);
  float nDotV = max(dot(s.n, s.v), 1e-4);
  float nDotH = max(dot(s.n, h), 0.0);
  float vDotH = max(dot(s.v, h), 0.0);
  float a = s.roughness * s.roughness;
  float a2 = a * a;
  float d = a2 / (PI * pow(nDotH * nDotH * (a2 - 1.0) + 1.0, 2.0));
  float vis = 0.5 / (nDotL * sqrt(nDotV * nDotV * (1.0 - a2) + a2) + nDotV * sqrt(nDotL * nDotL * (1.0 - a2) + a2) + 1e-7);
  vec3 f = f0 + (1.0 - f0) * pow(1.0 - vDotH, 5.0);
  specular = d * vis * f;
  diffuse = (1.0 - f) * (1.0 - s.metallic) * s.baseColor / PI;
}

// Karis' analytic approximation of the split-sum environment BRDF.
vec3 environmentBrdf(vec3 f0, float roughness, float nDotV) {
  const vec4 c0 = vec4(-1.0, -0.0275, -0.572, 0.022);
  const vec4 c1 = vec4(1.0, 0.0425, 1.04, -0.04);
  vec4 r = roughness * c0 + c1;
  float a004 = min(r.x * r.x, exp2(-9.28 * nDotV)) * r.x + r.y;
  vec2 ab = vec2(-1.04, 1.04) * a004 + r.zw;
  return f0 * ab.x + ab.y;
}

void main() {
  Surface s = evaluateSurface();
  alphaTest(s);
  const bool blended = draw.alphaMode == SE_ALPHA_BLEND;
  const bool screenInputs = !blended;
  vec2 screenUv = gl_FragCoord.xy * frame.viewport.zw;
  vec3 l = frame.sunDirection.xyz;
  vec3 h = normalize(l + s.v);
  float nDotL = max(dot(s.n, l), 0.0);
  float nDotV = max(dot(s.n, s.v), 1e-4);
  float nDotH = max(dot(s.n, h), 0.0);
  float vDotH = max(dot(s.v, h), 0.0);

  vec3 f0 = mix(vec3(0.04), s.baseColor, s.metallic);
  float a = s.roughness * s.roughness;
  float a2 = a * a;
  float d = a2 / (PI * pow(nDotH * nDotH * (a2 - 1.0) + 1.0, 2.0));
  // Height-correlated Smith visibility term (includes the 1 / (4 NdotL NdotV) factor).
  float vis = 0.5 / (nDotL * sqrt(nDotV * nDotV * (1.0 - a2) + a2) + nDotV * sqrt(nDotL * nDotL * (1.0 - a2) + a2) + 1e-7);
  vec3 f = f0 + (1.0 - f0) * pow(1.0 - vDotH, 5.0);
  vec3 specular = d * vis * f;
  vec3 diffuse = (1.0 - f) * (1.0 - s.metallic) * s.baseColor / PI;

  float visibility = screenInputs && frame.inputs.x != 0u ? clamp(texture(externalVisibility, screenUv).r, 0.0, 1.0)
                                                          : sunVisibility(shadowMap, inEyeRelativePos, s.n, s.ng);
  float ao = screenInputs && frame.inputs.y != 0u ? clamp(texture(externalAo, screenUv).r, 0.0, 1.0) : 1.0;
  ao *= s.occlusion;  // glTF material occlusion (gltf loader work): ambient and environment terms only

  vec3 color = (diffuse + specular) * frame.sunRadiance.rgb * nDotL * visibility;
  vec3 ambient = frame.sky.rgb * frame.sky.w;
  color += ambient * s.baseColor * (1.0 - s.metallic) * ao;  // Lambert under a uniform sky
  vec3 specularWeight = environmentBrdf(f0, s.roughness, nDotV);
  // The engine's own environment term: the reflection probe when in use, else the constant sky. The probe
  // is sharp at mip 0 and blurrier with roughness (box-filtered mips: an approximation of the GGX lobe, good
  // enough for a fallback).
  vec3 reflected = ambient * ao;
  if (frame.probe.x > 0.5) {
    vec3 r = reflect(-s.v, s.n);
    reflected = textureLod(probeCube, r, s.roughness * frame.probe.y).rgb * ao;
  }
  // An external reflection replaces it where it covers the pixel: alpha = coverage (1 = its radiance,
  // 0 = keep the engine's term, e.g. pixels a ray-traced pass did not trace).
  if (screenInputs && frame.inputs.z != 0u) {
    vec4 ext = texture(externalReflection, screenUv);
    reflected = mix(reflected, ext.rgb, clamp(ext.a, 0.0, 1.0));
  }
  color += reflected * specularWeight;
  // KHR lights: every light, shadow-mapped where it has a map this frame. With an external irradiance E the
  // diffuse is albedo * (1 - metallic) / pi * E and the specular the unshadowed one scaled by
  // lum(E) / lum(E_unshadowed) (ratio estimator).
  if (localLightCount() > 0u) {
    vec3 own = vec3(0.0), specularUnshadowed = vec3(0.0), unshadowedE = vec3(0.0);
    for (uint i = 0u; i < localLightCount(); ++i) {
      vec3 li;
      vec3 incident = localLightIncidence(i, inEyeRelativePos, li);
      float nDotLi = dot(s.n, li);
      if (nDotLi <= 0.0 || all(equal(incident, vec3(0.0)))) continue;
      vec3 e = incident * nDotLi;
      vec3 spec, diff;
      brdf(s, f0, li, spec, diff);
      float shadow = localLightShadow(i, inEyeRelativePos, s.ng);
      own += (diff + spec) * e * shadow;
      specularUnshadowed += spec * e;
      unshadowedE += e;
    }
    if (screenInputs && frame.localLights.y != 0u) {
      vec3 givenE = max(texture(externalLocalIrradiance, screenUv).rgb, vec3(0.0));
      float lu = luminance(unshadowedE);
      float ratio = lu > 0.0 ? clamp(luminance(givenE) / lu, 0.0, 1.0) : 0.0;
      color += s.baseColor * (1.0 - s.metallic) / PI * givenE + specularUnshadowed * ratio;
    } else {
      color += own;
    }
  }
  color += s.emissive;
  outColor = vec4(color, blended ? clamp(s.alpha, 0.0, 1.0) : 1.0);
}
