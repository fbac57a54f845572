// One EXR ZIP/ZIPS chunk decoded with libdeflate instead of zlib.
//
// Why: zlib's inflate was most of `shimmer metrics`'s time on ZIP frames;
// libdeflate (Biggers, https://github.com/ebiggers/libdeflate) inflates a
// whole buffer in one call several times faster (bench/metrics_bench's
// BM_DecodeOnly measures both). What follows inflation is OpenEXR 3.1's own
// reconstruction (src/lib/OpenEXRCore/internal_zip.c, undo_zip_impl): undo
// the byte predictor, then interleave the two halves; byte for byte the same
// as OpenEXR's, which tests/core/exr_zip_test.cpp checks against it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "shimmer/core/result.h"

struct libdeflate_decompressor;

namespace shimmer::detail {

class ZipChunkDecoder {
 public:
  ZipChunkDecoder();
  ~ZipChunkDecoder();
  ZipChunkDecoder(const ZipChunkDecoder&) = delete;
  ZipChunkDecoder& operator=(const ZipChunkDecoder&) = delete;

  // Inflates `packed` (one zlib stream) and reconstructs exactly
  // `unpacked_size` bytes into `unpacked`; fails, saying why, when the stream
  // is damaged or inflates to another size (OpenEXR's EXR_ERR_CORRUPT_CHUNK).
  Status Decode(const void* packed, size_t packed_size, void* unpacked, size_t unpacked_size);

 private:
  libdeflate_decompressor* inflater_ = nullptr;
  std::vector<uint8_t> scratch_;  // the inflated, still predicted bytes
};

}  // namespace shimmer::detail
