// Per-frame uniforms, set 0 of every pass (scene passes and fullscreen passes). Keep in sync with
// FrameUniforms in src/pipelines.h.
// Positions are camera-relative (world position - eye, world axes; the probe capture: - probe position).
layout(set = 0, binding = 0) uniform FrameUniforms {
  mat4 view;           // rotation only
  mat4 proj;
  mat4 viewProj;       // camera-relative position -> clip
  mat4 invViewProj;    // clip -> camera-relative position
  mat4 lightViewProj;  // camera-relative position -> the shadow map's clip space
  vec4 cameraPos;     // xyz: the world-space eye (float); no pass needs it
  vec4 sunDirection;  // xyz: towards the sun, normalized
  vec4 sunRadiance;   // rgb: color * intensity
  vec4 sky;           // rgb: sky radiance (background), w: ambient intensity
  vec4 viewport;      // width, height, 1/width, 1/height
  vec4 shadow;        // x: 1/map size, y: PCF taps per axis (0 = no shadow map), z: normal offset (world)
  uvec4 inputs;       // x: sun visibility image, y: AO image (external or SSAO), z: external reflection (1 = bound)
  mat4 invProj;
  vec4 probe;         // x: 1 = sample the reflection probe, y: its last mip level
  // x: KHR lights in the light buffer (0 = none: LocalLightSettings::enabled off, the probe capture),
  // y: 1 = LightingInputs::localLightIrradiance bound
  uvec4 localLights;
  // Last frame's camera-relative position -> clip, rebased to this frame's eye (its projection * rotation *
  // translation by eye - previous eye): with last frame's vertex positions and model matrices, where a surface
  // point was on screen (the pre-pass's motion vectors). The probe capture: its viewProj.
  mat4 previousViewProj;
} frame;
