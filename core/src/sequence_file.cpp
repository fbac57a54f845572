#include "shimmer/core/sequence_file.h"

#include <cmath>

#include "shimmer/core/atomic_file.h"
#include "shimmer/core/json_file.h"

namespace shimmer {

namespace {

using json = nlohmann::json;

// Field readers: absent keys keep the default, a present key of the wrong
// type is an error naming it.
class FieldReader {
 public:
  FieldReader(const json& object, std::string source) : object_(object), source_(std::move(source)) {}

  template <class T>
  void Read(const char* key, T* out) {
    if (!error_.empty() || !object_.contains(key)) return;
    const json& v = object_[key];
    if constexpr (std::is_same_v<T, std::string>) {
      if (!v.is_string()) return Fail(key, "a string");
      *out = v.get<std::string>();
    } else if constexpr (std::is_same_v<T, bool>) {
      if (!v.is_boolean()) return Fail(key, "true or false");
      *out = v.get<bool>();
    } else if constexpr (std::is_integral_v<T>) {
      if (!v.is_number_integer()) return Fail(key, "an integer");
      *out = v.get<T>();
    } else {
      if (!v.is_number() || !std::isfinite(v.get<double>())) return Fail(key, "a finite number");
      *out = v.get<double>();
    }
  }
  template <class T>
  void Read(const char* key, std::optional<T>* out) {
    if (!error_.empty() || !object_.contains(key)) return;
    T value{};
    Read(key, &value);
    if (error_.empty()) *out = value;
  }
  void Fail(const std::string& key, const std::string& expected) {
    if (error_.empty()) error_ = source_ + ": \"" + key + "\" must be " + expected;
  }
  const std::string& error() const { return error_; }

 private:
  const json& object_;
  std::string source_;
  std::string error_;
};

}  // namespace

const char* SequenceStatusName(SequenceStatus status) {
  switch (status) {
    case SequenceStatus::kRunning: return "running";
    case SequenceStatus::kComplete: return "complete";
    case SequenceStatus::kFailed: return "failed";
  }
  return "failed";
}

double SequenceFile::MeanGpuMs() const {
  if (frames.empty()) return 0;
  double sum = 0;
  for (const SequenceFrame& f : frames) sum += f.gpu_ms;
  return sum / double(frames.size());
}

json ToJson(const SequenceFile& s) {
  json params = json::object();
  for (const auto& [k, v] : s.params) params[k] = v;
  json frames = json::array();
  for (const SequenceFrame& f : s.frames) {
    json fj = {{"file", f.file}, {"gpu_ms", f.gpu_ms}, {"time_s", f.time_s}};
    if (f.mean_spp) fj["mean_spp"] = *f.mean_spp;
    if (f.rounds) fj["rounds"] = *f.rounds;
    if (f.unconverged_pixels) fj["unconverged_pixels"] = *f.unconverged_pixels;
    frames.push_back(std::move(fj));
  }
  const SequenceCamera& c = s.camera;
  json j = {
      {"status", SequenceStatusName(s.status)},
      {"scene", s.scene},
      {"material", s.material},
      {"light", s.light},
      {"camera",
       {{"path", c.path},
        {"target", c.target},
        {"distance", c.distance},
        {"elevation_deg", c.elevation_deg},
        {"azimuth_deg", c.azimuth_deg},
        {"fov_y_deg", c.fov_y_deg}}},
      {"variant", s.variant},
      {"params", params},
      {"derivatives", s.derivatives},
      {"width", s.width},
      {"height", s.height},
      {"frame_count", s.frame_count},
      {"spp", s.spp},
      {"reference", s.reference},
      {"device", s.device},
      {"driver", s.driver},
      {"revision", s.revision},
      {"timings_ms",
       {{"shader_compile", s.timings.shader_compile_ms},
        {"specialize", s.timings.specialize_ms},
        {"pipeline_create", s.timings.pipeline_create_ms},
        {"startup", s.timings.startup_ms},
        {"first_dispatch_jit", s.timings.first_dispatch_jit_ms},
        {"render_wall", s.timings.render_wall_ms},
        {"readback", s.timings.readback_ms},
        {"exr_write", s.timings.exr_write_ms}}},
      {"frames", frames},
  };
  if (s.fps) j["fps"] = *s.fps;
  if (s.reference) {
    j["reference_spp"] = s.reference_spp;
    j["reference_replicates"] = s.reference_replicates;
    j["reference_tolerance"] = s.reference_tolerance;
    j["reference_luminance_floor"] = s.reference_luminance_floor;
  }
  if (s.seed != 0) j["seed"] = s.seed;
  if (!s.variant_file.empty()) j["variant_file"] = s.variant_file;
  if (!s.error.empty()) j["error"] = s.error;
  return j;
}

namespace {

Status ReadCamera(const json& cj, const std::string& source, SequenceCamera* camera) {
  if (!cj.is_object()) return Status::Failure(source + ": \"camera\" must be an object");
  FieldReader cr(cj, source + ": camera");
  cr.Read("path", &camera->path);
  cr.Read("distance", &camera->distance);
  cr.Read("elevation_deg", &camera->elevation_deg);
  cr.Read("azimuth_deg", &camera->azimuth_deg);
  cr.Read("fov_y_deg", &camera->fov_y_deg);
  if (!cr.error().empty()) return Status::Failure(cr.error());
  if (cj.contains("target")) {
    const json& t = cj["target"];
    if (!t.is_array() || t.size() != 3 || !t[0].is_number() || !t[1].is_number() || !t[2].is_number())
      return Status::Failure(source + ": camera: \"target\" must be [x, y, z]");
    for (int i = 0; i < 3; ++i) camera->target[i] = t[i].get<double>();
  }
  return Ok();
}

Status ReadTimings(const json& tj, const std::string& source, SequenceTimings* t) {
  if (!tj.is_object()) return Status::Failure(source + ": \"timings_ms\" must be an object");
  FieldReader tr(tj, source + ": timings_ms");
  tr.Read("shader_compile", &t->shader_compile_ms);
  tr.Read("specialize", &t->specialize_ms);
  tr.Read("pipeline_create", &t->pipeline_create_ms);
  tr.Read("startup", &t->startup_ms);
  tr.Read("first_dispatch_jit", &t->first_dispatch_jit_ms);
  tr.Read("render_wall", &t->render_wall_ms);
  tr.Read("readback", &t->readback_ms);
  tr.Read("exr_write", &t->exr_write_ms);
  if (!tr.error().empty()) return Status::Failure(tr.error());
  return Ok();
}

// File names, or objects with a "file" (shimmer's renderer adds gpu_ms and time_s).
Status ReadFrames(const json& frames, const std::string& source, std::vector<SequenceFrame>* out) {
  const std::string shape = ": \"frames\" must be an array of file names or of {\"file\": name} objects";
  if (!frames.is_array()) return Status::Failure(source + shape);
  for (const json& f : frames) {
    SequenceFrame frame;
    if (f.is_string()) {
      frame.file = f.get<std::string>();
    } else if (f.is_object() && f.contains("file") && f["file"].is_string()) {
      FieldReader fr(f, source + ": frames[" + std::to_string(out->size()) + "]");
      fr.Read("file", &frame.file);
      fr.Read("gpu_ms", &frame.gpu_ms);
      fr.Read("time_s", &frame.time_s);
      fr.Read("mean_spp", &frame.mean_spp);
      fr.Read("rounds", &frame.rounds);
      fr.Read("unconverged_pixels", &frame.unconverged_pixels);
      if (!fr.error().empty()) return Status::Failure(fr.error());
    } else {
      return Status::Failure(source + shape);
    }
    if (frame.file.empty() || frame.file.find('\0') != std::string::npos)
      return Status::Failure(source + ": frames[" + std::to_string(out->size()) + "]: empty file name");
    out->push_back(std::move(frame));
  }
  return Ok();
}

}  // namespace

Result<SequenceFile> SequenceFromJson(const json& j, const std::string& source) {
  using R = Result<SequenceFile>;
  if (!j.is_object()) return R::Failure(source + ": expected a JSON object");
  SequenceFile s;
  FieldReader r(j, source);
  if (j.contains("status")) {
    const json& v = j["status"];
    if (v == "running")
      s.status = SequenceStatus::kRunning;
    else if (v == "complete")
      s.status = SequenceStatus::kComplete;
    else if (v == "failed")
      s.status = SequenceStatus::kFailed;
    else
      r.Fail("status", "\"running\", \"complete\" or \"failed\"");
  }
  r.Read("error", &s.error);
  r.Read("scene", &s.scene);
  r.Read("material", &s.material);
  r.Read("light", &s.light);
  r.Read("variant", &s.variant);
  r.Read("derivatives", &s.derivatives);
  r.Read("variant_file", &s.variant_file);
  r.Read("width", &s.width);
  r.Read("height", &s.height);
  r.Read("fps", &s.fps);
  r.Read("frame_count", &s.frame_count);
  r.Read("spp", &s.spp);
  r.Read("reference", &s.reference);
  r.Read("reference_spp", &s.reference_spp);
  r.Read("reference_replicates", &s.reference_replicates);
  std::int64_t seed = 0;
  r.Read("seed", &seed);
  if (seed < 0 || seed > std::int64_t(UINT32_MAX)) r.Fail("seed", "an integer in 0..4294967295");
  s.seed = std::uint32_t(seed);
  r.Read("reference_tolerance", &s.reference_tolerance);
  r.Read("reference_luminance_floor", &s.reference_luminance_floor);
  r.Read("device", &s.device);
  r.Read("driver", &s.driver);
  r.Read("revision", &s.revision);
  if (!r.error().empty()) return R::Failure(r.error());
  if (s.fps && !(*s.fps > 0)) return R::Failure(source + ": \"fps\" must be > 0");

  if (j.contains("camera"))
    if (Status c = ReadCamera(j["camera"], source, &s.camera); !c) return c.failure();
  if (j.contains("params")) {
    const json& pj = j["params"];
    if (!pj.is_object()) return R::Failure(source + ": \"params\" must be an object of numbers");
    for (const auto& [k, v] : pj.items()) {
      if (!v.is_number()) return R::Failure(source + ": params: \"" + k + "\" must be a number");
      s.params[k] = v.get<double>();
    }
  }
  if (j.contains("timings_ms"))
    if (Status t = ReadTimings(j["timings_ms"], source, &s.timings); !t) return t.failure();
  if (j.contains("frames"))
    if (Status f = ReadFrames(j["frames"], source, &s.frames); !f) return f.failure();
  return s;
}

Result<SequenceFile> ReadSequenceFile(const std::filesystem::path& path) {
  auto j = ReadJsonFile(path);
  if (!j) return j.failure();
  return SequenceFromJson(*j, path.string());
}

Status WriteSequenceFile(const std::filesystem::path& path, const SequenceFile& sequence) {
  return WriteFileAtomic(path, ToJson(sequence).dump(2) + "\n");
}

}  // namespace shimmer
