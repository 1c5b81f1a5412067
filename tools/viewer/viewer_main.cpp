// raybridge-viewer: the sample engine in a GLFW window with the Raybridge adapter, toggling at run time between
// the engine's own terms (shadow map, SSAO, reflection probe) and Raybridge's ray-traced shadows, AO and
// reflections, and between presets, with a Dear ImGui overlay (viewer_overlay.h, viewer_panel.h) showing the
// controls and the statistics, and any effect shown raw, denoised or as its history length behind it
// (viewer_inspect.h, drawn by viewer_backdrop.h). Combines exactly one platform side (the engine's GLFW Window) with
// the adapter.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include <GLFW/glfw3.h>

#include "cli_support.h"
#include "raybridge_sample_engine_adapter.h"
#include "sample_engine/gltf_loader.h"
#include "sample_engine/procedural.h"
#include "sample_engine/window.h"
#include "viewer_backdrop.h"
#include "viewer_inspect.h"
#include "viewer_overlay.h"
#include "viewer_panel.h"

namespace se = sample_engine;

namespace {

struct Options {
  std::string scene;
  uint32_t width = 1280, height = 720;
  uint32_t frames = 0;  // 0 = until closed
  std::string screenshot;
  rb::Preset preset = rb::Preset::High;
  bool validation = false;
  bool overlay = true;            // the ImGui window is shown at start (F1 toggles it)
  bool screenshotOverlay = true;  // the screenshot shows the overlay when it is shown
  rbViewer::Inspect inspect;      // the view at start (default: the lit frame)
};

const char* kKeys =
    "keys: drag = orbit, scroll = zoom, W/A/S/D/Q/E = move (Shift = faster), F1 = overlay on/off\n"
    "      M = mode raster (shadow map, SSAO, probe) <-> hybrid (Raybridge), P = next preset,\n"
    "      H = shadows hard <-> soft, O = ambient occlusion on/off, R = reflections on/off, L = local lights\n"
    "      (the scene's punctual lights, shadowed by Raybridge) on/off, N = denoise on/off,\n"
    "      Left/Right = sun azimuth, Up/Down = sun elevation, Space = pause/resume the animation, Esc = quit\n";

int fail(const std::string& message) {
  std::fprintf(stderr, "raybridge-viewer: error: %s\n", message.c_str());
  return 1;
}

// Returns 0 to go on, else the exit code (0 after --help is signalled through `exitNow`).
int parse(int argc, char** argv, Options& o, bool& exitNow) {
  exitNow = false;
  CLI::App app{"", "raybridge-viewer"};
  rbCli::prepare(app);
  app.description(
      "The sample engine in a window with Raybridge's effects (default: the procedural demo scene, 1280x720,\n"
      "preset high), with an overlay of controls and statistics.");
  app.footer(kKeys);
  app.add_option("--scene", o.scene, "glTF scene to show (default: the engine's procedural demo scene)")
      ->type_name("FILE.gltf|.glb")
      ->check(rbCli::nonEmpty("file name"));
  app.add_option("--width", o.width, "window width (default 1280)")
      ->type_name("W")
      ->check(rbCli::wholeNumber(1, 16384));
  app.add_option("--height", o.height, "window height (default 720)")
      ->type_name("H")
      ->check(rbCli::wholeNumber(1, 16384));
  app.add_option("--frames", o.frames, "quit after N frames (default 0 = run until the window is closed)")
      ->type_name("N")
      ->check(rbCli::wholeNumber(0, 100000000));
  app.add_option("--screenshot", o.screenshot, "write the last frame to this PNG when quitting")
      ->type_name("FILE.png")
      ->check(rbCli::nonEmpty("file name"));
  app.add_option_function<std::string>(
         "--preset", [&o](const std::string& value) { o.preset = *rb::parsePreset(value); },
         std::string("effects and quality at start (default high): one of\n") + rb::presetNames())
      ->type_name("NAME")
      ->check(CLI::Validator(
          [](std::string& value) {
            return rb::parsePreset(value) ? std::string()
                                          : rbCli::quote(value) + " is not a preset (" + rb::presetNames() + ")";
          },
          ""));
  app.add_option_function<std::string>(
         "--inspect", [&o](const std::string& value) { o.inspect = *rbViewer::parseInspect(value); },
         "start showing one effect instead of the lit frame (the overlay's inspect control):\n"
         "raw (before denoising), denoised, history (the denoiser's history length, black\n"
         "0 frames to white the maximum) or changes (white where a known change restarted the\n"
         "history this frame); e.g. ao:history. Default: lit.\n" +
             rbViewer::inspectNames())
      ->type_name("EFFECT:VIEW")
      ->check(CLI::Validator(
          [](std::string& value) {
            return rbViewer::parseInspect(value)
                       ? std::string()
                       : rbCli::quote(value) + " is not a view (" + rbViewer::inspectNames() + ")";
          },
          ""));
  app.add_flag("--validation", o.validation,
               "enable the Vulkan validation layer; exit code 3 when it reported errors\n"
               "(also RAYBRIDGE_VALIDATION=1)");
  app.add_flag_callback(
      "--no-overlay", [&o] { o.overlay = false; }, "start with the overlay hidden (F1 shows it; default: shown)");
  app.add_flag_callback(
      "--no-screenshot-overlay", [&o] { o.screenshotOverlay = false; },
      "keep the overlay out of --screenshot: one more frame is rendered without it\n"
      "(default: the screenshot shows what the window shows, overlay included)");
  bool help = false;
  if (std::string e = rbCli::parse(app, argc, argv, help); !e.empty()) {
    std::fprintf(stderr, "raybridge-viewer: error: %s\nRun with --help for the options.\n", e.c_str());
    exitNow = true;
    return 2;
  }
  if (help) {
    std::printf("%s", app.help().c_str());
    exitNow = true;
  }
  return 0;
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
    c.eye = target +
            glm::vec3(std::cos(pitch) * std::sin(yaw), std::sin(pitch), std::cos(pitch) * std::cos(yaw)) * distance;
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

std::string effectsToString(rb::EffectSet set) {
  std::string s;
  for (auto [bit, name] :
       {std::pair{rb::kEffectShadows, "shadows"}, std::pair{rb::kEffectAo, "ao"},
        std::pair{rb::kEffectReflections, "reflections"}, std::pair{rb::kEffectLocalLights, "lights"}})
    if (set & bit) s += (s.empty() ? "" : ",") + std::string(name);
  return s.empty() ? "none" : s;
}

// The effect settings the viewer switches, as HybridEffectsDesc spells them.
uint32_t shadowRays(const rb::HybridEffectsDesc& d) { return d.shadows.raysPerPixel ? d.shadows.raysPerPixel : 1u; }
uint32_t aoRays(const rb::HybridEffectsDesc& d) { return d.ao.raysPerPixel ? d.ao.raysPerPixel : rb::kDefaultAoRays; }
bool denoiseOn(const rb::HybridEffectsDesc& d) { return !d.shadows.disableDenoiser || !d.ao.disableDenoiser; }

// The window, the engine presenting to it, the adapter and the overlay, created in that order and destroyed in
// reverse. Once the overlay is attached, whatever way main() ends, the engine stops calling it and is idle before
// the overlay goes.
struct Viewer {
  std::unique_ptr<se::Window> window;
  std::unique_ptr<se::Engine> engine;
  std::unique_ptr<rbAdapter::Adapter> adapter;
  std::unique_ptr<rbViewer::ImGuiOverlay> overlay;
  std::unique_ptr<rbViewer::Backdrop> backdrop;
  rbViewer::Inspect inspect;  // what the backdrop shows, read by the overlay hook
  bool overlayAttached = false;

  Viewer() = default;
  Viewer(const Viewer&) = delete;
  Viewer& operator=(const Viewer&) = delete;
  ~Viewer() {
    if (!overlayAttached) return;
    engine->setOverlayHook({});
    (void)engine->waitIdle();
  }
};

// Builds the viewer on `scene`: Raybridge's effects of the preset, plus the scene's punctual lights shadowed by
// Raybridge on top of any preset (L toggles them). Returns "" or the error.
std::string createViewer(const Options& o, const se::Scene& scene, Viewer& v) {
  auto win = se::Window::create("Raybridge viewer", int(o.width), int(o.height));
  if (!win) return win.error;
  v.window = std::move(win.value);
  se::Window& window = *v.window;

  rb::RequiredFeatures features;
  se::EngineConfig config;
  config.enableValidation = o.validation;
  config.enableSwapchain = true;
  config.instanceExtensions = window.requiredInstanceExtensions();
  rbAdapter::configureEngine(config, features);
  auto created = se::Engine::create(config);
  if (!created) return "engine: " + created.error;
  v.engine = std::move(created.value);
  se::Engine& engine = *v.engine;
  if (se::Status s = engine.loadScene(scene); !s) return s.error;
  auto surface = window.createSurface(engine.instance());
  if (!surface) return surface.error;
  int fbw = 0, fbh = 0;
  window.framebufferSize(fbw, fbh);
  if (se::Status s = engine.attachSurface(surface.value, uint32_t(fbw), uint32_t(fbh)); !s) return s.error;

  rbAdapter::AdapterConfig adapterConfig;
  adapterConfig.preset = o.preset;
  if (!engine.scene().lights.empty()) adapterConfig.effects.effects = rb::kEffectLocalLights;
  auto adapter = rbAdapter::Adapter::create(engine, adapterConfig);
  if (!adapter) return "adapter: " + adapter.error;
  v.adapter = std::move(adapter.value);
  engine.setPrepassHook(v.adapter->prepassHook());

  auto overlay = rbViewer::ImGuiOverlay::create(static_cast<GLFWwindow*>(window.glfwHandle()));
  if (!overlay) return "overlay: " + overlay.error;
  v.overlay = std::move(overlay.value);
  v.backdrop = std::make_unique<rbViewer::Backdrop>();
  v.inspect = o.inspect;
  // The inspected image under the UI. Asked for in the hook, after this frame's effects were recorded: a history
  // ping-pongs, so only then does the front end name the image this frame wrote.
  engine.setOverlayHook([&v, ui = v.overlay->hook()](const se::OverlayHookInfo& info) {
    v.backdrop->record(info,
                       rbViewer::inspectImage(v.adapter->effects(), v.adapter->settings().enabled, v.inspect).image);
    ui(info);
  });
  v.overlayAttached = true;
  return {};
}

// What the user changes while the viewer runs (the effects through the front end, the mode, the camera, the sun,
// the animation clock) and the frame that shows it. The keys and the overlay's panel make the same changes.
struct Session {
  Session(const Options& options, Viewer& v)
      : o(options),
        window(*v.window),
        engine(*v.engine),
        rt(*v.adapter),
        fx(rt.effects()),
        overlay(*v.overlay),
        backdrop(*v.backdrop),
        inspect(v.inspect),
        keys{static_cast<GLFWwindow*>(window.glfwHandle())},
        preset(o.preset),
        localLights(!engine.scene().lights.empty()),
        showOverlay(o.overlay) {
    params.camera = engine.scene().camera ? *engine.scene().camera : se::defaultCameraFor(engine.sceneBounds());
    if (engine.scene().sun) params.sun = *engine.scene().sun;
    sunAzimuth = std::atan2(params.sun.direction.x, params.sun.direction.z);
    sunElevation = std::asin(std::clamp(glm::normalize(params.sun.direction).y, -1.0f, 1.0f));
    orbit = Orbit::from(params.camera);
    sceneSize = std::max(engine.sceneBounds().radius(), 1.0f);
  }

  const Options& o;
  se::Window& window;
  se::Engine& engine;
  rbAdapter::Adapter& rt;
  rb::HybridEffects& fx;
  rbViewer::ImGuiOverlay& overlay;
  const rbViewer::Backdrop& backdrop;
  rbViewer::Inspect& inspect;
  Keys keys;

  rb::Preset preset;
  bool localLights;  // the scene's punctual lights are on; kept across presets, which never name them
  bool showOverlay;
  se::FrameParams params;
  float sunAzimuth = 0.0f, sunElevation = 0.0f;
  Orbit orbit{};
  float sceneSize = 1.0f;
  double lastX = 0, lastY = 0;
  std::chrono::steady_clock::time_point last = std::chrono::steady_clock::now();
  double frameMs = 0.0;
  uint32_t frames = 0;
  bool paused = false;        // the animation clock (real time) stops while paused
  bool overlayDrawn = false;  // the last rendered frame has the overlay in it

  void printState() const {
    const rb::HybridEffectsDesc& d = fx.desc();
    std::printf("mode %s, preset %s, effects [%s], shadows %s (%u rays), AO %u rays, denoise %s, sun azimuth %.0f "
                "elevation %.0f deg\n",
                rt.settings().enabled ? "hybrid" : "raster", rb::toString(preset), effectsToString(d.effects).c_str(),
                shadowRays(d) > 1 ? "soft" : "hard", shadowRays(d), aoRays(d), denoiseOn(d) ? "on" : "off",
                glm::degrees(sunAzimuth), glm::degrees(sunElevation));
    if (inspect.view == rbViewer::InspectView::LitFrame) return;
    const bool off = !(d.effects & rbViewer::effectBit(inspect.effect));
    std::printf("inspect %s:%s%s\n", rbViewer::toString(inspect.effect), rbViewer::toString(inspect.view),
                off ? " (that effect is off: the lit frame is shown)" : "");
  }
  void setDesc(const rb::HybridEffectsDesc& d) {
    if (rb::Status s = fx.setDesc(d); !s) std::fprintf(stderr, "raybridge-viewer: %s\n", s.error().message.c_str());
    printState();
  }
  void applyPreset(rb::Preset p) {
    preset = p;
    rb::HybridEffectsDesc d = rb::withPreset(fx.desc(), p);
    if (localLights) d.effects |= rb::kEffectLocalLights;
    setDesc(d);
  }
  void toggleEffects(rb::EffectSet bits) {
    rb::HybridEffectsDesc d = fx.desc();
    d.effects ^= bits;
    if (bits & rb::kEffectLocalLights) localLights = d.effects & rb::kEffectLocalLights;
    setDesc(d);
  }
  void toggleSoftShadows() {
    rb::HybridEffectsDesc d = fx.desc();
    const uint32_t presetRays = rb::presetDesc(preset).shadowRaysPerPixel;
    d.shadows.raysPerPixel = shadowRays(d) > 1 ? 1u : (presetRays > 1 ? presetRays : rb::kDefaultSoftShadowRays);
    setDesc(d);
  }
  void toggleDenoise() {
    rb::HybridEffectsDesc d = fx.desc();
    d.shadows.disableDenoiser = d.ao.disableDenoiser = denoiseOn(d);
    // Converged tiles read the shadow denoiser's history: off with it, the preset's choice back with it.
    d.shadows.schedule.convergedTiles.enabled = !d.shadows.disableDenoiser &&
                                                rb::presetDesc(preset).shadowConvergedTiles;
    setDesc(d);
  }
  void setHybrid(bool hybrid) {
    rt.settings().enabled = hybrid;
    printState();
  }

  // Raster mode: the engine's own counterparts of the enabled effects; its shadow map is the preset's (the
  // engine's default one when the preset has none). Hybrid mode: Raybridge's visibility replaces the map.
  void engineTerms() {
    const rb::EffectSet fxOn = fx.desc().effects;
    const bool raster = !rt.settings().enabled;
    const rb::RasterShadowDesc r = rb::presetDesc(preset).raster;
    params.shadow = se::ShadowSettings{};
    params.shadow.enabled = raster && (fxOn & rb::kEffectShadows);
    if (r.mapSize) params.shadow.mapSize = r.mapSize, params.shadow.pcfKernelSize = r.pcfKernel;
    params.ssao.enabled = raster && (fxOn & rb::kEffectAo);
    params.reflectionProbe.enabled = raster && (fxOn & rb::kEffectReflections);
  }

  // The overlay's panel, drawn into the frame about to render; what it asks for is applied before the frame, as
  // the keys are.
  void drawPanel() {
    overlay.beginFrame();
    const rb::HybridEffectsDesc& d = fx.desc();
    rbViewer::PanelModel m;
    m.device = engine.deviceInfo().name;
    m.hybrid = rt.settings().enabled;
    m.preset = preset;
    m.effects = d.effects;
    m.denoise = denoiseOn(d);
    m.shadowRays = (d.effects & rb::kEffectShadows) ? shadowRays(d) : 0u;
    m.aoRays = (d.effects & rb::kEffectAo) ? aoRays(d) : 0u;
    m.paused = paused;
    m.inspect = inspect;
    m.inspectNote = rbViewer::inspectImage(fx, m.hybrid, inspect).note;
    m.sunAzimuthDegrees = glm::degrees(sunAzimuth);
    m.sunElevationDegrees = glm::degrees(sunElevation);
    m.frameMs = frameMs;
    m.engine = engine.lastTimings();
    m.effectStats = fx.stats();
    m.budgetMs = fx.desc().budgetMs;
    m.as = rt.accelerationStructures().stats();
    m.memory = rt.context().memoryStats();
    const rbViewer::PanelRequests req = rbViewer::drawPanel(m);
    overlay.endFrame();
    if (req.hybrid) setHybrid(*req.hybrid);
    if (req.preset) applyPreset(*req.preset);
    if (req.toggleEffects) toggleEffects(req.toggleEffects);
    if (req.toggleSoftShadows) toggleSoftShadows();
    if (req.toggleDenoise) toggleDenoise();
    if (req.inspect) inspect = *req.inspect, printState();
    if (req.budgetMs) {
      rb::HybridEffectsDesc d = fx.desc();
      d.budgetMs = *req.budgetMs;
      setDesc(d);
    }
    engineTerms();
  }

  se::Status render(bool withOverlay) {
    overlayDrawn = withOverlay;
    if (withOverlay) drawPanel();
    se::Status s = engine.renderFrame(params);
    if (s && !overlay.lastError().empty()) return se::Status::failure("overlay: " + overlay.lastError());
    if (s && !backdrop.lastError().empty()) return se::Status::failure("inspect view: " + backdrop.lastError());
    return s;
  }

  // The keys that switch the mode, the effects, the preset and the animation clock.
  void handleSwitchKeys() {
    if (keys.pressed(GLFW_KEY_SPACE)) {
      paused = !paused;
      rt.settings().updateDeformedMeshes = !paused;  // a paused animation costs no BLAS work
      std::printf("animation %s at %.2f s\n", paused ? "paused" : "playing", params.time);
    }
    if (keys.pressed(GLFW_KEY_M)) setHybrid(!rt.settings().enabled);
    if (keys.pressed(GLFW_KEY_H)) toggleSoftShadows();
    if (keys.pressed(GLFW_KEY_O)) toggleEffects(rb::kEffectAo);
    if (keys.pressed(GLFW_KEY_R)) toggleEffects(rb::kEffectReflections);
    if (keys.pressed(GLFW_KEY_L)) toggleEffects(rb::kEffectLocalLights);
    if (keys.pressed(GLFW_KEY_N)) toggleDenoise();
    if (keys.pressed(GLFW_KEY_P)) applyPreset(rb::Preset((uint32_t(preset) + 1) % rb::kPresetCount));
  }

  void moveSun(float dt, bool uiKeyboard) {
    const float sunSpeed = 0.8f * dt;
    if (!uiKeyboard) {
      if (keys.down(GLFW_KEY_LEFT)) sunAzimuth -= sunSpeed;
      if (keys.down(GLFW_KEY_RIGHT)) sunAzimuth += sunSpeed;
      if (keys.down(GLFW_KEY_UP)) sunElevation = std::min(sunElevation + sunSpeed, glm::radians(89.0f));
      if (keys.down(GLFW_KEY_DOWN)) sunElevation = std::max(sunElevation - sunSpeed, glm::radians(3.0f));
    }
    params.sun.direction = {std::cos(sunElevation) * std::sin(sunAzimuth), std::sin(sunElevation),
                            std::cos(sunElevation) * std::cos(sunAzimuth)};
  }

  void moveCamera(float dt, bool uiKeyboard, bool uiMouse) {
    double x, y;
    window.cursorPosition(x, y);
    if (window.mouseButtonDown(0) && !uiMouse) {
      orbit.yaw -= float(x - lastX) * 0.005f;
      orbit.pitch = std::clamp(orbit.pitch + float(y - lastY) * 0.005f, -1.5f, 1.5f);
    }
    lastX = x;
    lastY = y;
    const double scroll = window.takeScrollDelta();
    if (!uiMouse) orbit.distance = std::max(orbit.distance * std::pow(0.9f, float(scroll)), 0.05f);
    const float speed = sceneSize * 0.5f * dt * (window.keyDown(se::Window::Key::LeftShift) ? 4.0f : 1.0f);
    const glm::vec3 forward(-std::sin(orbit.yaw), 0.0f, -std::cos(orbit.yaw)), right(-forward.z, 0.0f, forward.x);
    if (!uiKeyboard) {
      if (window.keyDown(se::Window::Key::W)) orbit.target += forward * speed;
      if (window.keyDown(se::Window::Key::S)) orbit.target -= forward * speed;
      if (window.keyDown(se::Window::Key::D)) orbit.target += right * speed;
      if (window.keyDown(se::Window::Key::A)) orbit.target -= right * speed;
      if (window.keyDown(se::Window::Key::E)) orbit.target.y += speed;
      if (window.keyDown(se::Window::Key::Q)) orbit.target.y -= speed;
    }
    orbit.apply(params.camera);
  }

  // Events, the clock and the input of one turn of the loop; keys and mouse go to the overlay when it wants them.
  void readInput() {
    window.pollEvents();
    if (window.keyDown(se::Window::Key::Escape)) window.requestClose();
    const auto now = std::chrono::steady_clock::now();
    const float dt = std::min(std::chrono::duration<float>(now - last).count(), 0.1f);
    frameMs = frameMs * 0.9 + 100.0 * double(std::chrono::duration<float>(now - last).count());
    last = now;
    const bool uiKeyboard = showOverlay && overlay.wantsKeyboard();
    const bool uiMouse = showOverlay && overlay.wantsMouse();
    if (keys.pressed(GLFW_KEY_F1)) showOverlay = !showOverlay;
    if (!uiKeyboard) handleSwitchKeys();
    if (!paused) params.time += dt;
    moveSun(dt, uiKeyboard);
    engineTerms();
    moveCamera(dt, uiKeyboard, uiMouse);
  }

  // Renders a frame at the window's size (none while it is minimised), every 60th with its GPU times printed;
  // closes the window after --frames. Returns "" or the error.
  std::string drawFrame() {
    int w = 0, h = 0;
    window.framebufferSize(w, h);
    if (w == 0 || h == 0) return {};
    const VkExtent2D size = engine.renderSize();
    if (uint32_t(w) != size.width || uint32_t(h) != size.height) (void)engine.resizeSwapchain(uint32_t(w), uint32_t(h));
    if (se::Status s = render(showOverlay); !s) return s.error;
    if (!rt.lastError().empty()) return "Raybridge: " + rt.lastError();
    if (++frames % 60 == 0) {
      const se::PassTimings t = engine.lastTimings();
      const rb::HybridStats es = fx.stats();
      std::printf("GPU ms: shadow map %.1f probe %.1f prepass %.1f ssao %.1f hook (Raybridge) %.1f [shadows %.1f+%.1f, "
                  "AO %.1f+%.1f, reflections %.1f] lighting %.1f tonemap %.1f\n",
                  t.shadowMs, t.probeMs, t.prepassMs, t.ssaoMs, t.hookMs, es.shadow.gpuMs, es.shadowDenoise.gpuMs,
                  es.ao.gpuMs, es.aoDenoise.gpuMs, es.reflection.gpuMs, t.lightingMs, t.tonemapMs);
    }
    if (o.frames > 0 && frames >= o.frames) window.requestClose();
    return {};
  }

  // --screenshot: the last frame, without the overlay unless --screenshot-overlay asks for it.
  std::string writeScreenshot() {
    if (overlayDrawn && !o.screenshotOverlay)
      if (se::Status s = render(false); !s) return s.error;
    if (se::Status s = engine.waitIdle(); !s) return s.error;
    auto ldr = engine.readbackLdr();
    if (!ldr) return ldr.error;
    if (se::Status s = se::writePng(o.screenshot, ldr.value); !s) return s.error;
    std::printf("wrote %s\n", o.screenshot.c_str());
    return {};
  }
};

}  // namespace

int main(int argc, char** argv) {
  Options o;
  bool exitNow = false;
  if (int code = parse(argc, argv, o, exitNow); exitNow) return code;
  if (const char* v = std::getenv("RAYBRIDGE_VALIDATION"); v && std::string(v) == "1") o.validation = true;

  se::Scene scene = se::makeDefaultDemoScene();
  if (!o.scene.empty()) {
    se::SceneLoadResult r = se::loadGltf(o.scene);
    if (!r.ok()) return fail("--scene: cannot load glTF '" + o.scene + "': " + r.error);
    scene = std::move(r.scene);
  }
  Viewer viewer;
  if (std::string e = createViewer(o, scene, viewer); !e.empty()) return fail(e);
  Session session(o, viewer);
  se::Engine& engine = *viewer.engine;
  std::printf("device: %s\n%s", engine.deviceInfo().name.c_str(), kKeys);
  session.window.cursorPosition(session.lastX, session.lastY);
  session.last = std::chrono::steady_clock::now();

  session.printState();
  while (!session.window.shouldClose()) {
    session.readInput();
    if (std::string e = session.drawFrame(); !e.empty()) return fail(e);
  }
  if (!o.screenshot.empty())
    if (std::string e = session.writeScreenshot(); !e.empty()) return fail(e);
  if (se::Status s = engine.waitIdle(); !s) return fail(s.error);
  std::printf("rendered %u frames\n", session.frames);
  engine.setOverlayHook({});
  viewer.overlay.reset();
  viewer.backdrop.reset();
  engine.setPrepassHook({});
  viewer.adapter.reset();
  if (o.validation) {
    std::printf("validation errors: %u\n", engine.validationErrorCount());
    if (engine.validationErrorCount() > 0) return 3;
  }
  return 0;
}
