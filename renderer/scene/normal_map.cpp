// Normal maps: the built-in procedural ones, PNG and EXR files, and the mip
// chain of box-filtered moments with its baked Toksvig factors.
#include "shimmer/renderer/normal_map.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <filesystem>
#include <map>
#include <mutex>
#include <span>
#include <tuple>

#include "shimmer/core/atomic_file.h"
#include "shimmer/core/exr_input.h"
#include "shimmer/core/number_text.h"

namespace shimmer::scene {

namespace {

namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;

std::string TexelText(int x, int y) { return "texel (" + std::to_string(x) + ", " + std::to_string(y) + ")"; }

std::string SizeText(std::int64_t width, std::int64_t height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

bool PowerOfTwo(std::int64_t n) { return n >= 1 && (n & (n - 1)) == 0; }

// 64-bit so that a forged PNG header's 2^31 - 1 side is reported, not wrapped.
Status CheckSize(const std::string& name, std::int64_t width, std::int64_t height) {
  if (!PowerOfTwo(width) || !PowerOfTwo(height))
    return Status::Failure(name + ": the map is " + SizeText(width, height) + "; both sides must be powers of two");
  if (width > kMaxNormalMapSide || height > kMaxNormalMapSide)
    return Status::Failure(name + ": the map is " + SizeText(width, height) + "; sides up to " +
                           std::to_string(kMaxNormalMapSide) + " are supported");
  return Ok();
}

// Normalises in place. The error names the first texel (row-major order)
// that cannot be a tangent-space normal.
Status NormaliseNormals(const std::string& name, int width, std::vector<glm::dvec3>& normals) {
  for (std::size_t i = 0; i < normals.size(); ++i) {
    const int x = static_cast<int>(i % width), y = static_cast<int>(i / width);
    glm::dvec3& n = normals[i];
    if (!std::isfinite(n.x) || !std::isfinite(n.y) || !std::isfinite(n.z))
      return Status::Failure(name + ": " + TexelText(x, y) + " has a non-finite normal (" + NumberText(n.x) + ", " +
                             NumberText(n.y) + ", " + NumberText(n.z) + ")");
    const double length = glm::length(n);
    if (!(length > 1e-6))
      return Status::Failure(name + ": " + TexelText(x, y) + " has a zero-length normal (length " + NumberText(length) +
                             ")");
    n /= length;
    if (!(n.z > 0))
      return Status::Failure(name + ": " + TexelText(x, y) + " has a normal that points into the surface (z = " +
                             NumberText(n.z) + " after normalising; tangent-space normals need z > 0)");
  }
  return Ok();
}

// On unit normals with z > 0: scaling x and y by `strength` scales the slope
// n.xy / n.z by it (normal_map.h).
void ApplyStrength(double strength, std::vector<glm::dvec3>& normals) {
  if (strength == 1) return;
  for (glm::dvec3& n : normals) n = glm::normalize(glm::dvec3(strength * n.x, strength * n.y, n.z));
}

// What a texel averages, in double until it is stored: summing 2x2 blocks of
// floats level after level would lose the small differences that the
// variances M - B^2 are made of.
struct Moments {
  glm::dvec3 n{0};
  glm::dvec2 b{0};
  glm::dvec3 m{0};

  static Moments Of(const glm::dvec3& unit) {
    const glm::dvec2 t = glm::dvec2(unit) / unit.z;
    return {unit, t, {t.x * t.x, t.y * t.y, t.x * t.y}};
  }
  void Add(const Moments& o) {
    n += o.n;
    b += o.b;
    m += o.m;
  }
  void Scale(double s) {
    n *= s;
    b *= s;
    m *= s;
  }
  NormalMapTexel Texel() const {
    NormalMapTexel t;
    t.mean_normal = glm::vec3(n);
    t.b = glm::vec2(b);
    t.m = glm::vec3(m);
    return t;
  }
};

// Seed 003 (003_fd5f3d677171d779.txt, "The Wild Hunch"
// and the Toksvig formula before it): "pre-compute the Toksvig Factors from a
// gaussian-filtered version of each MIP level", baked "with a fixed power ...
// around 100", f_t = |N_a| / (|N_a| + s (1 - |N_a|)). The Gaussian (sigma one
// texel of the level, 5x5) runs on the tiled map, so the border wraps. OpenCV's
// filters have no BORDER_WRAP, hence the wrapped copy first; copyMakeBorder
// wraps repeatedly when the level is narrower than the 2-texel border (1x1,
// 2x1, 2x2: the tests check these against a hand-computed wrapped sum).
void BakeToksvig(const cv::Mat& mean_normals, NormalMapLevel& level) {
  constexpr int kRadius = 2;
  constexpr double kSigma = 1;
  cv::Mat padded, blurred;
  cv::copyMakeBorder(mean_normals, padded, kRadius, kRadius, kRadius, kRadius, cv::BORDER_WRAP);
  // The border mode only reaches texels that the crop below drops.
  cv::GaussianBlur(padded, blurred, cv::Size(2 * kRadius + 1, 2 * kRadius + 1), kSigma, kSigma, cv::BORDER_REPLICATE);
  for (int y = 0; y < level.height; ++y)
    for (int x = 0; x < level.width; ++x) {
      const cv::Vec3d f = blurred.at<cv::Vec3d>(y + kRadius, x + kRadius);
      const double r = std::clamp(cv::norm(f), 1e-6, 1.0);
      level.texels[static_cast<std::size_t>(y) * level.width + x].toksvig_ft =
          static_cast<float>(r / (r + kToksvigFixedPower * (1 - r)));
    }
}

// ---- Procedural maps ----

// A height wave sin(2 pi (ku u + kv v) + phase) on the unit tile; integer
// cycles per tile make every map tile seamlessly.
struct Wave {
  int ku, kv;
  double phase;
};

struct ProceduralMap {
  std::string_view name;
  std::vector<Wave> waves;
  bool left_half_only = false;  // bumps on u in [0, 0.5), flat on [0.5, 1)
};

constexpr int kProceduralSide = 256;
// Steepest slope |grad h| of a procedural map at strength 1 (about 19 degrees):
// bumpy enough that a glossy lobe's highlights alias, far from grazing.
constexpr double kProceduralMaxSlope = 0.35;

const std::vector<ProceduralMap>& ProceduralMaps() {
  static const std::vector<ProceduralMap> maps = {
      // Isotropic bumps: six waves of 8.5-11.2 cycles per tile in spread directions.
      {"bumps", {{8, 3, 0.3}, {-3, 9, 1.7}, {10, -4, 4.1}, {5, 10, 2.6}, {-11, 2, 5.3}, {7, -7, 0.9}}},
      // The same kind of bumps at 33-47 cycles per tile (5-8 texels a cycle).
      {"bumps-fine", {{36, 10, 0.3}, {-12, 40, 1.7}, {44, -15, 4.1}, {20, 30, 2.6}, {-33, 5, 5.3}, {25, -35, 0.9}}},
      // Brushed ridges: 16-64 cycles along u, at most one cycle along v, so the
      // slope spreads about 1000 times more along u than along v.
      {"ridges", {{16, 1, 0.4}, {23, 0, 2.1}, {31, -1, 4.4}, {40, 1, 1.2}, {52, 0, 5.0}, {64, -1, 3.3}}},
      // "bumps-fine" on u in [0, 0.5) (fading in and out over 1/8 of the tile),
      // exactly flat on [0.5, 1): one area where gloss from distance alone is wrong.
      {"patches", {{36, 10, 0.3}, {-12, 40, 1.7}, {44, -15, 4.1}, {20, 30, 2.6}, {-33, 5, 5.3}, {25, -35, 0.9}}, true},
  };
  return maps;
}

// (h, dh/du, dh/dv) of the sum of waves, each with slope amplitude 1 (height
// amplitude 1 / (2 pi |k|)) so every frequency adds alike to the slope spread.
glm::dvec3 WaveSum(std::span<const Wave> waves, double u, double v) {
  glm::dvec3 sum(0);
  for (const Wave& w : waves) {
    const double k = std::hypot(w.ku, w.kv);
    const double arg = 2 * kPi * (w.ku * u + w.kv * v) + w.phase;
    sum += glm::dvec3(std::sin(arg) / (2 * kPi * k), std::cos(arg) * w.ku / k, std::cos(arg) * w.kv / k);
  }
  return sum;
}

double TexelCentre(int i) { return (i + 0.5) / kProceduralSide; }

// The height scale that makes the steepest texel centre's slope kProceduralMaxSlope.
double HeightScale(std::span<const Wave> waves) {
  double steepest = 0;
  for (int y = 0; y < kProceduralSide; ++y)
    for (int x = 0; x < kProceduralSide; ++x) {
      const glm::dvec3 s = WaveSum(waves, TexelCentre(x), TexelCentre(y));
      steepest = std::max(steepest, std::hypot(s.y, s.z));
    }
  return kProceduralMaxSlope / steepest;
}

// Smoothstep and its derivative: C1, so the normals of "patches" are continuous.
double Smoothstep(double t) { return t * t * (3 - 2 * t); }
double SmoothstepSlope(double t) { return 6 * t * (1 - t); }

// (w, dw/du) of the "patches" mask: 1 on [1/8, 3/8], 0 on [1/2, 1), smooth
// ramps between. w and w' are 0 at u = 0 and u = 1, so the mask tiles.
glm::dvec2 LeftHalfMask(double u) {
  constexpr double kRamp = 0.125;
  if (u < kRamp) return {Smoothstep(u / kRamp), SmoothstepSlope(u / kRamp) / kRamp};
  if (u <= 0.5 - kRamp) return {1, 0};
  if (u < 0.5) return {Smoothstep((0.5 - u) / kRamp), -SmoothstepSlope((0.5 - u) / kRamp) / kRamp};
  return {0, 0};
}

std::vector<glm::dvec3> ProceduralNormals(const ProceduralMap& map) {
  const double scale = HeightScale(map.waves);
  std::vector<glm::dvec3> normals(static_cast<std::size_t>(kProceduralSide) * kProceduralSide);
  for (int y = 0; y < kProceduralSide; ++y)
    for (int x = 0; x < kProceduralSide; ++x) {
      const double u = TexelCentre(x), v = TexelCentre(y);
      const glm::dvec3 s = WaveSum(map.waves, u, v);
      glm::dvec2 gradient(s.y, s.z);
      if (map.left_half_only) {
        // h = w(u) h0: dh/du = w' h0 + w dh0/du.
        const glm::dvec2 w = LeftHalfMask(u);
        gradient = glm::dvec2(w.y * s.x + w.x * s.y, w.x * s.z);
      }
      gradient *= scale;
      normals[static_cast<std::size_t>(y) * kProceduralSide + x] =
          glm::normalize(glm::dvec3(-gradient.x, -gradient.y, 1));
    }
  return normals;
}

// ---- Files ----

struct FileNormals {
  int width = 0, height = 0;
  std::vector<glm::dvec3> normals;
};

std::uint32_t BigEndian32(const unsigned char* p) {
  return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) | std::uint32_t(p[3]);
}

Result<FileNormals> ReadPng(const std::string& file) {
  using R = Result<FileNormals>;
  errno = 0;
  std::ifstream in(file, std::ios::binary);
  if (!in) return R::Failure(file + ": cannot read (" + SystemReason(errno) + ")", ErrorCode::kIo);
  // Signature and IHDR: the size is checked before decoding, so that a forged
  // header cannot make the decoder allocate gigabytes.
  std::array<unsigned char, 24> head{};
  in.read(reinterpret_cast<char*>(head.data()), head.size());
  constexpr std::array<unsigned char, 8> kSignature = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (in.gcount() < static_cast<std::streamsize>(head.size()) ||
      !std::equal(kSignature.begin(), kSignature.end(), head.begin()) ||
      std::string_view(reinterpret_cast<const char*>(head.data()) + 12, 4) != "IHDR")
    return R::Failure(file + ": not a PNG file (no PNG signature and header)");
  if (Status s = CheckSize(file, BigEndian32(&head[16]), BigEndian32(&head[20])); !s) return s.failure();

  cv::Mat image;
  try {
    image = cv::imread(file, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    return R::Failure(file + ": not a readable PNG file (" + e.what() + ")");
  }
  if (image.empty()) return R::Failure(file + ": not a readable PNG file (corrupt or truncated)");
  if (image.depth() != CV_8U && image.depth() != CV_16U)
    return R::Failure(file + ": has " + std::to_string(8 * image.elemSize1()) +
                      "-bit samples; a PNG normal map needs 8 or 16 bits per channel");
  if (image.channels() != 3 && image.channels() != 4)
    return R::Failure(file + ": has " + std::to_string(image.channels()) +
                      (image.channels() == 1 ? " channel" : " channels") +
                      "; a normal map needs 3 (RGB = xyz) or 4 (RGBA, alpha ignored)");
  if (Status s = CheckSize(file, image.cols, image.rows); !s) return s.failure();

  FileNormals out{image.cols, image.rows, {}};
  out.normals.reserve(static_cast<std::size_t>(image.cols) * image.rows);
  const double max = image.depth() == CV_8U ? 255 : 65535;
  const int channels = image.channels();
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) {
      // OpenCV's order is BGR(A): x = R, y = G, z = B.
      double bgr[3];
      for (int c = 0; c < 3; ++c)
        bgr[c] = image.depth() == CV_8U ? image.ptr<std::uint8_t>(y)[x * channels + c]
                                        : image.ptr<std::uint16_t>(y)[x * channels + c];
      out.normals.emplace_back(2 * bgr[2] / max - 1, 2 * bgr[1] / max - 1, 2 * bgr[0] / max - 1);
    }
  return out;
}

Result<FileNormals> ReadExr(const std::string& file) {
  using R = Result<FileNormals>;
  auto in = ExrInput::Open(file, /*whole_file=*/true);
  if (!in) return in.failure();
  if (in->parts().empty()) return R::Failure(file + ": the EXR file has no image part");
  const ExrPartInfo& part = in->parts().front();
  if (part.deep) return R::Failure(file + ": a deep EXR image; a normal map needs flat R, G, B channels");
  std::string missing;
  for (const char* name : {"R", "G", "B"}) {
    auto c = std::find_if(part.channels.begin(), part.channels.end(),
                          [&](const ExrChannelInfo& info) { return info.name == name; });
    if (c == part.channels.end())
      missing += std::string(missing.empty() ? "" : ", ") + name;
    else if (c->x_sampling != 1 || c->y_sampling != 1)
      return R::Failure(file + ": channel " + name + " is subsampled; a normal map needs full-resolution R, G, B");
  }
  if (!missing.empty())
    return R::Failure(file + ": no " + missing + " channel" + (missing.size() > 1 ? "s" : "") +
                      "; a normal map needs R, G, B (x, y, z)");
  if (Status s = CheckSize(file, part.width, part.height); !s) return s.failure();

  const std::size_t count = static_cast<std::size_t>(part.width) * part.height;
  std::vector<float> r(count), g(count), b(count);
  if (Status s = in->Read(0, {{"R", r.data()}, {"G", g.data()}, {"B", b.data()}}); !s) return s.failure();
  FileNormals out{part.width, part.height, {}};
  out.normals.reserve(count);
  for (std::size_t i = 0; i < count; ++i) out.normals.emplace_back(r[i], g[i], b[i]);
  return out;
}

Result<NormalMap> LoadFileMap(const std::string& file, double strength) {
  using R = Result<NormalMap>;
  std::error_code ec;
  if (!fs::exists(file, ec)) return R::Failure(file + ": no such file");
  if (fs::is_directory(file, ec)) return R::Failure(file + ": is a directory, expected a normal map (.png or .exr)");
  std::string ext = fs::path(file).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext != ".png" && ext != ".exr")
    return R::Failure(file +
                      ": not a normal map format shimmer reads (.png with 8 or 16 bits per channel, or .exr "
                      "with R, G, B)");
  // Here for both formats: OpenEXR's reader reports a file it cannot open as unreadable content.
  errno = 0;
  if (!std::ifstream(file, std::ios::binary))
    return R::Failure(file + ": cannot read (" + SystemReason(errno) + ")", ErrorCode::kIo);
  Result<FileNormals> read = ext == ".png" ? ReadPng(file) : ReadExr(file);
  if (!read) return read.failure();
  // Checked before the strength: at strength 0 a sideways normal (z = 0)
  // would otherwise pass as flat.
  if (Status s = NormaliseNormals(file, read->width, read->normals); !s) return s.failure();
  ApplyStrength(strength, read->normals);
  return BuildNormalMap(file, read->width, read->height, read->normals);
}

std::string KnownNames() {
  std::string names;
  for (std::string_view n : ProceduralNormalMapNames()) names += (names.empty() ? "" : ", ") + std::string(n);
  return names;
}

}  // namespace

std::vector<std::string_view> ProceduralNormalMapNames() {
  std::vector<std::string_view> names;
  for (const ProceduralMap& m : ProceduralMaps()) names.push_back(m.name);
  return names;
}

Result<NormalMap> BuildNormalMap(std::string name, int width, int height, const std::vector<glm::dvec3>& normals) {
  using R = Result<NormalMap>;
  if (Status s = CheckSize(name, width, height); !s) return s.failure();
  const std::size_t count = static_cast<std::size_t>(width) * height;
  if (normals.size() != count)
    return R::Failure(name + ": " + std::to_string(normals.size()) + " normals for a " + SizeText(width, height) +
                      " map (" + std::to_string(count) + " needed)");
  std::vector<glm::dvec3> unit = normals;
  if (Status s = NormaliseNormals(name, width, unit); !s) return s.failure();

  NormalMap map;
  map.name = std::move(name);
  NormalMapLevel base{width, height, std::vector<NormalMapTexel>(count)};
  for (std::size_t i = 0; i < count; ++i) base.texels[i] = Moments::Of(unit[i]).Texel();
  static_assert(sizeof(glm::dvec3) == 3 * sizeof(double), "viewed in place as a CV_64FC3 matrix");
  BakeToksvig(cv::Mat(height, width, CV_64FC3, unit.data()), base);
  map.levels.push_back(std::move(base));

  // Level k + 1 from level k's double moments (level 0's are derived from the
  // unit normals on the fly: a stored double level 0 would be 1 GiB at 4096^2).
  std::vector<Moments> previous;
  int w = width, h = height;
  while (w > 1 || h > 1) {
    const int step_x = w > 1 ? 2 : 1, step_y = h > 1 ? 2 : 1;
    const int next_w = w / step_x, next_h = h / step_y;
    std::vector<Moments> next(static_cast<std::size_t>(next_w) * next_h);
    cv::Mat mean_normals(next_h, next_w, CV_64FC3);
    NormalMapLevel level{next_w, next_h, std::vector<NormalMapTexel>(next.size())};
    for (int y = 0; y < next_h; ++y)
      for (int x = 0; x < next_w; ++x) {
        Moments sum;
        for (int dy = 0; dy < step_y; ++dy)
          for (int dx = 0; dx < step_x; ++dx) {
            const std::size_t i = static_cast<std::size_t>(y * step_y + dy) * w + (x * step_x + dx);
            sum.Add(previous.empty() ? Moments::Of(unit[i]) : previous[i]);
          }
        sum.Scale(1.0 / (step_x * step_y));
        const std::size_t j = static_cast<std::size_t>(y) * next_w + x;
        next[j] = sum;
        level.texels[j] = sum.Texel();
        mean_normals.at<cv::Vec3d>(y, x) = cv::Vec3d(sum.n.x, sum.n.y, sum.n.z);
      }
    BakeToksvig(mean_normals, level);
    map.levels.push_back(std::move(level));
    previous = std::move(next);
    w = next_w;
    h = next_h;
  }
  return map;
}

Result<std::shared_ptr<const NormalMap>> LoadNormalMap(const NormalMapSource& source) {
  using R = Result<std::shared_ptr<const NormalMap>>;
  const bool from_file = !source.file.empty(), procedural = !source.procedural.empty();
  if (from_file && procedural)
    return R::Failure("normal map: both a file (" + source.file + ") and a procedural map (" + source.procedural +
                      ") given; give one");
  if (!from_file && !procedural)
    return R::Failure("normal map: neither a file nor a procedural map given (procedural: " + KnownNames() + ")");
  const std::string& label = from_file ? source.file : source.procedural;
  if (!std::isfinite(source.strength) || source.strength < 0 || source.strength > 10)
    return R::Failure(label + ": normal map strength " + NumberText(source.strength) + " is outside [0, 10]");
  const ProceduralMap* recipe = nullptr;
  if (procedural) {
    for (const ProceduralMap& m : ProceduralMaps())
      if (m.name == source.procedural) recipe = &m;
    if (!recipe)
      return R::Failure("unknown procedural normal map '" + source.procedural + "' (known: " + KnownNames() + ")");
  }

  // Keyed by the path as given (the caller resolves it) with the file's size
  // and modification time: a file is read once per process unless it is
  // rewritten meanwhile, and then its new texels are what a job id hashes.
  using Key = std::tuple<std::string, std::string, double, std::uintmax_t, std::int64_t>;
  static std::mutex mutex;
  static std::map<Key, std::shared_ptr<const NormalMap>> cache;
  std::uintmax_t size = 0;
  std::int64_t modified = 0;
  if (from_file) {
    std::error_code ec;
    size = std::filesystem::file_size(source.file, ec);
    if (ec) size = 0;
    const auto time = std::filesystem::last_write_time(source.file, ec);
    if (!ec) modified = std::int64_t(time.time_since_epoch().count());
  }
  const Key key{source.file, source.procedural, source.strength, size, modified};
  {
    std::lock_guard lock(mutex);
    if (auto found = cache.find(key); found != cache.end()) return found->second;
  }
  // Built outside the lock (a 4096^2 file takes seconds); when two threads
  // build the same map, the first to finish is kept and both get it.
  auto build = [&]() -> Result<NormalMap> {
    if (!recipe) return LoadFileMap(source.file, source.strength);
    std::vector<glm::dvec3> normals = ProceduralNormals(*recipe);
    ApplyStrength(source.strength, normals);
    return BuildNormalMap(std::string(recipe->name), kProceduralSide, kProceduralSide, normals);
  };
  Result<NormalMap> built = build();
  if (!built) return built.failure();
  std::lock_guard lock(mutex);
  auto [entry, inserted] = cache.try_emplace(key, std::make_shared<const NormalMap>(std::move(*built)));
  return entry->second;
}

}  // namespace shimmer::scene
