// The KHR lights (Scene::lights): the per-frame light buffer, the local shadow maps and the irradiance they
// give, shared by the lighting pass and the local-irradiance output pass so that the image an application
// reads back is exactly the E the lighting uses. Needs frame_uniforms.glsl; the includer defines
// LOCAL_LIGHT_SET and LOCAL_LIGHT_BINDING: three consecutive bindings (shadow maps, lights, shadow views).
// Keep in sync with GpuLocalLight / GpuLocalShadows in src/local_lights.h.
// Positions are camera-relative like every other position of the frame.

#define SE_LIGHT_DIRECTIONAL 0u
#define SE_LIGHT_POINT 1u
#define SE_LIGHT_SPOT 2u
#define SE_MAX_SHADOWED_LOCAL_LIGHTS 8
#define SE_MAX_LOCAL_SHADOW_VIEWS 48

struct LocalLight {
  vec4 positionRange;  // xyz: position - eye, w: range (0 = unlimited)
  vec4 directionType;  // xyz: the way the light travels (normalized), w: SE_LIGHT_*
  vec4 radiance;       // rgb: color * intensity
  vec4 cone;           // x: cos(outer), y: 1 / (cos(inner) - cos(outer)), z: shadow slot (-1 = none)
};

// Every shadow view is one layer (a spot or directional light: one, a point light: six, +X -X +Y -Y +Z -Z).
layout(set = LOCAL_LIGHT_SET, binding = LOCAL_LIGHT_BINDING) uniform sampler2DArrayShadow localShadowMaps;
layout(std430, set = LOCAL_LIGHT_SET, binding = LOCAL_LIGHT_BINDING + 1) readonly buffer LocalLights {
  LocalLight localLights[];
};
layout(std140, set = LOCAL_LIGHT_SET, binding = LOCAL_LIGHT_BINDING + 2) uniform LocalShadows {
  uvec4 localShadowCounts;  // x: PCF taps per axis (0 = no local shadow maps this frame)
  vec4 localShadowParams;   // x: 1 / map size, y: normal offset (texels, kernel reach included)
  // Per slot: x first view (layer), y view count (1 or 6), z texel footprint (orthographic: world units;
  // perspective: world units per unit of distance along the view axis), w: 1 = orthographic.
  vec4 localShadowSlots[SE_MAX_SHADOWED_LOCAL_LIGHTS];
  mat4 localShadowViewProj[SE_MAX_LOCAL_SHADOW_VIEWS];  // camera-relative position -> the view's clip space
};

uint localLightCount() { return frame.localLights.x; }

// Light i at camera-relative p: `l` = unit vector towards the light, returns the unshadowed irradiance on a
// surface facing it (no cosine): glTF's I / d^2 * range window * spot falloff for point and spot lights, the
// illuminance for directional ones.
vec3 localLightIncidence(uint i, vec3 p, out vec3 l) {
  LocalLight light = localLights[i];
  uint type = uint(light.directionType.w + 0.5);
  if (type == SE_LIGHT_DIRECTIONAL) {
    l = -light.directionType.xyz;
    return light.radiance.rgb;
  }
  vec3 toLight = light.positionRange.xyz - p;
  float d2 = max(dot(toLight, toLight), 1e-12);
  float d = sqrt(d2);
  l = toLight / d;
  float attenuation = 1.0 / d2;
  float range = light.positionRange.w;
  if (range > 0.0) {  // the spec's recommended window, without changing the 1 / d^2 falloff inside it
    float r = d / range;
    attenuation *= clamp(1.0 - (r * r) * (r * r), 0.0, 1.0);
  }
  if (type == SE_LIGHT_SPOT) {
    float t = clamp((dot(light.directionType.xyz, -l) - light.cone.x) * light.cone.y, 0.0, 1.0);
    attenuation *= t * t;
  }
  return light.radiance.rgb * attenuation;
}

// Shadow-map visibility of light i at p (1 = lit): 1 for lights without a map this frame. ng: geometric normal
// (the lookup is offset along it, like the sun's). PCF as the sun's: taps x taps 2x2-filtered compares.
float localLightShadow(uint i, vec3 p, vec3 ng) {
  int slot = int(localLights[i].cone.z);
  int taps = int(localShadowCounts.x);
  if (slot < 0 || taps <= 0) return 1.0;
  vec4 info = localShadowSlots[slot];
  int view = int(info.x);
  float footprint = info.z;
  if (info.w < 0.5) {
    vec3 v = p - localLights[i].positionRange.xyz;
    vec3 a = abs(v);
    float axis;
    if (info.y > 1.5) {  // six faces: the one whose axis dominates
      int face = a.x >= a.y && a.x >= a.z ? (v.x > 0.0 ? 0 : 1) : a.y >= a.z ? (v.y > 0.0 ? 2 : 3) : (v.z > 0.0 ? 4 : 5);
      view += face;
      axis = max(a.x, max(a.y, a.z));
    } else {
      axis = dot(v, localLights[i].directionType.xyz);
    }
    footprint *= max(axis, 0.0);
  }
  vec4 lp = localShadowViewProj[view] * vec4(p + ng * (localShadowParams.y * footprint), 1.0);
  if (lp.w <= 0.0) return 1.0;
  vec3 ndc = lp.xyz / lp.w;
  vec2 uv = ndc.xy * 0.5 + 0.5;
  if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0))) || ndc.z >= 1.0 || ndc.z < 0.0) return 1.0;
  float first = -0.5 * float(taps - 1);
  float sum = 0.0;
  for (int y = 0; y < taps; ++y)
    for (int x = 0; x < taps; ++x)
      sum += texture(localShadowMaps, vec4(uv + (vec2(x, y) + first) * localShadowParams.x, float(view), ndc.z));
  return sum / float(taps * taps);
}

// Shadowed diffuse irradiance E from every light at p for shading normal n (what the local-irradiance output
// writes, and what LightingInputs::localLightIrradiance replaces).
vec3 localLightIrradiance(vec3 p, vec3 n, vec3 ng) {
  vec3 e = vec3(0.0);
  for (uint i = 0u; i < localLightCount(); ++i) {
    vec3 l;
    vec3 incident = localLightIncidence(i, p, l);
    float nDotL = dot(n, l);
    if (nDotL <= 0.0 || all(equal(incident, vec3(0.0)))) continue;
    e += incident * nDotL * localLightShadow(i, p, ng);
  }
  return e;
}
