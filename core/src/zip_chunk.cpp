#include "zip_chunk.h"

#include <libdeflate.h>

#include <emmintrin.h>

#include <new>
#include <string>

namespace shimmer::detail {

namespace {

// Prefix sum of the 16 bytes of x, modulo 256 (Hillis-Steele: four shifted adds).
inline __m128i PrefixBytes(__m128i x) {
  x = _mm_add_epi8(x, _mm_slli_si128(x, 1));
  x = _mm_add_epi8(x, _mm_slli_si128(x, 2));
  x = _mm_add_epi8(x, _mm_slli_si128(x, 4));
  return _mm_add_epi8(x, _mm_slli_si128(x, 8));
}

// Byte 15 of x in all 16 bytes, with SSE2 only (x86-64's baseline; SSSE3's
// pshufb would do it in one step, but then the binary needs a CPU check).
inline __m128i BroadcastLastByte(__m128i x) {
  const __m128i pairs = _mm_unpackhi_epi8(x, x);  // word 7 = byte 15 twice
  return _mm_shuffle_epi32(_mm_shufflehi_epi16(pairs, 0xFF), 0xFF);
}

// OpenEXR's two steps after inflating, fused into one pass over the bytes:
// reconstruct() (d[0] = t[0], d[i] = d[i-1] + t[i] - 128, mod 256) over the
// whole buffer, then interleave() (out[2k] = d[k], out[2k+1] = d[h + k] with
// h = (n + 1) / 2). Unsigned bytes wrap as the C code's do, so the order in
// which the sums are formed changes nothing: d[i] = 128 + sum_{j<=i} (t[j] - 128).
void ReconstructAndInterleave(const uint8_t* t, uint8_t* out, size_t n) {
  const size_t h = (n + 1) / 2, m = n / 2;  // lengths of the even and odd halves
  const uint8_t* a = t;
  const uint8_t* b = t + h;
  // The odd half continues the even half's running sum: d[h - 1].
  uint8_t carry_b = 128;
  {
    size_t i = 0;
    __m128i wide = _mm_setzero_si128();
    for (; i + 16 <= h; i += 16)
      wide = _mm_add_epi64(wide, _mm_sad_epu8(_mm_loadu_si128((const __m128i*)(a + i)), _mm_setzero_si128()));
    uint64_t sum = uint64_t(_mm_cvtsi128_si64(wide)) + uint64_t(_mm_cvtsi128_si64(_mm_unpackhi_epi64(wide, wide)));
    for (; i < h; ++i) sum += a[i];
    carry_b = static_cast<uint8_t>(128 + sum - 128 * h);
  }
  const __m128i minus128 = _mm_set1_epi8(-128);
  __m128i run_a = _mm_set1_epi8(-128);  // 128: d[-1] as the sum's start
  __m128i run_b = _mm_set1_epi8(static_cast<char>(carry_b));
  size_t k = 0;
  for (; k + 16 <= m; k += 16) {
    const __m128i da =
        _mm_add_epi8(PrefixBytes(_mm_add_epi8(_mm_loadu_si128((const __m128i*)(a + k)), minus128)), run_a);
    const __m128i db =
        _mm_add_epi8(PrefixBytes(_mm_add_epi8(_mm_loadu_si128((const __m128i*)(b + k)), minus128)), run_b);
    run_a = BroadcastLastByte(da);
    run_b = BroadcastLastByte(db);
    _mm_storeu_si128((__m128i*)(out + 2 * k), _mm_unpacklo_epi8(da, db));
    _mm_storeu_si128((__m128i*)(out + 2 * k + 16), _mm_unpackhi_epi8(da, db));
  }
  uint8_t last_a = static_cast<uint8_t>(_mm_cvtsi128_si32(run_a));
  uint8_t last_b = static_cast<uint8_t>(_mm_cvtsi128_si32(run_b));
  for (; k < h; ++k) {
    last_a = static_cast<uint8_t>(last_a + a[k] - 128);
    out[2 * k] = last_a;
    if (k < m) {
      last_b = static_cast<uint8_t>(last_b + b[k] - 128);
      out[2 * k + 1] = last_b;
    }
  }
}

const char* Why(libdeflate_result result) {
  switch (result) {
    case LIBDEFLATE_BAD_DATA: return "corrupt zlib stream";
    case LIBDEFLATE_INSUFFICIENT_SPACE: return "zlib stream inflates to more bytes than the chunk holds";
    default: return "zlib stream ends early";
  }
}

}  // namespace

ZipChunkDecoder::ZipChunkDecoder() : inflater_(libdeflate_alloc_decompressor()) {
  if (!inflater_) throw std::bad_alloc();
}

ZipChunkDecoder::~ZipChunkDecoder() { libdeflate_free_decompressor(inflater_); }

Status ZipChunkDecoder::Decode(const void* packed, size_t packed_size, void* unpacked, size_t unpacked_size) {
  if (scratch_.size() < unpacked_size) scratch_.resize(unpacked_size);
  size_t inflated = 0;
  // Like zlib's uncompress(): the stream's own end decides, bytes after it are
  // ignored, and its Adler-32 is checked.
  const libdeflate_result result =
      libdeflate_zlib_decompress(inflater_, packed, packed_size, scratch_.data(), unpacked_size, &inflated);
  if (result != LIBDEFLATE_SUCCESS) return Status::Failure(Why(result));
  if (inflated != unpacked_size)
    return Status::Failure("zlib stream inflates to " + std::to_string(inflated) + " bytes, the chunk holds " +
                           std::to_string(unpacked_size));
  ReconstructAndInterleave(scratch_.data(), static_cast<uint8_t*>(unpacked), unpacked_size);
  return Ok();
}

}  // namespace shimmer::detail
