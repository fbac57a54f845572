// Writing what the renderer produces: frames as EXR (on a worker thread while
// the next frame renders), the preview PNG, and sequence.json, whose status
// says at every moment what the directory holds.
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <new>
#include <thread>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "shimmer/core/atomic_file.h"
#include "shimmer/core/directories.h"
#include "shimmer/core/exr_output.h"
#include "shimmer/core/host_memory.h"
#include "shimmer/renderer/renderer.h"

namespace shimmer::render {

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;
double MsSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

// EXR writing on a worker thread, at most two frames queued.
class FrameWriter {
 public:
  FrameWriter(bool with_stderr, bool compress)
      : with_stderr_(with_stderr), compress_(compress), thread_([this] { Loop(); }) {}
  ~FrameWriter() { (void)Finish(); }  // a failure was already returned by the caller's Finish()

  void Push(std::string path, Frame frame) {
    std::unique_lock<std::mutex> lock(mutex_);
    space_.wait(lock, [this] { return queue_.size() < 2; });
    queue_.push_back({std::move(path), std::move(frame)});
    ready_.notify_one();
  }
  // Waits for every queued frame; returns the first error.
  Status Finish() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
      ready_.notify_one();
    }
    if (thread_.joinable()) thread_.join();
    return status_;
  }
  double write_ms() const { return write_ms_; }

 private:
  void Loop() {
    for (;;) {
      std::pair<std::string, Frame> job;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        ready_.wait(lock, [this] { return done_ || !queue_.empty(); });
        if (queue_.empty()) return;
        job = std::move(queue_.front());
        queue_.pop_front();
        space_.notify_one();
      }
      if (!status_) continue;  // after a failure, later frames are dropped
      auto t0 = Clock::now();
      status_ = WriteFrameExr(job.first, job.second, with_stderr_, compress_);
      write_ms_ += MsSince(t0);
    }
  }

  bool with_stderr_;
  bool compress_;
  std::mutex mutex_;
  std::condition_variable ready_, space_;
  std::deque<std::pair<std::string, Frame>> queue_;
  bool done_ = false;
  Status status_ = Ok();
  double write_ms_ = 0;
  std::thread thread_;
};

std::string FrameName(int i) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%04d.exr", i);
  return name;
}

// At least two frames live at once: one rendering while the last is written.
// A size that cannot have them is refused before the device is touched: the
// allocation itself may succeed and its first use bring the OOM killer.
Status CheckHostMemory(const RenderSettings& s) {
  const std::uint64_t frame = std::uint64_t(s.width) * std::uint64_t(s.height) * kChannelCount * sizeof(float);
  const std::uint64_t available = AvailableHostMemory();
  if (available == 0 || 2 * frame <= available) return Ok();
  // Starts with the field's name, as ValidateSettings' messages do (the CLI names its flag instead).
  char text[192];
  std::snprintf(text, sizeof text,
                "width and height %dx%d: a frame takes %.1f GiB of host memory and rendering holds two at once; "
                "%.1f GiB are available",
                s.width, s.height, double(frame) / (1 << 30), double(available) / (1 << 30));
  return Status::Failure(text, ErrorCode::kOutOfMemory);
}

SequenceFile Describe(const RenderSettings& settings, const Renderer& renderer) {
  const ResolvedVariant& v = renderer.variant();
  const auto& rig = settings.scene.rig;
  SequenceFile seq;
  seq.status = SequenceStatus::kRunning;
  seq.scene = settings.scene.name;
  seq.material = scene::MaterialSpec(settings.material);
  seq.light = std::string(shading::LightTypeName(settings.scene.light.type));
  seq.camera = {std::string(scene::CameraPathName(settings.camera)),
                {rig.target.x, rig.target.y, rig.target.z},
                rig.distance,
                rig.elevation_deg,
                rig.azimuth_deg,
                rig.fov_y_deg};
  seq.variant = v.name;
  for (const auto& [k, x] : v.shown_params) seq.params[k] = x;
  // Supersampled pixels never read a derivative; their footprint is the analytic one.
  seq.derivatives = std::string(
      shading::DerivativeSourceName(v.spp_n > 1 ? shading::DerivativeSource::kAnalytic : settings.derivatives));
  seq.width = settings.width;
  seq.height = settings.height;
  seq.fps = settings.fps;
  seq.frame_count = settings.frames;
  seq.spp = v.spp_n * v.spp_n;
  seq.reference = v.reference;
  if (v.reference) {
    seq.reference_spp = v.spp_n;
    seq.reference_replicates = v.spp_n > 1 ? settings.reference_replicates : 1;
    seq.reference_tolerance = settings.reference_tolerance;
    seq.reference_luminance_floor = kReferenceLuminanceFloor;
  }
  seq.seed = settings.seed;
  seq.variant_file = settings.variant_file;
  seq.device = renderer.device_name();
  seq.driver = renderer.device_driver();
  seq.revision = SourceRevision();
  seq.timings.shader_compile_ms = renderer.timings().compile_ms;
  seq.timings.specialize_ms = renderer.timings().specialize_ms;
  seq.timings.pipeline_create_ms = renderer.timings().pipeline_ms;
  seq.timings.startup_ms = renderer.timings().startup_ms;
  seq.timings.first_dispatch_jit_ms = renderer.timings().jit_ms;
  return seq;
}

}  // namespace

Status WriteFrameExr(const std::string& path, const Frame& frame, bool with_stderr, bool compress) {
  const std::size_t plane = std::size_t(frame.width) * frame.height;
  std::vector<ExrPlane> planes;
  for (const FrameChannel& c : FrameChannels(with_stderr))
    planes.push_back({c.name, frame.planes.data() + c.plane * plane});
  return WriteExr(path, frame.width, frame.height, planes, compress ? ExrCompression::kZip : ExrCompression::kNone);
}

Status WritePreviewPng(const std::string& path, const Frame& frame) {
  cv::Mat img(frame.height, frame.width, CV_8UC3);
  const std::size_t plane = std::size_t(frame.width) * frame.height;
  auto encode = [](float x) {
    double v = std::max(0.0, double(x));
    v = v / (1.0 + v);
    v = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
    return cv::saturate_cast<unsigned char>(v * 255.0 + 0.5);
  };
  for (int y = 0; y < frame.height; ++y)
    for (int x = 0; x < frame.width; ++x) {
      std::size_t i = std::size_t(y) * frame.width + x;
      img.at<cv::Vec3b>(y, x) = {encode(frame.planes[(kBeautyR + 2) * plane + i]),
                                 encode(frame.planes[(kBeautyR + 1) * plane + i]),
                                 encode(frame.planes[kBeautyR * plane + i])};
    }
  // Encoded in memory, then written as any file is: a failed write gets the
  // system's reason (a full disk) and leaves no partial PNG.
  std::vector<unsigned char> png;
  try {
    if (!cv::imencode(".png", img, png))
      return Status::Failure(path + ": OpenCV cannot encode PNG", ErrorCode::kInternal);
  } catch (const cv::Exception& e) {
    return Status::Failure(path + ": cannot encode the preview (" + e.err + ")", ErrorCode::kInternal);
  }
  return WriteFileAtomic(path, std::string_view(reinterpret_cast<const char*>(png.data()), png.size()));
}

Result<SequenceFile> RenderSequence(const RenderSettings& settings, const std::string& out_dir,
                                    const std::function<void(int, int)>& progress) {
  // Everything that can be refused without a device is, before any file exists.
  if (Status s = ValidateSettings(settings); !s) return s.failure();
  // Checked before anything is created, so that a render refused for its
  // output leaves no directory behind.
  if (Status s = CheckCreatableDirectory(out_dir); !s)
    return Prefixed(out_dir + ": cannot create the output directory", s.failure());
  if (Status s = CheckHostMemory(settings); !s) return s.failure();
  auto renderer = Renderer::Create(settings);
  if (!renderer) return renderer.failure();
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec || !fs::is_directory(out_dir))
    return Result<SequenceFile>::Failure(
        out_dir + ": cannot create the output directory" + (ec ? " (" + ec.message() + ")" : ""), ErrorCode::kIo);
  const fs::path seq_path = fs::path(out_dir) / "sequence.json";
  SequenceFile seq = Describe(settings, **renderer);
  if (Status s = WriteSequenceFile(seq_path, seq); !s) return s.failure();

  // From here on, a failure is recorded in sequence.json as well as returned.
  auto fail = [&](const Error& error) -> Result<SequenceFile> {
    seq.status = SequenceStatus::kFailed;
    seq.error = error.message;
    (void)WriteSequenceFile(seq_path, seq);  // the original error is the one to report
    return error;
  };
  const bool reference = (*renderer)->variant().reference;
  FrameWriter writer(reference, settings.compress_exr);
  double render_ms = 0, readback_ms = 0;
  try {
    for (int i = 0; i < settings.frames; ++i) {
      auto t0 = Clock::now();
      auto frame = (*renderer)->RenderFrame(i);
      render_ms += MsSince(t0);
      if (!frame) {
        // Frames already handed to the writer are whole; this one never gets a file.
        (void)writer.Finish();
        return fail(Prefixed("frame " + std::to_string(i), frame.failure()));
      }
      readback_ms += frame->readback_ms;
      SequenceFrame entry;
      entry.file = FrameName(i);
      entry.gpu_ms = frame->gpu_ms;
      entry.time_s = i / settings.fps;
      if (reference) {
        entry.mean_spp = frame->mean_spp;
        entry.rounds = frame->rounds;
        if (settings.reference_tolerance > 0) entry.unconverged_pixels = frame->unconverged_pixels;
      }
      seq.frames.push_back(entry);
      if (i == 0 && !settings.preview_png.empty()) {
        if (Status s = WritePreviewPng(settings.preview_png, *frame); !s) {
          (void)writer.Finish();
          return fail(s.failure());
        }
      }
      writer.Push((fs::path(out_dir) / FrameName(i)).string(), std::move(*frame));
      if (progress) progress(i + 1, settings.frames);
    }
  } catch (const std::bad_alloc&) {
    (void)writer.Finish();
    return fail(Error{ErrorCode::kOutOfMemory, "out of memory after " + std::to_string(seq.frames.size()) +
                                                   " frames of " + std::to_string(settings.width) + "x" +
                                                   std::to_string(settings.height)});
  }
  if (Status s = writer.Finish(); !s) {
    // Only the frames before the failed write are whole on disk.
    std::erase_if(seq.frames, [&](const SequenceFrame& f) { return !fs::exists(fs::path(out_dir) / f.file, ec); });
    return fail(s.failure());
  }
  seq.status = SequenceStatus::kComplete;
  seq.timings.render_wall_ms = render_ms;
  seq.timings.readback_ms = readback_ms;
  seq.timings.exr_write_ms = writer.write_ms();
  if (Status s = WriteSequenceFile(seq_path, seq); !s) return fail(s.failure());
  return seq;
}

}  // namespace shimmer::render
