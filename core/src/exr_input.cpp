#include "shimmer/core/exr_input.h"

#include <ImfFrameBuffer.h>
#include <ImfInputPart.h>
#include <ImfMultiPartInputFile.h>
#include <openexr.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <fstream>
#include <mutex>
#include <new>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "imf_threads.h"
#include "zip_chunk.h"

namespace shimmer {

namespace fs = std::filesystem;

struct ExrInput::Context {
  exr_context_t exr = nullptr;
  std::mutex mutex;
  std::string message;      // OpenEXR's own wording of the first error
  std::vector<char> bytes;  // the whole file, when read in one go

  ~Context() {
    if (exr) exr_finish(&exr);
  }
  void Record(const char* text) {
    std::lock_guard lock(mutex);
    if (message.empty() && text) message = text;
  }
  std::string Describe(exr_result_t code) {
    std::lock_guard lock(mutex);
    return message.empty() ? exr_get_default_error_message(code) : message;
  }
  void Forget() {
    std::lock_guard lock(mutex);
    message.clear();
  }
};

namespace {

// OpenEXR's default handler prints to stderr; keep the text for our one message.
void RecordError(exr_const_context_t exr, exr_result_t, const char* text) {
  void* user = nullptr;
  if (exr_get_user_data(exr, &user) == EXR_ERR_SUCCESS && user) static_cast<ExrInput::Context*>(user)->Record(text);
}

// pread semantics over the file's bytes in memory: a short count at the end.
int64_t ReadFromMemory(exr_const_context_t, void* user, void* buffer, uint64_t size, uint64_t offset,
                       exr_stream_error_func_ptr_t) {
  const std::vector<char>& bytes = static_cast<ExrInput::Context*>(user)->bytes;
  if (offset >= bytes.size()) return 0;
  const uint64_t n = std::min<uint64_t>(size, bytes.size() - offset);
  std::memcpy(buffer, bytes.data() + offset, n);
  return static_cast<int64_t>(n);
}

int64_t MemorySize(exr_const_context_t, void* user) {
  return static_cast<int64_t>(static_cast<ExrInput::Context*>(user)->bytes.size());
}

std::string Unreadable(const fs::path& file, const std::string& why) {
  std::error_code ec;
  if (!fs::exists(file, ec)) return file.string() + ": no such file";
  return file.string() + ": not a readable EXR file (" + why + ")";
}

// Where chunk `index` of a part lies, in pixels from the data window's corner.
struct ChunkPlace {
  exr_chunk_info_t info{};
  int x = 0, y = 0;
};

// OpenEXR 3.1's core API cannot decompress DWAA/DWAB, and it misdecodes the
// partial edge tiles of B44 parts (ExrSequence.ReadsEveryStorageAndCompression
// AsOpenExrDoes caught it); its C++ library reads both right. Such parts go
// through Imf, which decodes line buffers on its own thread pool.
Status ReadWithImf(const fs::path& file, int part, const ExrPartInfo& info,
                   const std::vector<ExrPlaneRequest>& requests) {
  detail::UseImfThreadPool();
  try {
    Imf::MultiPartInputFile in(file.c_str());
    Imf::InputPart input(in, part);
    Imf::FrameBuffer buffer;
    for (const ExrPlaneRequest& r : requests) {
      // Imf addresses pixels in data-window coordinates; shift the base so
      // that the window's corner lands on the plane's first element.
      char* base = reinterpret_cast<char*>(r.plane) -
                   (static_cast<std::ptrdiff_t>(info.min_y) * info.width + info.min_x) * sizeof(float);
      buffer.insert(r.channel, Imf::Slice(Imf::FLOAT, base, sizeof(float), info.width * sizeof(float)));
    }
    input.setFrameBuffer(buffer);
    input.readPixels(info.min_y, info.min_y + info.height - 1);
  } catch (const std::exception& e) {
    return Status::Failure(Unreadable(file, e.what()));
  }
  return Done{};
}

// The pipeline's decompress step for ZIP/ZIPS chunks, in place of OpenEXR's
// default_decompress_chunk (src/lib/OpenEXRCore/decoding.c), whose cases
// before inflating it repeats: an empty chunk, and one stored raw because
// compressing did not make it smaller.
exr_result_t InflateZipChunk(exr_decode_pipeline_t* pipeline) {
  const exr_chunk_info_t& chunk = pipeline->chunk;
  if (chunk.packed_size == 0) return EXR_ERR_SUCCESS;
  if (chunk.packed_size == chunk.unpacked_size) {
    if (pipeline->unpacked_buffer != pipeline->packed_buffer)
      std::memcpy(pipeline->unpacked_buffer, pipeline->packed_buffer, chunk.unpacked_size);
    return EXR_ERR_SUCCESS;
  }
  auto* context = static_cast<ExrInput::Context*>(pipeline->decoding_user_data);
  try {
    // One per thread, kept: its inflater's tables and scratch buffer are
    // then allocated (and their pages faulted in) once, not once per read.
    thread_local detail::ZipChunkDecoder decoder;
    Status s =
        decoder.Decode(pipeline->packed_buffer, chunk.packed_size, pipeline->unpacked_buffer, chunk.unpacked_size);
    if (s) return EXR_ERR_SUCCESS;
    const std::string where = chunk.type == EXR_STORAGE_TILED
                                  ? "tile " + std::to_string(chunk.start_x) + "," + std::to_string(chunk.start_y)
                                  : "scanline " + std::to_string(chunk.start_y);
    context->Record(("ZIP chunk at " + where + ": " + s.error()).c_str());
    return EXR_ERR_CORRUPT_CHUNK;
  } catch (const std::bad_alloc&) {
    // Not through OpenEXR's C frames: they would leak the pipeline's buffers.
    return EXR_ERR_OUT_OF_MEMORY;
  }
}

}  // namespace

Result<ExrInput> ExrInput::Open(const fs::path& file, bool whole_file) {
  using R = Result<ExrInput>;
  ExrInput input;
  input.file_ = file;
  input.context_ = std::make_shared<Context>();
  Context& context = *input.context_;
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  init.error_handler_fn = RecordError;
  init.user_data = &context;
  if (whole_file) {
    std::ifstream in(file, std::ios::binary | std::ios::ate);
    if (!in) return R::Failure(Unreadable(file, "cannot open it"));
    context.bytes.resize(static_cast<size_t>(in.tellg()));
    in.seekg(0);
    if (!in.read(context.bytes.data(), static_cast<std::streamsize>(context.bytes.size())))
      return R::Failure(Unreadable(file, "cannot read it"));
    init.read_fn = ReadFromMemory;
    init.size_fn = MemorySize;
  }
  if (exr_result_t rv = exr_start_read(&context.exr, file.c_str(), &init); rv != EXR_ERR_SUCCESS)
    return R::Failure(Unreadable(file, context.Describe(rv)));

  int count = 0;
  if (exr_result_t rv = exr_get_count(context.exr, &count); rv != EXR_ERR_SUCCESS)
    return R::Failure(Unreadable(file, context.Describe(rv)));
  for (int p = 0; p < count; ++p) {
    ExrPartInfo part;
    const char* name = nullptr;
    if (exr_get_name(context.exr, p, &name) == EXR_ERR_SUCCESS && name) part.name = name;
    exr_storage_t storage = EXR_STORAGE_SCANLINE;
    exr_attr_box2i_t window{};
    const exr_attr_chlist_t* channels = nullptr;
    exr_result_t rv = exr_get_storage(context.exr, p, &storage);
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_data_window(context.exr, p, &window);
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_channels(context.exr, p, &channels);
    if (rv != EXR_ERR_SUCCESS) return R::Failure(Unreadable(file, context.Describe(rv)));
    part.deep = storage == EXR_STORAGE_DEEP_SCANLINE || storage == EXR_STORAGE_DEEP_TILED;
    part.min_x = window.min.x;
    part.min_y = window.min.y;
    part.width = window.max.x - window.min.x + 1;
    part.height = window.max.y - window.min.y + 1;
    // Every chunk has an 8-byte entry in the offset table: a data window
    // that needs more chunks than the file has bytes for is a damaged (or
    // forged) header, and believing it would mean planes of gigabytes.
    int32_t chunks = 0;
    if (exr_get_chunk_count(context.exr, p, &chunks) != EXR_ERR_SUCCESS || chunks <= 0)
      return R::Failure(Unreadable(file, "its header gives no chunk count"));
    std::error_code ec;
    const std::uint64_t size = whole_file ? context.bytes.size() : fs::file_size(file, ec);
    if (!ec && std::uint64_t(chunks) * 8 > size)
      return R::Failure(Unreadable(file, "its header's " + std::to_string(part.width) + "x" +
                                             std::to_string(part.height) + " data window needs " +
                                             std::to_string(chunks) + " chunks, more than its " + std::to_string(size) +
                                             " bytes can hold"));
    for (int c = 0; c < channels->num_channels; ++c) {
      const exr_attr_chlist_entry_t& e = channels->entries[c];
      part.channels.push_back({std::string(e.name.str, e.name.length), e.x_sampling, e.y_sampling});
    }
    input.parts_.push_back(std::move(part));
  }
  // A missing optional attribute (a part without a name) reports through the
  // handler too; that is not an error of the pixels read later.
  context.Forget();
  return input;
}

Status ExrInput::Read(int part, const std::vector<ExrPlaneRequest>& requests, ExrZipInflater inflater) const {
  Context& context = *context_;
  exr_context_t exr = context.exr;
  const ExrPartInfo& info = parts_.at(part);
  const int width = info.width, height = info.height;
  for (const ExrPlaneRequest& r : requests) {
    bool found = false;
    for (const ExrChannelInfo& c : info.channels) found = found || c.name == r.channel;
    if (!found) return Status::Failure(file_.string() + ": no channel " + r.channel);
  }

  exr_compression_t compression = EXR_COMPRESSION_NONE;
  exr_get_compression(exr, part, &compression);
  if (compression == EXR_COMPRESSION_B44 || compression == EXR_COMPRESSION_B44A ||
      compression == EXR_COMPRESSION_DWAA || compression == EXR_COMPRESSION_DWAB)
    return ReadWithImf(file_, part, info, requests);

  // Chunks in file order: scanline blocks, or level-0 tiles row by row.
  exr_storage_t storage = EXR_STORAGE_SCANLINE;
  exr_get_storage(exr, part, &storage);
  const bool tiled = storage == EXR_STORAGE_TILED;
  const bool libdeflate = inflater == ExrZipInflater::kLibdeflate && !info.deep &&
                          (compression == EXR_COMPRESSION_ZIP || compression == EXR_COMPRESSION_ZIPS);
  int32_t block_w = width, block_h = 1;
  exr_result_t rv = tiled ? exr_get_tile_sizes(exr, part, 0, 0, &block_w, &block_h)
                          : exr_get_scanlines_per_chunk(exr, part, &block_h);
  if (rv != EXR_ERR_SUCCESS || block_w <= 0 || block_h <= 0)
    return Status::Failure(Unreadable(file_, context.Describe(rv)));
  const int columns = (width + block_w - 1) / block_w;
  const int chunks = columns * ((height + block_h - 1) / block_h);
  auto locate = [&](int index, ChunkPlace* place) {
    place->x = (index % columns) * block_w;
    place->y = (index / columns) * block_h;
    exr_result_t r = tiled ? exr_read_tile_chunk_info(exr, part, index % columns, index / columns, 0, 0, &place->info)
                           : exr_read_scanline_chunk_info(exr, part, info.min_y + place->y, &place->info);
    if (r == EXR_ERR_SUCCESS && (place->info.width > width - place->x || place->info.height > height - place->y))
      r = EXR_ERR_CORRUPT_CHUNK;  // would write outside the plane
    return r;
  };

  std::atomic<exr_result_t> failure{EXR_ERR_SUCCESS};
  auto decode = [&](const tbb::blocked_range<int>& range) {
    exr_decode_pipeline_t pipeline = EXR_DECODE_PIPELINE_INITIALIZER;
    std::vector<std::vector<float>> scratch;  // unrequested channels land here
    bool initialized = false;
    for (int index = range.begin(); index < range.end() && failure == EXR_ERR_SUCCESS; ++index) {
      ChunkPlace place;
      exr_result_t r = locate(index, &place);
      if (r == EXR_ERR_SUCCESS)
        r = initialized ? exr_decoding_update(exr, part, &place.info, &pipeline)
                        : exr_decoding_initialize(exr, part, &place.info, &pipeline);
      if (r == EXR_ERR_SUCCESS) {
        initialized = true;
        for (int c = 0; c < pipeline.channel_count; ++c) {
          exr_coding_channel_info_t& channel = pipeline.channels[c];
          float* corner = nullptr;
          for (const ExrPlaneRequest& request : requests)
            if (request.channel == channel.channel_name)
              corner = request.plane + static_cast<size_t>(place.y) * width + place.x;
          if (!corner) {
            // Every channel gets a destination: OpenEXR 3.1's specialised
            // half-to-float unpackers write all of a part's channels (a null
            // one crashes), and a uniform layout lets it pick them at all.
            scratch.resize(pipeline.channel_count);
            scratch[c].resize(static_cast<size_t>(width) * block_h);
            corner = scratch[c].data();
          }
          channel.decode_to_ptr = reinterpret_cast<uint8_t*>(corner);
          channel.user_pixel_stride = sizeof(float);
          channel.user_line_stride = static_cast<int32_t>(width * sizeof(float));
          channel.user_data_type = EXR_PIXEL_FLOAT;
          channel.user_bytes_per_element = sizeof(float);
        }
        r = exr_decoding_choose_default_routines(exr, part, &pipeline);
        if (r == EXR_ERR_SUCCESS && libdeflate && pipeline.decompress_fn) {
          pipeline.decompress_fn = InflateZipChunk;
          pipeline.decoding_user_data = &context;
        }
      }
      if (r == EXR_ERR_SUCCESS) r = exr_decoding_run(exr, part, &pipeline);
      if (r != EXR_ERR_SUCCESS) {
        exr_result_t none = EXR_ERR_SUCCESS;
        failure.compare_exchange_strong(none, r);
      }
    }
    if (initialized) exr_decoding_destroy(exr, &pipeline);
  };
  // One stripe per thread: each stripe sets up one decoding pipeline (its
  // scratch buffers), so finer stripes only add set-up (measured 15 % slower
  // at 4 stripes on 2 cores). TBB directly, not cv::parallel_for_: OpenCV runs
  // its loops in an arena of its own, and a read that overlaps an OpenCV loop
  // (metrics_report.cpp) would then wait for a slot there.
  const int stripes = std::max(1, std::min(chunks, tbb::this_task_arena::max_concurrency()));
  tbb::parallel_for(tbb::blocked_range<int>(0, chunks, (chunks + stripes - 1) / stripes), decode,
                    tbb::simple_partitioner());
  if (failure != EXR_ERR_SUCCESS) return Status::Failure(Unreadable(file_, context.Describe(failure)));
  return Done{};
}

}  // namespace shimmer
