// sequence.json, the sidecar of a rendered sequence: one schema, one writer
// (the renderer) and one reader (the metrics, the runner, tests). Another
// renderer may write just {"fps": .., "frames": [names]}; every other field
// is optional when reading.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shimmer/core/result.h"

namespace shimmer {

enum class SequenceStatus { kRunning, kComplete, kFailed };
const char* SequenceStatusName(SequenceStatus status);

struct SequenceFrame {
  std::string file;  // relative to the sequence.json's directory
  double gpu_ms = 0;
  double time_s = 0;
  std::optional<double> mean_spp;  // references only
  std::optional<int> rounds;       // references only
  // Adaptive references only: pixels still above the tolerance at max_rounds.
  std::optional<int> unconverged_pixels;
};

struct SequenceCamera {
  std::string path;  // "orbit", "pan", ...
  std::array<double, 3> target{0, 0, 0};
  double distance = 0, elevation_deg = 0, azimuth_deg = 0, fov_y_deg = 0;
};

struct SequenceTimings {
  double shader_compile_ms = 0, specialize_ms = 0, pipeline_create_ms = 0, first_dispatch_jit_ms = 0;
  double startup_ms = 0;  // the renderer's whole start-up, the above included
  double render_wall_ms = 0, readback_ms = 0, exr_write_ms = 0;
};

struct SequenceFile {
  SequenceStatus status = SequenceStatus::kComplete;
  std::string error;  // why it failed

  std::string scene, material, light, variant, derivatives, variant_file;
  SequenceCamera camera;
  std::map<std::string, double> params;
  int width = 0, height = 0;
  std::optional<double> fps;
  int frame_count = 0;  // the frames asked for; `frames` lists those on disk
  int spp = 1;
  bool reference = false;
  int reference_spp = 0;
  int reference_replicates = 0;  // K: independent N x N patterns (at least) per pixel
  double reference_tolerance = 0, reference_luminance_floor = 0;
  std::uint32_t seed = 0;  // the render's seed; written when not 0
  std::string device, driver, revision;
  SequenceTimings timings;
  std::vector<SequenceFrame> frames;

  // Mean GPU milliseconds per frame over `frames`; 0 when none.
  double MeanGpuMs() const;
};

nlohmann::json ToJson(const SequenceFile& sequence);
// `source` names the file in messages, which name the key that is wrong.
Result<SequenceFile> SequenceFromJson(const nlohmann::json& json, const std::string& source);

Result<SequenceFile> ReadSequenceFile(const std::filesystem::path& path);
// Atomic: a reader sees the previous version or this one.
Status WriteSequenceFile(const std::filesystem::path& path, const SequenceFile& sequence);

}  // namespace shimmer
