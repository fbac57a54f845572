#include "shimmer/metrics/exr_sequence.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <set>

#include <tbb/parallel_for.h>
#include <opencv2/imgcodecs.hpp>

#include "shimmer/core/atomic_file.h"
#include "shimmer/core/exr_input.h"
#include "shimmer/core/sequence_file.h"

namespace shimmer::metrics {

namespace fs = std::filesystem;

namespace {

struct ChannelRef {
  int part = 0;
  std::string name;  // full channel name inside the part
};
// layer -> component ("R", "G", "B", "Y", "X", ...) -> where it lives.
using LayerMap = std::map<std::string, std::map<std::string, ChannelRef>>;

bool IsBeautyPartName(const std::string& name) {
  return name.empty() || name == "rgba" || name == "RGBA" || name == kBeautyLayer;
}

// Layer naming follows the OpenEXR multi-view/layer convention ("layer.C"):
// the last '.' separates the component. In multi-part files an unprefixed
// channel belongs to the part's name, so that a part "specular" with R,G,B is
// the same layer as channels "specular.R/G/B" in a single-part file.
LayerMap MapLayers(const ExrInput& file) {
  LayerMap layers;
  const auto& parts = file.parts();
  for (int p = 0; p < static_cast<int>(parts.size()); ++p) {
    const std::string& name = parts[p].name;
    std::string part_layer = kBeautyLayer;
    if (parts.size() > 1 && !IsBeautyPartName(name)) part_layer = name;
    for (const ExrChannelInfo& channel : parts[p].channels) {
      const std::string& full = channel.name;
      auto dot = full.rfind('.');
      std::string layer = dot == std::string::npos ? part_layer : full.substr(0, dot);
      std::string component = dot == std::string::npos ? full : full.substr(dot + 1);
      layers[layer].emplace(component, ChannelRef{p, full});
    }
  }
  return layers;
}

bool HasLuminance(const std::map<std::string, ChannelRef>& components) {
  return (components.count("R") && components.count("G") && components.count("B")) || components.count("Y");
}

bool HasMotion(const LayerMap& layers) {
  auto it = layers.find("motion");
  return it != layers.end() && it->second.count("X") && it->second.count("Y");
}

bool HasStderr(const LayerMap& layers) {
  auto it = layers.find("stderr");
  return it != layers.end() && it->second.count("Y");
}

std::vector<std::string> LuminanceLayers(const LayerMap& layers) {
  std::vector<std::string> names;
  for (const auto& [name, components] : layers)
    if (HasLuminance(components)) names.push_back(name);
  return names;
}

std::string Join(const std::vector<std::string>& items) {
  std::string out;
  for (const std::string& s : items) out += (out.empty() ? "" : ", ") + s;
  return out.empty() ? "none" : out;
}

// A frame's size is its first part's data window; every part must agree.
struct FrameSize {
  int width = 0, height = 0;
};
FrameSize SizeOf(const ExrPartInfo& part) { return {part.width, part.height}; }

Result<std::vector<fs::path>> ListExrFiles(const fs::path& dir) {
  std::error_code ec;
  std::vector<fs::path> frames;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (!it->is_regular_file(ec)) continue;
    std::string ext = it->path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext == ".exr") frames.push_back(it->path());
  }
  if (ec)
    return Result<std::vector<fs::path>>::Failure(dir.string() + ": cannot list directory (" + ec.message() + ")");
  std::sort(frames.begin(), frames.end(),
            [](const fs::path& a, const fs::path& b) { return a.filename().string() < b.filename().string(); });
  return frames;
}

// Header-level check of one frame: opens it, maps its layers.
Result<LayerMap> ReadLayerMap(const fs::path& file, FrameSize* size) {
  auto in = ExrInput::Open(file);
  if (!in) return Result<LayerMap>::Failure(in.error());
  for (const ExrPartInfo& part : in->parts())
    if (part.deep) return Result<LayerMap>::Failure(file.string() + ": deep EXR images are not supported");
  if (size) *size = SizeOf(in->parts().front());
  return MapLayers(*in);
}

// One frame against frame 0's size and the chosen layer.
struct FrameCheck {
  std::optional<std::string> problem;
  bool motion = false;
  bool stderr_y = false;
};
FrameCheck CheckFrame(const fs::path& frame, const ExrSequence& seq) {
  FrameSize size;
  auto layers = ReadLayerMap(frame, &size);
  if (!layers) return {layers.error()};
  if (size.width != seq.width || size.height != seq.height)
    return {frame.string() + ": frame is " + std::to_string(size.width) + "x" + std::to_string(size.height) + " but " +
            seq.frames[0].filename().string() + " is " + std::to_string(seq.width) + "x" + std::to_string(seq.height)};
  auto it = layers->find(seq.layer);
  if (it == layers->end())
    return {frame.string() + ": no layer '" + seq.layer + "' (layers: " + Join(LuminanceLayers(*layers)) + ")"};
  if (!HasLuminance(it->second)) {
    std::vector<std::string> present;
    for (const auto& [component, ref] : it->second) present.push_back(ref.name);
    return {frame.string() + ": layer '" + seq.layer + "' lacks channel R, G or B (has " + Join(present) + ")"};
  }
  return {std::nullopt, HasMotion(*layers), HasStderr(*layers)};
}

// One layer's luminance (and motion) from an open file into `frame`.
Status ReadLayer(const ExrInput& in, const fs::path& file, const std::string& layer, int width, int height,
                 bool with_motion, bool with_stderr, FrameScratch& scratch, LuminanceFrame& frame) {
  LayerMap layers = MapLayers(in);
  auto it = layers.find(layer);
  if (it == layers.end() || !HasLuminance(it->second))
    return Status::Failure(file.string() + ": no layer '" + layer +
                           "' with R,G,B (layers: " + Join(LuminanceLayers(layers)) + ")");
  const auto& components = it->second;
  const bool rgb = components.count("R") && components.count("G") && components.count("B");
  if (with_motion && !HasMotion(layers)) return Status::Failure(file.string() + ": no motion.X/motion.Y channels");
  if (with_stderr && !HasStderr(layers)) return Status::Failure(file.string() + ": no stderr.Y channel");

  // Component planes to fill, grouped by part below. A luminance channel Y
  // and stderr.Y go straight into the frame.
  std::vector<std::pair<ChannelRef, cv::Mat*>> wanted;
  if (rgb) {
    wanted = {{components.at("R"), &scratch.r}, {components.at("G"), &scratch.g}, {components.at("B"), &scratch.b}};
  } else {
    wanted = {{components.at("Y"), &frame.luminance}};
  }
  if (with_motion) {
    wanted.push_back({layers.at("motion").at("X"), &scratch.motion_x});
    wanted.push_back({layers.at("motion").at("Y"), &scratch.motion_y});
  }
  if (with_stderr) wanted.push_back({layers.at("stderr").at("Y"), &frame.stderr_y});
  for (auto& [ref, plane] : wanted) plane->create(height, width, CV_32F);
  std::set<int> parts;
  for (const auto& w : wanted) parts.insert(w.first.part);
  for (int p : parts) {
    const ExrPartInfo& part = in.parts()[p];
    if (part.deep) return Status::Failure(file.string() + ": deep EXR images are not supported");
    if (part.width != width || part.height != height)
      return Status::Failure(file.string() + ": frame is " + std::to_string(part.width) + "x" +
                             std::to_string(part.height) + ", expected " + std::to_string(width) + "x" +
                             std::to_string(height));
    std::vector<ExrPlaneRequest> requests;
    for (const auto& [ref, plane] : wanted) {
      if (ref.part != p) continue;
      for (const ExrChannelInfo& c : part.channels)
        if (c.name == ref.name && (c.x_sampling != 1 || c.y_sampling != 1))
          return Status::Failure(file.string() + ": channel " + ref.name + " is subsampled; not supported");
      requests.push_back({ref.name, plane->ptr<float>()});
    }
    if (Status read = in.Read(p, requests); !read) return read;
  }
  if (rgb) {
    frame.luminance.create(height, width, CV_32F);
    for (int y = 0; y < height; ++y) {
      const float *pr = scratch.r.ptr<float>(y), *pg = scratch.g.ptr<float>(y), *pb = scratch.b.ptr<float>(y);
      float* out = frame.luminance.ptr<float>(y);
      for (int x = 0; x < width; ++x) out[x] = static_cast<float>(kLumaR * pr[x] + kLumaG * pg[x] + kLumaB * pb[x]);
    }
  }
  if (with_motion)
    cv::merge(std::vector<cv::Mat>{scratch.motion_x, scratch.motion_y}, frame.motion);
  else
    frame.motion.release();
  if (!with_stderr) frame.stderr_y.release();
  return Ok();
}

// A renderer that stopped (or is still going) says so in its sequence.json;
// its frames are not a sequence to measure.
Status CheckComplete(const SequenceFile& sequence, const fs::path& file) {
  if (sequence.status == SequenceStatus::kComplete) return Ok();
  std::string why = file.string() + ": the sequence is " + SequenceStatusName(sequence.status) + ", not complete";
  if (!sequence.error.empty()) why += " (" + sequence.error + ")";
  return Status::Failure(why);
}

}  // namespace

Result<ExrSequence> OpenSequence(const fs::path& path, const SequenceRequest& request) {
  using R = Result<ExrSequence>;
  ExrSequence seq;
  seq.source = path;
  std::error_code ec;
  std::optional<double> json_fps;
  if (fs::is_directory(path, ec)) {
    auto files = ListExrFiles(path);
    if (!files) return files.failure();
    seq.frames = std::move(*files);
    if (seq.frames.empty()) return R::Failure(path.string() + ": no .exr frames in this directory");
    // The renderer writes sequence.json beside its frames; honour its fps.
    if (fs::path sidecar = path / "sequence.json"; fs::is_regular_file(sidecar, ec)) {
      auto sequence = ReadSequenceFile(sidecar);
      if (!sequence) return sequence.failure();
      if (Status s = CheckComplete(*sequence, sidecar); !s) return s.failure();
      json_fps = sequence->fps;
    }
  } else if (fs::is_regular_file(path, ec) && path.extension() == ".json") {
    auto sequence = ReadSequenceFile(path);
    if (!sequence) return sequence.failure();
    if (Status s = CheckComplete(*sequence, path); !s) return s.failure();
    json_fps = sequence->fps;
    fs::path dir = path.parent_path().empty() ? fs::path(".") : path.parent_path();
    for (const SequenceFrame& f : sequence->frames) seq.frames.push_back(dir / f.file);
    if (sequence->frames.empty()) {
      auto files = ListExrFiles(dir);
      if (!files) return files.failure();
      seq.frames = std::move(*files);
    }
    if (seq.frames.empty()) return R::Failure(path.string() + ": lists no frames and its directory has no .exr files");
  } else if (!fs::exists(path, ec)) {
    return R::Failure(path.string() + ": no such file or directory");
  } else {
    return R::Failure(path.string() + ": expected a directory of EXR frames or a sequence.json");
  }

  if (json_fps) {
    if (!(std::isfinite(*json_fps) && *json_fps > 0)) return R::Failure(path.string() + ": fps must be > 0");
    seq.fps = *json_fps;
    seq.fps_source = "sequence.json";
    if (request.fps && *request.fps != *json_fps)
      seq.warnings.push_back("--fps " + std::to_string(*request.fps) + " ignored: sequence.json says " +
                             std::to_string(*json_fps));
  } else if (request.fps) {
    seq.fps = *request.fps;
    seq.fps_source = "--fps";
  } else {
    seq.fps = 60;
    seq.fps_source = "default";
  }

  // Frame 0 decides the layer and size; every other frame must match it.
  FrameSize first;
  auto layers0 = ReadLayerMap(seq.frames[0], &first);
  if (!layers0) return R::Failure(layers0.error());
  seq.layers = LuminanceLayers(*layers0);
  if (request.layer.empty()) {
    if (layers0->count("specular") && HasLuminance(layers0->at("specular")))
      seq.layer = "specular";
    else if (layers0->count(kBeautyLayer) && HasLuminance(layers0->at(kBeautyLayer)))
      seq.layer = kBeautyLayer;
    else if (seq.layers.size() == 1)
      seq.layer = seq.layers[0];
    else
      return R::Failure(seq.frames[0].string() +
                        ": no 'specular' layer and no R,G,B channels; pick one with --layer (" + Join(seq.layers) +
                        ")");
  } else {
    seq.layer = request.layer;
  }
  seq.width = first.width;
  seq.height = first.height;
  seq.has_motion = HasMotion(*layers0);
  seq.has_stderr = HasStderr(*layers0);

  // Headers are checked in parallel (a ~1 ms parse each, 128 of them for a
  // 64-frame pair); the first bad frame in sequence order is the one reported.
  std::vector<FrameCheck> checks(seq.frames.size());
  tbb::parallel_for(size_t{0}, seq.frames.size(), [&](size_t i) { checks[i] = CheckFrame(seq.frames[i], seq); });
  for (const FrameCheck& check : checks) {
    if (check.problem) return R::Failure(*check.problem);
    seq.has_motion = seq.has_motion && check.motion;
    seq.has_stderr = seq.has_stderr && check.stderr_y;
  }
  return seq;
}

Status ReadFrameInto(const fs::path& file, const std::string& layer, int width, int height, bool with_motion,
                     bool with_stderr, FrameScratch& scratch, LuminanceFrame& frame) {
  auto in = ExrInput::Open(file, /*whole_file=*/true);
  if (!in) return in.failure();
  return ReadLayer(*in, file, layer, width, height, with_motion, with_stderr, scratch, frame);
}

Result<LuminanceFrame> ReadFrame(const fs::path& file, const std::string& layer, int width, int height,
                                 bool with_motion, bool with_stderr) {
  FrameScratch scratch;
  LuminanceFrame frame;
  if (Status read = ReadFrameInto(file, layer, width, height, with_motion, with_stderr, scratch, frame); !read)
    return read.failure();
  return frame;
}

Result<cv::Mat> ReadMask(const fs::path& file, int width, int height) {
  using R = Result<cv::Mat>;
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) return R::Failure(file.string() + ": no such mask file");
  cv::Mat image;
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".exr") {
    // One open: the file's layers, its own size (checked against the
    // frames' below, as for any image), then its pixels.
    auto in = ExrInput::Open(file, /*whole_file=*/true);
    if (!in) return R::Failure(in.error());
    const std::vector<std::string> layers = LuminanceLayers(MapLayers(*in));
    std::string layer = layers.empty() ? "" : layers.front();
    for (const std::string& l : layers)
      if (l == kBeautyLayer) layer = l;
    if (layer.empty()) return R::Failure(file.string() + ": mask EXR has no R,G,B or Y channels");
    const FrameSize size = SizeOf(in->parts().front());
    FrameScratch scratch;
    LuminanceFrame frame;
    if (Status read = ReadLayer(*in, file, layer, size.width, size.height, false, false, scratch, frame); !read)
      return R::Failure(read.error());
    image = frame.luminance;
  } else {
    image = cv::imread(file.string(), cv::IMREAD_UNCHANGED | cv::IMREAD_ANYDEPTH);
    if (image.empty()) return R::Failure(file.string() + ": not an image OpenCV can read");
  }
  if (image.cols != width || image.rows != height)
    return R::Failure(file.string() + ": mask is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                      " but the frames are " + std::to_string(width) + "x" + std::to_string(height));
  std::vector<cv::Mat> channels;
  cv::split(image, channels);
  cv::Mat inside = cv::Mat::zeros(height, width, CV_8U);
  for (const cv::Mat& c : channels) {
    cv::Mat as_float;
    c.convertTo(as_float, CV_32F);
    // NaN compares unequal to 0 and would count as inside; only finite nonzero is in.
    cv::Mat nonzero = (as_float != 0) & (as_float == as_float);
    inside |= nonzero;
  }
  return cv::Mat(inside / 255);
}

ExrPlane PlaneOf(std::string name, const cv::Mat& plane, bool half) {
  CV_Assert(plane.type() == CV_32F && plane.isContinuous());
  return ExrPlane{std::move(name), plane.ptr<float>(), half};
}

}  // namespace shimmer::metrics
