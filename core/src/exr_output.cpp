#include "shimmer/core/exr_output.h"

#include <Imath/half.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>

#include <algorithm>
#include <new>

#include "imf_threads.h"
#include "shimmer/core/atomic_file.h"

namespace shimmer {

namespace fs = std::filesystem;

Status WriteExr(const fs::path& file, int width, int height, const std::vector<ExrPlane>& planes,
                ExrCompression compression) {
  if (planes.empty()) return Status::Failure(file.string() + ": no channels to write", ErrorCode::kInternal);
  if (width <= 0 || height <= 0)
    return Status::Failure(
        file.string() + ": cannot write an empty " + std::to_string(width) + "x" + std::to_string(height) + " image",
        ErrorCode::kInternal);
  // ZIP-compressing the 16-line blocks is most of a frame's write: OpenEXR
  // compresses them on its thread pool when it has one.
  detail::UseImfThreadPool();
  const fs::path temporary = TemporaryPathFor(file);
  const std::size_t pixels = std::size_t(width) * std::size_t(height);
  try {
    Imf::Header header(width, height);
    header.compression() = compression == ExrCompression::kZip ? Imf::ZIP_COMPRESSION : Imf::NO_COMPRESSION;
    Imf::FrameBuffer fb;
    std::vector<std::vector<Imath::half>> halves;
    halves.reserve(planes.size());
    for (const ExrPlane& p : planes) {
      header.channels().insert(p.name, Imf::Channel(p.half ? Imf::HALF : Imf::FLOAT));
      if (p.half) {
        auto& h = halves.emplace_back(pixels);
        for (std::size_t i = 0; i < pixels; ++i) h[i] = Imath::half(p.pixels[i]);
        fb.insert(p.name, Imf::Slice(Imf::HALF, reinterpret_cast<char*>(h.data()), sizeof(Imath::half),
                                     sizeof(Imath::half) * width));
      } else {
        char* base = reinterpret_cast<char*>(const_cast<float*>(p.pixels));
        fb.insert(p.name, Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * width));
      }
    }
    Imf::OutputFile out(temporary.c_str(), header);
    out.setFrameBuffer(fb);
    out.writePixels(height);
  } catch (const std::bad_alloc&) {
    std::error_code ec;
    fs::remove(temporary, ec);
    return Status::Failure(
        file.string() + ": out of memory writing a " + std::to_string(width) + "x" + std::to_string(height) + " EXR",
        ErrorCode::kOutOfMemory);
  } catch (const std::exception& e) {
    std::error_code ec;
    fs::remove(temporary, ec);
    // OpenEXR's text carries the system's reason: 'Failed to write pixel data
    // to image file "<temporary>". No space left on device.' The user knows
    // no temporary name, only the reason.
    std::string why = e.what();
    const std::string named = "\"" + temporary.string() + "\". ";
    if (auto at = why.find(named); at != std::string::npos) why = why.substr(at + named.size());
    if (!why.empty() && why.back() == '.') why.pop_back();
    return Status::Failure(file.string() + ": cannot write EXR (" + why + ")", ErrorCode::kIo);
  }
  return CommitFile(temporary, file);
}

}  // namespace shimmer
