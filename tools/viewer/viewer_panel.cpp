// The viewer's ImGui window: see viewer_panel.h.
#include "viewer_panel.h"

#include <cstdio>

#include <imgui.h>

namespace rbViewer {

namespace {

double mib(VkDeviceSize bytes) { return double(bytes) / (1024.0 * 1024.0); }

// One row of the GPU table: name, ms, and rays/s where the pass traces.
// The frame budget (HybridEffectsDesc::budgetMs): a slider (0 = off) and how the SDK divides it (FrameBudgetStats).
void budgetControls(const PanelModel& m, PanelRequests& r) {
  if (!ImGui::CollapsingHeader("Frame budget", ImGuiTreeNodeFlags_DefaultOpen)) return;
  float ms = m.budgetMs;
  if (ImGui::SliderFloat("budget ms (0 = off)", &ms, 0.0f, 16.0f, "%.1f") && ms != m.budgetMs) r.budgetMs = ms;
  const rb::FrameBudgetStats& b = m.effectStats.budget;
  if (b.budgetMs <= 0.0f) return;
  ImGui::Text("record() %.2f ms of %.1f; fixed %.2f, floor %.2f%s", m.effectStats.hook.gpuMs, b.budgetMs, b.fixedMs,
              b.floorMs, b.belowFloor ? "  (under the floor: everything at its cheapest)" : "");
  ImGui::Text("given: shadows %.2f  AO %.2f  reflections %.2f (level %u)  local lights %.2f (rays / %u)", b.shadowsMs,
              b.aoMs, b.reflectionsMs, b.reflectionLevel, b.localLightsMs, 1u << b.localLightLevel);
}

void passRow(const char* name, double ms, const rb::PassStats* rays = nullptr) {
  ImGui::TableNextRow();
  ImGui::TableNextColumn();
  ImGui::TextUnformatted(name);
  ImGui::TableNextColumn();
  ImGui::Text("%6.2f", ms);
  ImGui::TableNextColumn();
  // Grays/s on GPUs, Mrays/s on software rasterisers (lavapipe), so the value never reads as 0.000.
  const double perSecond = rays ? rays->raysPerSecond() : 0.0;
  if (perSecond >= 1e8) ImGui::Text("%7.2f G", perSecond * 1e-9);
  else if (perSecond > 0.0)
    ImGui::Text("%7.2f M", perSecond * 1e-6);
  else
    ImGui::TextDisabled("-");
}

void effectToggle(const char* label, rb::EffectBits bit, const PanelModel& m, PanelRequests& r) {
  bool on = (m.effects & bit) != 0;
  if (ImGui::Checkbox(label, &on)) r.toggleEffects |= bit;
}

// Which effect (among those enabled) to show, and how; the lit frame by default.
void inspectControls(const PanelModel& m, PanelRequests& r) {
  // Wide enough for the longest name and the arrow.
  auto comboWidth = [](const char* longest) {
    return ImGui::CalcTextSize(longest).x + ImGui::GetFrameHeight() + 2 * ImGui::GetStyle().FramePadding.x;
  };
  ImGui::TextUnformatted("inspect");
  ImGui::SameLine();
  ImGui::SetNextItemWidth(comboWidth("reflections"));
  if (ImGui::BeginCombo("##inspect effect", toString(m.inspect.effect))) {
    for (uint32_t i = 0; i < kInspectEffectCount; ++i) {
      const InspectEffect e = InspectEffect(i);
      if (!(m.effects & effectBit(e))) continue;
      if (ImGui::Selectable(toString(e), e == m.inspect.effect)) r.inspect = Inspect{e, m.inspect.view};
    }
    ImGui::EndCombo();
  }
  ImGui::SameLine();
  ImGui::SetNextItemWidth(comboWidth("history length"));
  if (ImGui::BeginCombo("##inspect view", label(m.inspect.view))) {
    for (uint32_t i = 0; i < kInspectViewCount; ++i) {
      const InspectView v = InspectView(i);
      if (ImGui::Selectable(label(v), v == m.inspect.view)) r.inspect = Inspect{m.inspect.effect, v};
    }
    ImGui::EndCombo();
  }
  if (!m.inspectNote.empty()) {
    ImGui::SameLine();
    ImGui::TextDisabled("%s", m.inspectNote.c_str());
  }
}

}  // namespace

PanelRequests drawPanel(const PanelModel& m) {
  PanelRequests r;
  ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowBgAlpha(0.85f);
  if (!ImGui::Begin("Raybridge (F1 hides)", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
    ImGui::End();
    return r;
  }
  ImGui::Text("%s   %.1f ms/frame", m.device.c_str(), m.frameMs);

  // --- What runs ---
  int mode = m.hybrid ? 1 : 0;
  ImGui::TextUnformatted("mode (M)");
  ImGui::SameLine();
  if (ImGui::RadioButton("hybrid (Raybridge)", &mode, 1) && !m.hybrid) r.hybrid = true;
  ImGui::SameLine();
  if (ImGui::RadioButton("raster (engine)", &mode, 0) && m.hybrid) r.hybrid = false;
  if (ImGui::BeginCombo("preset (P)", rb::toString(m.preset))) {
    for (uint32_t i = 0; i < rb::kPresetCount; ++i) {
      const rb::Preset p = rb::Preset(i);
      if (ImGui::Selectable(rb::toString(p), p == m.preset)) r.preset = p;
    }
    ImGui::EndCombo();
  }
  effectToggle("shadows", rb::kEffectShadows, m, r);
  ImGui::SameLine();
  effectToggle("AO (O)", rb::kEffectAo, m, r);
  ImGui::SameLine();
  effectToggle("reflections (R)", rb::kEffectReflections, m, r);
  ImGui::SameLine();
  effectToggle("lights (L)", rb::kEffectLocalLights, m, r);
  bool soft = m.shadowRays > 1;
  if (ImGui::Checkbox("soft shadows (H)", &soft)) r.toggleSoftShadows = true;
  ImGui::SameLine();
  bool denoise = m.denoise;
  if (ImGui::Checkbox("denoise (N)", &denoise)) r.toggleDenoise = true;
  ImGui::Text("rays/pixel: shadows %u, AO %u   sun az %.0f el %.0f deg%s", m.shadowRays, m.aoRays, m.sunAzimuthDegrees,
              m.sunElevationDegrees, m.paused ? "   (paused)" : "");
  inspectControls(m, r);

  // --- GPU time ---
  if (ImGui::CollapsingHeader("GPU passes", ImGuiTreeNodeFlags_DefaultOpen)) {
    if (!m.engine.valid) ImGui::TextDisabled("no timestamps yet");
    if (ImGui::BeginTable("passes", 3, ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingFixedFit)) {
      ImGui::TableSetupColumn("pass");
      ImGui::TableSetupColumn("ms");
      ImGui::TableSetupColumn("rays/s");
      ImGui::TableHeadersRow();
      const sample_engine::PassTimings& t = m.engine;
      if (t.deformMs > 0.0) passRow("deform (engine)", t.deformMs);
      passRow("shadow map (engine)", t.shadowMs);
      if (t.probeCaptured) passRow("probe capture (engine)", t.probeMs);
      passRow("pre-pass (engine)", t.prepassMs);
      passRow("SSAO (engine)", t.ssaoMs);
      passRow("Raybridge hook", t.hookMs);
      const rb::HybridStats& s = m.effectStats;
      passRow("  shadows", s.shadow.gpuMs, &s.shadow);
      passRow("  shadow denoise", s.shadowDenoise.gpuMs);
      passRow("  AO", s.ao.gpuMs, &s.ao);
      passRow("  AO denoise", s.aoDenoise.gpuMs);
      passRow("  reflections", s.reflection.gpuMs, &s.reflection);
      passRow("  local lights", s.localLights.gpuMs, &s.localLights);
      passRow("  local lights denoise", s.localLightsDenoise.gpuMs);
      passRow("lighting (engine)", t.lightingMs);
      passRow("tonemap (engine)", t.tonemapMs);
      ImGui::EndTable();
    }
  }

  budgetControls(m, r);

  // --- Acceleration structures ---
  if (ImGui::CollapsingHeader("Acceleration structures", ImGuiTreeNodeFlags_DefaultOpen)) {
    const rb::AsStats& a = m.as;
    ImGui::Text("BLAS %u (%u queued, %u compacted), mesh handles %u, dedup hits %u", a.blasCount, a.blasQueued,
                a.blasCompacted, a.meshHandles, a.dedupHits);
    ImGui::Text("triangles %llu, %.1f B/triangle, TLAS instances %u", static_cast<unsigned long long>(a.triangles),
                a.bytesPerTriangle, a.lastTlasInstances);
    ImGui::Text("dynamic: %llu refits, %llu rebuilds (last frame %llu / %llu triangles)%s",
                static_cast<unsigned long long>(a.refits), static_cast<unsigned long long>(a.rebuilds),
                static_cast<unsigned long long>(a.lastFrameRefitTriangles),
                static_cast<unsigned long long>(a.lastFrameRebuildTriangles), a.async ? ", async queue" : "");
    if (!a.batches.empty()) {
      const rb::BuildBatchTiming& b = a.batches.back();
      ImGui::Text("last build batch: %u builds, %llu triangles, %.2f ms", b.blasBuilds,
                  static_cast<unsigned long long>(b.triangles), b.gpuMs);
    }
    if (a.staleBlas) ImGui::Text("stale BLAS in the last TLAS: %u", a.staleBlas);
  }

  // --- Memory ---
  if (ImGui::CollapsingHeader("Memory (Raybridge)", ImGuiTreeNodeFlags_DefaultOpen)) {
    if (ImGui::BeginTable("memory", 2, ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingFixedFit)) {
      for (uint32_t c = 0; c < uint32_t(rb::MemoryCategory::Count); ++c) {
        ImGui::TableNextRow();
        ImGui::TableNextColumn();
        ImGui::TextUnformatted(rb::toString(rb::MemoryCategory(c)));
        ImGui::TableNextColumn();
        ImGui::Text("%8.2f MiB", mib(m.memory.of(rb::MemoryCategory(c))));
      }
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::Text("total (%u allocations)", m.memory.allocations);
      ImGui::TableNextColumn();
      ImGui::Text("%8.2f MiB", mib(m.memory.total()));
      ImGui::EndTable();
    }
  }
  ImGui::End();
  return r;
}

}  // namespace rbViewer
