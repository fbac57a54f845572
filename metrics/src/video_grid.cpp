#include "shimmer/metrics/video_grid.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include <opencv2/imgproc.hpp>

#include "shimmer/core/atomic_file.h"

namespace shimmer::metrics {

namespace {

const cv::Scalar kBackground(32, 32, 32), kText(255, 255, 255), kDim(170, 170, 170);
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;

std::string Tick(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%+.2g", v);
  return v == 0 ? "0" : buf;
}

// Text that fits `width`: cut with an ellipsis rather than drawn past the tile.
std::string Fitted(std::string text, int width, double font_scale) {
  int baseline = 0;
  while (text.size() > 3 && cv::getTextSize(text, kFont, font_scale, 1, &baseline).width > width - 8)
    text = text.substr(0, text.size() - 4) + "...";
  return text;
}

}  // namespace

cv::Mat DisplayGrey(const cv::Mat& luminance) {
  cv::Mat out(luminance.size(), CV_8UC3);
  for (int y = 0; y < luminance.rows; ++y) {
    const float* l = luminance.ptr<float>(y);
    cv::Vec3b* o = out.ptr<cv::Vec3b>(y);
    for (int x = 0; x < luminance.cols; ++x) {
      double v = std::isfinite(l[x]) ? std::max(0.0f, l[x]) : 0.0;
      v = v / (1.0 + v);  // Reinhard: keeps highlights from clipping flat
      v = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;  // sRGB OETF
      const uchar g = cv::saturate_cast<uchar>(255.0 * v);
      o[x] = cv::Vec3b(g, g, g);
    }
  }
  return out;
}

GridLayout LayoutGrid(int tiles, int width, int height) {
  GridLayout g;
  g.scale = std::max(1, (GridLayout::kMinTileWidth + width - 1) / std::max(1, width));
  const int w = width * g.scale, h = height * g.scale, gap = 4;
  const int columns = std::min(tiles, 3), rows = (tiles + 2) / 3;
  const int tile_w = w + gap, tile_h = GridLayout::kLabelHeight + 2 * h + gap;
  for (int i = 0; i < tiles; ++i) {
    const int x = (i % 3) * tile_w, y = (i / 3) * tile_h;
    GridTile t;
    t.label = cv::Rect(x, y, w, GridLayout::kLabelHeight);
    t.image = cv::Rect(x, y + GridLayout::kLabelHeight, w, h);
    t.panel = cv::Rect(x, y + GridLayout::kLabelHeight + h, w, h);
    g.tiles.push_back(t);
  }
  g.frame = cv::Size((columns * tile_w - gap + 1) / 2 * 2, (rows * tile_h - gap + 1) / 2 * 2);
  return g;
}

Result<std::unique_ptr<VideoGrid>> VideoGrid::Open(const std::filesystem::path& file, VideoGridOptions options) {
  using R = Result<std::unique_ptr<VideoGrid>>;
  // Tile 0 is the reference's, with the legend below it; without a
  // reference it holds the legend alone.
  const int tiles = int(options.labels.size()) + 1;
  if (options.labels.empty()) return R::Failure(file.string() + ": a video grid needs at least one test sequence");
  if (tiles > kMaxTiles)
    return R::Failure(file.string() + ": a video grid has at most " + std::to_string(kMaxTiles) + " tiles (" +
                      std::to_string(tiles) + " asked for, the reference's included): at most " +
                      std::to_string(kMaxTiles - 1) + " test sequences");
  if (options.width < 1 || options.height < 1) return R::Failure(file.string() + ": the frames have no pixels");
  if (options.slow < 1 || options.slow > 100)
    return R::Failure(file.string() + ": slow motion must repeat each frame 1 to 100 times");
  if (!(options.fps > 0)) return R::Failure(file.string() + ": fps must be > 0");
  std::error_code ec;
  // A missing directory is the user's typo, not a tree to create.
  if (!file.parent_path().empty() && !std::filesystem::is_directory(file.parent_path(), ec))
    return R::Failure(file.string() + ": the directory " + file.parent_path().string() + " does not exist");
  std::unique_ptr<VideoGrid> grid(new VideoGrid());
  grid->file_ = file;
  grid->temporary_ = TemporaryPathFor(file);
  grid->layout_ = LayoutGrid(tiles, options.width, options.height);
  grid->options_ = std::move(options);
  struct Codec {
    const char* name;
    int fourcc;
  };
  const Codec codecs[] = {{"avc1", cv::VideoWriter::fourcc('a', 'v', 'c', '1')},
                          {"mp4v", cv::VideoWriter::fourcc('m', 'p', '4', 'v')}};
  for (const Codec& c : codecs) {
    try {
      if (grid->writer_.open(grid->temporary_.string(), cv::CAP_FFMPEG, c.fourcc, grid->options_.fps,
                             grid->layout_.frame, true)) {
        grid->fourcc_name_ = c.name;
        return R(std::move(grid));
      }
    } catch (const cv::Exception&) {
    }
  }
  std::filesystem::remove(grid->temporary_, ec);
  return R::Failure(file.string() +
                    ": OpenCV cannot encode MP4 here (tried fourcc avc1 and mp4v through FFmpeg); "
                    "install an OpenCV built with FFmpeg (libopencv-videoio with libavcodec)");
}

VideoGrid::~VideoGrid() {
  if (!finished_) {
    writer_.release();
    std::error_code ec;
    std::filesystem::remove(temporary_, ec);
  }
}

// Labels and the legend: drawn once, when the error scale is known.
void VideoGrid::DrawStatic() {
  background_ = cv::Mat(layout_.frame, CV_8UC3, kBackground);
  const bool signed_scale = options_.with_reference;
  std::vector<std::string> labels = options_.labels;
  labels.insert(labels.begin(), options_.with_reference ? options_.reference_label : "legend");
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const cv::Rect& r = layout_.tiles[i].label;
    // A long label gets a smaller font before it loses its end.
    int baseline = 0;
    const double scale = cv::getTextSize(labels[i], kFont, 0.5, 1, &baseline).width > r.width - 8 ? 0.37 : 0.5;
    cv::putText(background_, Fitted(labels[i], r.width, scale), cv::Point(r.x + 4, r.y + 16), kFont, scale, kText, 1,
                cv::LINE_AA);
  }
  // The legend: a horizontal colour bar on the error's own scale, its ends
  // and middle labelled, and what the colours mean in words.
  const cv::Rect& legend = layout_.tiles[0].panel;
  const int bar_w = legend.width - 24, bar_h = 16, x0 = legend.x + 12, y0 = legend.y + legend.height / 2 - bar_h;
  cv::Mat values(1, bar_w, CV_64F);
  for (int i = 0; i < bar_w; ++i) {
    const double t = double(i) / std::max(1, bar_w - 1);
    values.at<double>(0, i) = signed_scale ? range_.lo + t * (range_.hi - range_.lo)
                                           : std::pow(10.0, std::log10(range_.lo) +
                                                                t * (std::log10(range_.hi) - std::log10(range_.lo)));
  }
  cv::Mat bar = ColourMap(values, signed_scale ? HeatmapScaling::kSigned : HeatmapScaling::kLog, range_);
  cv::resize(bar, bar, cv::Size(bar_w, bar_h), 0, 0, cv::INTER_NEAREST);
  bar.copyTo(background_(cv::Rect(x0, y0, bar_w, bar_h)));
  const double s = 0.4;
  const int ty = y0 + bar_h + 14;
  if (signed_scale) {
    cv::putText(background_, "error: test - reference", cv::Point(x0, y0 - 8), kFont, s, kText, 1, cv::LINE_AA);
    cv::putText(background_, Tick(range_.lo), cv::Point(x0, ty), kFont, s, kText, 1, cv::LINE_AA);
    cv::putText(background_, "0", cv::Point(x0 + bar_w / 2 - 3, ty), kFont, s, kText, 1, cv::LINE_AA);
    const std::string hi = Tick(range_.hi);
    int baseline = 0;
    const int hi_w = cv::getTextSize(hi, kFont, s, 1, &baseline).width;
    cv::putText(background_, hi, cv::Point(x0 + bar_w - hi_w, ty), kFont, s, kText, 1, cv::LINE_AA);
    cv::putText(background_, "blue: darker   red: brighter", cv::Point(x0, ty + 16), kFont, s, kDim, 1,
                cv::LINE_AA);
  } else {
    cv::putText(background_, "|T(t) - T(t-1)|, log", cv::Point(x0, y0 - 8), kFont, s, kText, 1, cv::LINE_AA);
    char lo[32], hi[32];
    std::snprintf(lo, sizeof lo, "%.2g", range_.lo);
    std::snprintf(hi, sizeof hi, "%.2g", range_.hi);
    cv::putText(background_, lo, cv::Point(x0, ty), kFont, s, kText, 1, cv::LINE_AA);
    int baseline = 0;
    const int hi_w = cv::getTextSize(hi, kFont, s, 1, &baseline).width;
    cv::putText(background_, hi, cv::Point(x0 + bar_w - hi_w, ty), kFont, s, kText, 1, cv::LINE_AA);
  }
}

Status VideoGrid::AddFrame(const std::vector<cv::Mat>& tests, const cv::Mat& reference) {
  if (tests.size() != options_.labels.size())
    return Status::Failure(file_.string() + ": " + std::to_string(tests.size()) + " test frames for " +
                           std::to_string(options_.labels.size()) + " labels");
  if (options_.with_reference == reference.empty())
    return Status::Failure(file_.string() + (reference.empty() ? ": a reference frame is missing"
                                                               : ": a reference frame for a grid without one"));
  const cv::Size size(options_.width, options_.height);
  for (const cv::Mat& t : tests)
    if (t.size() != size || t.type() != CV_32F)
      return Status::Failure(file_.string() + ": every frame must be " + std::to_string(size.width) + "x" +
                             std::to_string(size.height) + " luminance");
  if (!reference.empty() && (reference.size() != size || reference.type() != CV_32F))
    return Status::Failure(file_.string() + ": the reference frame is not the tests' size");
  std::vector<cv::Mat> errors;
  for (std::size_t i = 0; i < tests.size(); ++i) {
    if (options_.with_reference) {
      errors.push_back(tests[i] - reference);
    } else {
      errors.push_back(previous_.empty() ? cv::Mat::zeros(size, CV_32F) : cv::Mat(cv::abs(tests[i] - previous_[i])));
    }
  }
  if (!options_.with_reference) {
    previous_.clear();
    for (const cv::Mat& t : tests) previous_.push_back(t.clone());
  }
  // With a reference the scale is the first frame's; without, the first
  // difference's (frame 0 has none).
  if (!have_range_ && (options_.with_reference || frames_added_ > 0)) {
    const HeatmapScaling scaling = options_.with_reference ? HeatmapScaling::kSigned : HeatmapScaling::kLog;
    for (const cv::Mat& e : errors) {
      const HeatmapRange r = AutoRange(e, cv::Mat(), scaling);
      if (!have_range_ || r.hi > range_.hi) range_ = r;
      have_range_ = true;
    }
    DrawStatic();
  }
  frame_ = have_range_ ? background_.clone() : cv::Mat(layout_.frame, CV_8UC3, kBackground);
  auto place = [&](const cv::Mat& bgr, const cv::Rect& where) {
    cv::Mat big;
    cv::resize(bgr, big, where.size(), 0, 0, cv::INTER_NEAREST);
    big.copyTo(frame_(where));
  };
  std::size_t tile = 1;
  if (options_.with_reference) place(DisplayGrey(reference), layout_.tiles[0].image);
  for (std::size_t i = 0; i < tests.size(); ++i, ++tile) {
    place(DisplayGrey(tests[i]), layout_.tiles[tile].image);
    if (have_range_)
      place(ColourMap(errors[i], options_.with_reference ? HeatmapScaling::kSigned : HeatmapScaling::kLog, range_),
            layout_.tiles[tile].panel);
  }
  for (int k = 0; k < options_.slow; ++k) writer_.write(frame_);
  frames_added_ += 1;
  return Ok();
}

Status VideoGrid::Finish() {
  writer_.release();
  finished_ = true;
  return CommitFile(temporary_, file_);
}

std::string SequenceLabel(const std::filesystem::path& sequence) {
  const std::filesystem::path p = sequence.lexically_normal();
  const std::filesystem::path dir = p.extension() == ".json" ? p.parent_path() : p;
  const std::string name = (dir.filename().empty() ? dir.parent_path() : dir).filename().string();
  return name.empty() ? p.string() : name;
}

Result<GridVideoWritten> WriteGridVideo(const GridSequences& in, const std::filesystem::path& file) {
  using R = Result<GridVideoWritten>;
  if (!in.labels.empty() && in.labels.size() != in.tests.size())
    return R::Failure(file.string() + ": " + std::to_string(in.labels.size()) + " labels for " +
                      std::to_string(in.tests.size()) + " test sequences");
  std::vector<ExrSequence> tests;
  for (const std::filesystem::path& t : in.tests) {
    auto opened = OpenSequence(t, in.request);
    if (!opened) return opened.failure();
    tests.push_back(std::move(*opened));
  }
  if (tests.empty()) return R::Failure(file.string() + ": a video grid needs at least one test sequence");
  std::optional<ExrSequence> reference;
  if (!in.reference.empty()) {
    auto opened = OpenSequence(in.reference, in.request);
    if (!opened) return opened.failure();
    reference = std::move(*opened);
  }
  const ExrSequence& first = tests.front();
  auto check = [&](const ExrSequence& s) -> Status {
    if (s.width != first.width || s.height != first.height)
      return Status::Failure(s.source.string() + " is " + std::to_string(s.width) + "x" + std::to_string(s.height) +
                             " and " + first.source.string() + " " + std::to_string(first.width) + "x" +
                             std::to_string(first.height) + "; a grid's sequences must be the same size");
    if (s.frames.size() != first.frames.size())
      return Status::Failure(s.source.string() + " has " + std::to_string(s.frames.size()) + " frames and " +
                             first.source.string() + " " + std::to_string(first.frames.size()) +
                             "; a grid's sequences must be as long");
    return Ok();
  };
  for (const ExrSequence& s : tests)
    if (Status c = check(s); !c) return c.failure();
  if (reference)
    if (Status c = check(*reference); !c) return c.failure();
  VideoGridOptions options;
  for (std::size_t i = 0; i < tests.size(); ++i)
    options.labels.push_back(in.labels.empty() ? SequenceLabel(in.tests[i]) : in.labels[i]);
  options.with_reference = reference.has_value();
  options.width = first.width, options.height = first.height;
  options.fps = first.fps;
  options.slow = in.slow;
  auto grid = VideoGrid::Open(file, options);
  if (!grid) return grid.failure();
  for (std::size_t f = 0; f < first.frames.size(); ++f) {
    std::vector<cv::Mat> frames;
    for (const ExrSequence& s : tests) {
      auto frame = ReadFrame(s.frames[f], s.layer, s.width, s.height, false);
      if (!frame) return frame.failure();
      frames.push_back(frame->luminance);
    }
    cv::Mat ref;
    if (reference) {
      auto frame = ReadFrame(reference->frames[f], reference->layer, first.width, first.height, false);
      if (!frame) return frame.failure();
      ref = frame->luminance;
    }
    if (Status s = (*grid)->AddFrame(frames, ref); !s) return s.failure();
  }
  if (Status s = (*grid)->Finish(); !s) return s.failure();
  return GridVideoWritten{int((*grid)->layout().tiles.size()), (*grid)->frames_added() * in.slow,
                          (*grid)->fourcc_name()};
}

}  // namespace shimmer::metrics
