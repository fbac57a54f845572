// Test-only knobs of the renderer, kept out of the public RenderSettings.
// They apply to renderers created while a ScopedTestHooks lives.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace shimmer::render::testing {

struct TestHooks {
  // Every dispatch after this many reports VK_ERROR_DEVICE_LOST (see
  // vk::ContextOptions); the renderer then gets a private device. -1: never.
  int lose_device_after_dispatches = -1;
  // Rows per dispatch (a multiple of 8), to test banding on small images.
  // 0: as many as the device's storage buffer range allows.
  int band_rows = 0;
  // Hand the driver the whole kernel with specialization constants, as
  // before shimmer specialized it itself: the test that both render alike.
  bool driver_specializes = false;
  // Kernel or shading-core GLSL files (by name, e.g. "ggx_rect.glsl") with
  // other text: how the job-id tests edit a shader without rebuilding.
  std::vector<std::pair<std::string, std::string>> source_overrides;
  // Every tile walks the BVH instead of testing its list (tile_lists.h):
  // the test that both give the same frames.
  bool walk_instead_of_tile_lists = false;
};

class ScopedTestHooks {
 public:
  explicit ScopedTestHooks(const TestHooks& hooks);
  ~ScopedTestHooks();
  ScopedTestHooks(const ScopedTestHooks&) = delete;
  ScopedTestHooks& operator=(const ScopedTestHooks&) = delete;

 private:
  TestHooks previous_;
};

// The hooks in force (defaults outside a ScopedTestHooks).
TestHooks CurrentTestHooks();

}  // namespace shimmer::render::testing
