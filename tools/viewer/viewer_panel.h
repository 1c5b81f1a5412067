// The viewer's ImGui window: mode, preset, effect and denoise toggles, the inspect view (viewer_inspect.h), per-pass
// GPU times and rays/s, the acceleration structures' statistics and the SDK's memory by category. It only shows what it
// is given and returns what the user asked for; the viewer applies those requests exactly as it applies its keys.
#pragma once

#include <optional>
#include <string>

#include <raybridge/raybridge.h>

#include "sample_engine/engine.h"
#include "viewer_inspect.h"

namespace rbViewer {

// What the panel shows, filled by the viewer every frame.
struct PanelModel {
  std::string device;
  bool hybrid = true;                    // Raybridge's effects (true) or the engine's raster counterparts
  rb::Preset preset = rb::Preset::None;  // the preset applied last (the effects may have been changed since)
  rb::EffectSet effects = 0;             // what runs now
  bool denoise = true;
  uint32_t shadowRays = 0, aoRays = 0;  // effective rays per pixel (1 shadow ray = hard shadows)
  bool paused = false;                  // animation clock
  Inspect inspect;                      // what the window shows behind the panel
  std::string inspectNote;              // why that is not quite what was asked for ("" = it is)
  float sunAzimuthDegrees = 0.0f, sunElevationDegrees = 0.0f;
  double frameMs = 0.0;               // CPU time between frames, smoothed
  sample_engine::PassTimings engine;  // the engine's passes (hookMs holds everything Raybridge recorded)
  rb::HybridStats effectStats;        // Raybridge's passes, and the frame budget's split (effectStats.budget)
  float budgetMs = 0.0f;              // HybridEffectsDesc::budgetMs now (0 = off)
  rb::AsStats as;
  rb::MemoryStats memory;  // the rb::Context's, every category
};

// What the user changed this frame (nothing by default).
struct PanelRequests {
  std::optional<bool> hybrid;
  std::optional<rb::Preset> preset;
  rb::EffectSet toggleEffects = 0;  // effects to switch on or off
  bool toggleDenoise = false;
  bool toggleSoftShadows = false;
  std::optional<Inspect> inspect;
  std::optional<float> budgetMs;  // HybridEffectsDesc::budgetMs (0 = off)
};

// Draws the window (between ImGuiOverlay::beginFrame and endFrame).
PanelRequests drawPanel(const PanelModel& model);

}  // namespace rbViewer
