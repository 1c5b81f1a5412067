# The SDK's shader variants: modules compiled from one body with a set of defines, declared here instead of as a
# stub file each (the VARIANTS of raybridge_embed_shaders, cmake/EmbedShaders.cmake; included by sdk/CMakeLists.txt).
# One row per module:
#   <module name>  <body, in shaders/>  <defines: comma-separated, NAME or NAME=VALUE, passed in this order; - for none>
# The module name's extension is its stage (glslangValidator -S), and the name gives the C++ array and the exported
# file (ao_tiles.rgen -> rb::spirv::ao_tiles_rgen, ao_tiles.rgen.spv). The comment above a row says what the variant
# is for. A body starts with its own #version and #extension lines.
set(raybridge_shader_variants
  # module                             body                        defines

  # Ambient occlusion with pc.raysPerPixel rays in every surface pixel.
  ao.rgen                              ao_raygen.glsl              -
  # Ambient occlusion with each pixel's rays from the adaptive plan (sdk/src/schedule/adaptive_rays.h).
  ao_adaptive.rgen                     ao_raygen.glsl              RB_ADAPTIVE_RAYS
  # Ambient occlusion over the tile classifier's list (AoSettings::schedule.convergedTiles).
  ao_tiles.rgen                        ao_raygen.glsl              RB_AO_TILE_LIST
  # Ambient occlusion over the tile classifier's list with each pixel's rays from the adaptive plan
  # (AoSettings::schedule.convergedTiles and AoSettings::schedule.adaptive).
  ao_adaptive_tiles.rgen               ao_raygen.glsl              RB_ADAPTIVE_RAYS,RB_AO_TILE_LIST

  # Shadow rays towards the light.
  shadow.rgen                          shadow_raygen.glsl          -
  # The same, plus the occluder-distance image (ShadowPassDesc::outputHitDistance).
  shadow_distance.rgen                 shadow_raygen.glsl          RB_WRITE_HIT_DISTANCE=1
  # Soft shadows with each pixel's rays from the adaptive plan (sdk/src/schedule/adaptive_rays.h).
  shadow_adaptive.rgen                 shadow_raygen.glsl          RB_ADAPTIVE_RAYS
  # The shadow pass's tile classifier, without and with the occluder-distance image.
  shadow_classify.comp                 shadow_classify.glsl        -
  shadow_classify_distance.comp        shadow_classify.glsl        RB_WRITE_HIT_DISTANCE=1

  # The reflection pass's ray generation: rays traced and shaded in place.
  reflect.rgen                         reflection_raygen.glsl      -
  # Reflections that skip the converged tiles (ReflectionSettings::schedule.convergedTiles).
  reflect_converged.rgen               reflection_raygen.glsl      RB_REFLECTION_CONVERGED_TILES
  # The reflection pass's ray generation with shader execution reordering (VK_NV_ray_tracing_invocation_reorder):
  # the same rays as reflect.rgen, the hits regrouped by instance before shading. Built into a pipeline only on a
  # Context with DeviceInfo::invocationReorder.
  reflect_reorder.rgen                 reflection_raygen.glsl      RB_REFLECTION_REORDER=1
  # Reflections that skip the converged tiles (ReflectionSettings::schedule.convergedTiles), with shader execution
  # reordering (reflect_reorder.rgen).
  reflect_reorder_converged.rgen       reflection_raygen.glsl      RB_REFLECTION_REORDER=1,RB_REFLECTION_CONVERGED_TILES

  # ManyLightPass, step 2: the shadowed irradiance of every pixel.
  many_lights.rgen                     many_lights_raygen.glsl     -
  # ManyLightPass, step 2, skipping the converged tiles (ManyLightSettings::schedule.convergedTiles).
  many_lights_converged.rgen           many_lights_raygen.glsl     RB_ML_CONVERGED_TILES

  # An a-trous step of the scalar denoiser that another step follows.
  denoise_atrous.comp                  denoise_atrous.glsl         -
  # The last a-trous step of the scalar denoiser: writes its output.
  denoise_atrous_final.comp            denoise_atrous.glsl         RB_DN_ATROUS_FINAL

  # The depth-aware upsample of half-resolution AO: R16F open fraction.
  upsample_depth_aware_ao.comp         upsample_depth_aware.glsl   -
  # The depth-aware upsample of half-resolution reflections: RGBA16F radiance, a = coverage.
  upsample_depth_aware_reflection.comp upsample_depth_aware.glsl   RB_UPSAMPLE_REFLECTION
)
