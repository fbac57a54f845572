// Reading EXR files through OpenEXR's core C API (openexr.h): the one EXR
// reader of shimmer (frames, masks, tests).
//
// Why not Imf::InputFile: the core API decodes each chunk (a block of
// scanlines, or a tile) independently, so one frame's chunks are spread over
// threads; and its unpacking into float planes is specialised, where the C++
// library copies pixel by pixel through a generic slice loop. On 512x512 ZIP
// frames with 8 float channels it decodes in 18 ms single-threaded against
// 27 ms for Imf::InputFile (bench/metrics_bench measures the whole pass).
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "shimmer/core/result.h"

namespace shimmer {

struct ExrChannelInfo {
  std::string name;  // full name inside its part, e.g. "specular.R"
  int x_sampling = 1, y_sampling = 1;
};

struct ExrPartInfo {
  std::string name;  // empty when the part has no name attribute
  bool deep = false;
  int min_x = 0, min_y = 0, width = 0, height = 0;  // data window
  std::vector<ExrChannelInfo> channels;
};

// One channel to decode as float into a width x height plane (row-major,
// tightly packed), with the data window's corner at plane[0].
struct ExrPlaneRequest {
  std::string channel;
  float* plane = nullptr;
};

// What inflates ZIP and ZIPS chunks: libdeflate (several times faster than
// zlib; the reconstruction after it is OpenEXR's, byte for byte), or
// OpenEXR's own zlib path, kept to compare against in tests and benchmarks.
enum class ExrZipInflater { kLibdeflate, kOpenExr };

class ExrInput {
 public:
  // Reads the headers; fails with a message naming the file. With
  // `whole_file`, the file is read into memory in one go first and the
  // chunks are served from there: OpenEXR otherwise issues one pread per
  // chunk, and an uncompressed file has a chunk per scanline (a system call
  // costs microseconds in a virtual machine).
  static Result<ExrInput> Open(const std::filesystem::path& file, bool whole_file = false);

  const std::vector<ExrPartInfo>& parts() const { return parts_; }

  // Decodes the requested channels of one part (level 0 of a tiled part).
  // Chunks are decoded in parallel. Half and uint channels become float.
  // Other compressions than ZIP/ZIPS always take OpenEXR's own decoders.
  Status Read(int part, const std::vector<ExrPlaneRequest>& requests,
              ExrZipInflater inflater = ExrZipInflater::kLibdeflate) const;

  struct Context;  // the open file and OpenEXR's error text

 private:
  std::filesystem::path file_;
  std::shared_ptr<Context> context_;
  std::vector<ExrPartInfo> parts_;
};

}  // namespace shimmer
