// GLFW window for the interactive viewer. Only this file's functions touch GLFW/X11; a headless program
// that never creates a Window never initialises GLFW.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

#include "sample_engine/result.h"

namespace sample_engine {

class Window {
 public:
  static Result<std::unique_ptr<Window>> create(const std::string& title, int width, int height);
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;

  // Instance extensions needed to present to this window (put them into EngineConfig::instanceExtensions).
  std::vector<std::string> requiredInstanceExtensions() const;
  Result<VkSurfaceKHR> createSurface(VkInstance instance) const;

  bool shouldClose() const;
  void requestClose();
  void pollEvents();
  void framebufferSize(int& width, int& height) const;

  // Minimal input for a viewer, so programs need not include GLFW themselves.
  enum class Key { W, A, S, D, Q, E, LeftShift, Escape };
  bool keyDown(Key key) const;
  bool mouseButtonDown(int button) const;  // 0 = left, 1 = right, 2 = middle
  void cursorPosition(double& x, double& y) const;
  double takeScrollDelta();                     // vertical scroll accumulated since the last call
  void* glfwHandle() const { return window_; }  // GLFWwindow*, for input callbacks

 private:
  Window() = default;
  void* window_ = nullptr;
  double scroll_ = 0.0;
};

}  // namespace sample_engine
