// Raybridge: ray-traced effects for rasterizing Vulkan engines. Include this or the individual headers.
// The headless device helper of the samples and tests is not part of it: <raybridge/headless_device.h>, in the
// separate library Raybridge::headless.
#pragma once

#include <raybridge/acceleration_structures.h>
#include <raybridge/ao_pass.h>
#include <raybridge/context.h>
#include <raybridge/denoiser.h>
#include <raybridge/effects.h>
#include <raybridge/gbuffer.h>
#include <raybridge/hybrid_effects.h>
#include <raybridge/light_list.h>
#include <raybridge/many_light_pass.h>
#include <raybridge/material_table.h>
#include <raybridge/presets.h>
#include <raybridge/primary_ray_pass.h>
#include <raybridge/primary_shading_pass.h>
#include <raybridge/ray_schedule.h>
#include <raybridge/reflection_pass.h>
#include <raybridge/result.h>
#include <raybridge/scene_lighting.h>
#include <raybridge/shadow_pass.h>
