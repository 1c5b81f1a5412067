// raybridge-viewer: the sample engine in a GLFW window with the Raybridge adapter, toggling at run time between
// the engine's own terms (shadow map, SSAO, reflection probe) and Raybridge's ray-traced shadows, AO and
// reflections, and between presets. Combines exactly one platform side (the engine's GLFW Window)
// with the adapter.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <GLFW/glfw3.h>

#include "raybridge_sample_engine_adapter.h"
#include "sample_engine/gltf_loader.h"
#include "sample_engine/procedural.h"
#include "sample_engine/window.h"

namespace se = sample_engine;

namespace {

struct Options {
  std::string scene;
  int width = 1280, height = 720;
  int frames = 0;  // 0 = until closed
  std::string screenshot;
  rbAdapter::Preset preset = rbAdapter::Preset::High;
  bool validation = false;
};

const char* kUsage =
    "usage: raybridge-viewer [--scene FILE.gltf] [--width W] [--height H] [--frames N] [--screenshot FILE.png]\n"
    "                        [--preset low|medium|high|ultra|shadows|ao|reflections] [--validation]\n";

const char* kKeys =
    "keys: drag = orbit, scroll = zoom, W/A/S/D/Q/E = move (Shift = faster)\n"
    "      M = mode raster (shadow map, SSAO, probe) <-> hybrid (Raybridge), P = next preset,\n"
    "      H = shadows hard <-> soft, O = ambient occlusion on/off, R = reflections on/off, N = denoise on/off,\n"
    "      Left/Right = sun azimuth, Up/Down = sun elevation, Space = pause/resume the animation, Esc = quit\n";

int fail(const std::string& message) {
  std::fprintf(stderr, "raybridge-viewer: error: %s\n", message.c_str());
  return 1;
}

bool parse(int argc, char** argv, Options& o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool hasValue = i + 1 < argc;
    if (a == "--validation") o.validation = true;
    else if (a == "--scene" && hasValue) o.scene = argv[++i];
    else if (a == "--screenshot" && hasValue) o.screenshot = argv[++i];
    else if (a == "--width" && hasValue) o.width = std::atoi(argv[++i]);
    else if (a == "--height" && hasValue) o.height = std::atoi(argv[++i]);
    else if (a == "--frames" && hasValue) o.frames = std::atoi(argv[++i]);
    else if (a == "--preset" && hasValue) {
      auto p = rbAdapter::parsePreset(argv[++i]);
      if (!p) {
        std::fprintf(stderr, "raybridge-viewer: error: --preset: '%s' is not a preset\n%s", argv[i], kUsage);
        return false;
      }
      o.preset = *p;
    } else {
      std::fprintf(stderr, "raybridge-viewer: error: unknown option or missing value '%s'\n%s", a.c_str(), kUsage);
      return false;
    }
  }
  if (o.width <= 0 || o.height <= 0 || o.width > 16384 || o.height > 16384 || o.frames < 0) {
    std::fprintf(stderr, "raybridge-viewer: error: invalid size or frame count\n%s", kUsage);
    return false;
  }
  return true;
}

// Orbit camera around a target, as in the engine demo.
struct Orbit {
  glm::vec3 target;
  float yaw, pitch, distance;
  static Orbit from(const se::Camera& c) {
    glm::vec3 d = c.eye - c.target;
    float dist = std::max(glm::length(d), 1e-3f);
    return {c.target, std::atan2(d.x, d.z), std::asin(std::clamp(d.y / dist, -1.0f, 1.0f)), dist};
  }
  void apply(se::Camera& c) const {
    c.target = target;
    c.eye = target + glm::vec3(std::cos(pitch) * std::sin(yaw), std::sin(pitch), std::cos(pitch) * std::cos(yaw)) * distance;
  }
};

// Edge-triggered key presses, polled (the engine's Window owns the GLFW callbacks).
struct Keys {
  GLFWwindow* window;
  bool previous[GLFW_KEY_LAST + 1] = {};
  bool pressed(int key) {
    const bool down = glfwGetKey(window, key) == GLFW_PRESS;
    const bool edge = down && !previous[key];
    previous[key] = down;
    return edge;
  }
  bool down(int key) const { return glfwGetKey(window, key) == GLFW_PRESS; }
};

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!parse(argc, argv, o)) return 2;
  if (const char* v = std::getenv("RAYBRIDGE_VALIDATION"); v && std::string(v) == "1") o.validation = true;

  se::Scene scene = se::makeDefaultDemoScene();
  if (!o.scene.empty()) {
    se::SceneLoadResult r = se::loadGltf(o.scene);
    if (!r.ok()) return fail("--scene: cannot load glTF '" + o.scene + "': " + r.error);
    scene = std::move(r.scene);
  }
  auto win = se::Window::create("Raybridge viewer", o.width, o.height);
  if (!win) return fail(win.error);
  se::Window& window = *win.value;

  rb::RequiredFeatures features;
  se::EngineConfig config;
  config.enableValidation = o.validation;
  config.enableSwapchain = true;
  config.instanceExtensions = window.requiredInstanceExtensions();
  rbAdapter::configureEngine(config, features);
  auto created = se::Engine::create(config);
  if (!created) return fail("engine: " + created.error);
  se::Engine& engine = *created.value;
  if (se::Status s = engine.loadScene(scene); !s) return fail(s.error);
  auto surface = window.createSurface(engine.instance());
  if (!surface) return fail(surface.error);
  int fbw = 0, fbh = 0;
  window.framebufferSize(fbw, fbh);
  if (se::Status s = engine.attachSurface(surface.value, uint32_t(fbw), uint32_t(fbh)); !s) return fail(s.error);

  auto adapter = rbAdapter::Adapter::create(engine, {});
  if (!adapter) return fail("adapter: " + adapter.error);
  rbAdapter::FrameSettings& rt = adapter.value->settings();
  rbAdapter::Preset preset = o.preset;
  if (se::Status s = adapter.value->applyPreset(preset); !s) return fail("adapter: " + s.error);
  engine.setPrepassHook(adapter.value->prepassHook());

  se::FrameParams params;
  params.camera = engine.scene().camera ? *engine.scene().camera : se::defaultCameraFor(engine.sceneBounds());
  if (engine.scene().sun) params.sun = *engine.scene().sun;
  float sunAzimuth = std::atan2(params.sun.direction.x, params.sun.direction.z);
  float sunElevation = std::asin(std::clamp(glm::normalize(params.sun.direction).y, -1.0f, 1.0f));

  std::printf("device: %s\n%s", engine.deviceInfo().name.c_str(), kKeys);
  Orbit orbit = Orbit::from(params.camera);
  Keys keys{static_cast<GLFWwindow*>(window.glfwHandle())};
  const float sceneSize = std::max(engine.sceneBounds().radius(), 1.0f);
  double lastX = 0, lastY = 0;
  window.cursorPosition(lastX, lastY);
  auto last = std::chrono::steady_clock::now();
  int frames = 0;
  bool paused = false;  // the animation clock (real time) stops while paused
  auto printState = [&] {
    const rbAdapter::EffectSet fx = adapter.value->effects();
    std::printf("mode %s, preset %s, effects [%s], shadows %s (%u rays), AO %u rays, denoise %s, sun azimuth %.0f "
                "elevation %.0f deg\n",
                rt.enabled ? "hybrid" : "raster", rbAdapter::toString(preset),
                rbAdapter::effectsToString(fx).c_str(), rt.sunAngularRadiusDegrees > 0.0f ? "soft" : "hard",
                rt.sunAngularRadiusDegrees > 0.0f ? rt.shadowRaysPerPixel : 1u, rt.aoRaysPerPixel,
                rt.denoise ? "on" : "off", glm::degrees(sunAzimuth), glm::degrees(sunElevation));
  };
  auto toggle = [&](rbAdapter::Effect effect) {
    if (se::Status s = adapter.value->setEffects(adapter.value->effects() ^ effect); !s)
      std::fprintf(stderr, "raybridge-viewer: %s\n", s.error.c_str());
    printState();
  };
  printState();
  while (!window.shouldClose()) {
    window.pollEvents();
    if (window.keyDown(se::Window::Key::Escape)) window.requestClose();
    const auto now = std::chrono::steady_clock::now();
    const float dt = std::min(std::chrono::duration<float>(now - last).count(), 0.1f);
    last = now;

    if (keys.pressed(GLFW_KEY_SPACE)) paused = !paused, std::printf("animation %s at %.2f s\n", paused ? "paused" : "playing", params.time);
    if (!paused) params.time += dt;
    if (keys.pressed(GLFW_KEY_M)) rt.enabled = !rt.enabled, printState();
    if (keys.pressed(GLFW_KEY_H)) {
      rt.sunAngularRadiusDegrees = rt.sunAngularRadiusDegrees > 0.0f ? 0.0f : rbAdapter::kDefaultSoftSunRadiusDegrees;
      if (rt.shadowRaysPerPixel < 2) rt.shadowRaysPerPixel = 4;
      printState();
    }
    if (keys.pressed(GLFW_KEY_O)) toggle(rbAdapter::kEffectAo);
    if (keys.pressed(GLFW_KEY_R)) toggle(rbAdapter::kEffectReflections);
    if (keys.pressed(GLFW_KEY_N)) rt.denoise = !rt.denoise, printState();
    if (keys.pressed(GLFW_KEY_P)) {
      preset = rbAdapter::Preset((int(preset) + 1) % (int(rbAdapter::Preset::ReflectionsOnly) + 1));
      if (se::Status s = adapter.value->applyPreset(preset); !s) return fail("adapter: " + s.error);
      printState();
    }
    const float sunSpeed = 0.8f * dt;
    if (keys.down(GLFW_KEY_LEFT)) sunAzimuth -= sunSpeed;
    if (keys.down(GLFW_KEY_RIGHT)) sunAzimuth += sunSpeed;
    if (keys.down(GLFW_KEY_UP)) sunElevation = std::min(sunElevation + sunSpeed, glm::radians(89.0f));
    if (keys.down(GLFW_KEY_DOWN)) sunElevation = std::max(sunElevation - sunSpeed, glm::radians(3.0f));
    params.sun.direction = {std::cos(sunElevation) * std::sin(sunAzimuth), std::sin(sunElevation),
                            std::cos(sunElevation) * std::cos(sunAzimuth)};
    rt.lightingFrom(params);
    // Raster mode: the engine's own counterparts of the enabled effects (its shadow map is always on).
    params.ssao.enabled = !rt.enabled && (adapter.value->effects() & rbAdapter::kEffectAo);
    params.reflectionProbe.enabled = !rt.enabled && (adapter.value->effects() & rbAdapter::kEffectReflections);

    double x, y;
    window.cursorPosition(x, y);
    if (window.mouseButtonDown(0)) {
      orbit.yaw -= float(x - lastX) * 0.005f;
      orbit.pitch = std::clamp(orbit.pitch + float(y - lastY) * 0.005f, -1.5f, 1.5f);
    }
    lastX = x;
    lastY = y;
    orbit.distance = std::max(orbit.distance * std::pow(0.9f, float(window.takeScrollDelta())), 0.05f);
    const float speed = sceneSize * 0.5f * dt * (window.keyDown(se::Window::Key::LeftShift) ? 4.0f : 1.0f);
    const glm::vec3 forward(-std::sin(orbit.yaw), 0.0f, -std::cos(orbit.yaw)), right(-forward.z, 0.0f, forward.x);
    if (window.keyDown(se::Window::Key::W)) orbit.target += forward * speed;
    if (window.keyDown(se::Window::Key::S)) orbit.target -= forward * speed;
    if (window.keyDown(se::Window::Key::D)) orbit.target += right * speed;
    if (window.keyDown(se::Window::Key::A)) orbit.target -= right * speed;
    if (window.keyDown(se::Window::Key::E)) orbit.target.y += speed;
    if (window.keyDown(se::Window::Key::Q)) orbit.target.y -= speed;
    orbit.apply(params.camera);

    int w = 0, h = 0;
    window.framebufferSize(w, h);
    if (w == 0 || h == 0) continue;  // minimised
    const VkExtent2D size = engine.renderSize();
    if (uint32_t(w) != size.width || uint32_t(h) != size.height) (void)engine.resizeSwapchain(uint32_t(w), uint32_t(h));
    if (se::Status s = engine.renderFrame(params); !s) return fail(s.error);
    if (!adapter.value->lastError().empty()) return fail("Raybridge: " + adapter.value->lastError());
    if (++frames % 60 == 0) {
      const se::PassTimings t = engine.lastTimings();
      const rbAdapter::EffectStats es = adapter.value->stats();
      std::printf("GPU ms: shadow map %.1f probe %.1f prepass %.1f ssao %.1f hook (Raybridge) %.1f [shadows %.1f+%.1f, "
                  "AO %.1f+%.1f, reflections %.1f] lighting %.1f tonemap %.1f\n",
                  t.shadowMs, t.probeMs, t.prepassMs, t.ssaoMs, t.hookMs, es.shadow.gpuMs, es.shadowDenoise.gpuMs,
                  es.ao.gpuMs, es.aoDenoise.gpuMs, es.reflection.gpuMs, t.lightingMs, t.tonemapMs);
    }
    if (o.frames > 0 && frames >= o.frames) window.requestClose();
  }
  if (se::Status s = engine.waitIdle(); !s) return fail(s.error);
  if (!o.screenshot.empty()) {
    auto ldr = engine.readbackLdr();
    if (!ldr) return fail(ldr.error);
    if (se::Status s = se::writePng(o.screenshot, ldr.value); !s) return fail(s.error);
    std::printf("wrote %s\n", o.screenshot.c_str());
  }
  std::printf("rendered %d frames\n", frames);
  engine.setPrepassHook({});
  adapter.value.reset();
  if (o.validation) {
    std::printf("validation errors: %u\n", engine.validationErrorCount());
    if (engine.validationErrorCount() > 0) return 3;
  }
  return 0;
}
