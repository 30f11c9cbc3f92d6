#include "io/exr_zip.h"

#include <libdeflate.h>

#include <memory>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace mcr::exr_zip {

namespace {

struct FreeDecompressor {
  void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
};
struct FreeCompressor {
  void operator()(libdeflate_compressor* c) const { libdeflate_free_compressor(c); }
};

// One decompressor per thread (chunks decode in parallel); one compressor per thread and level.
libdeflate_decompressor* decompressor() {
  thread_local std::unique_ptr<libdeflate_decompressor, FreeDecompressor> d(libdeflate_alloc_decompressor());
  return d.get();
}

libdeflate_compressor* compressor(int level) {
  thread_local std::unique_ptr<libdeflate_compressor, FreeCompressor> c[10];
  auto& slot = c[level];
  if (!slot) slot.reset(libdeflate_alloc_compressor(level));
  return slot.get();
}

// Scratch for the reordered bytes, kept per thread across chunks.
std::vector<std::uint8_t>& scratch(std::size_t n) {
  thread_local std::vector<std::uint8_t> s;
  if (s.size() < n) s.resize(n);
  return s;
}

// The byte transforms, 16 bytes at a time where SSE2 is there (every x86-64): scalar, they
// cost a third of libdeflate's own time on a frame. Same bytes either way.

// t[i] = t[i-1] + t[i] - 128 for i >= 1: a running sum, mod 256, of t[i] - 128.
void undo_predictor(std::uint8_t* t, std::size_t n) {
  std::size_t i = 1;
#if defined(__SSE2__)
  const __m128i k128 = _mm_set1_epi8(char(-128));
  for (; i + 16 <= n; i += 16) {
    __m128i x = _mm_sub_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(t + i)), k128);
    x = _mm_add_epi8(x, _mm_slli_si128(x, 1));  // prefix sum within the 16 bytes
    x = _mm_add_epi8(x, _mm_slli_si128(x, 2));
    x = _mm_add_epi8(x, _mm_slli_si128(x, 4));
    x = _mm_add_epi8(x, _mm_slli_si128(x, 8));
    x = _mm_add_epi8(x, _mm_set1_epi8(char(t[i - 1])));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(t + i), x);
  }
#endif
  for (; i < n; ++i) t[i] = std::uint8_t(t[i - 1] + t[i] - 128);
}

// out[2k] = even[k], out[2k+1] = odd[k].
void interleave(const std::uint8_t* even, const std::uint8_t* odd, std::uint8_t* out, std::size_t n) {
  std::size_t i = 0;
#if defined(__SSE2__)
  for (; i + 32 <= n; i += 32) {
    const __m128i e = _mm_loadu_si128(reinterpret_cast<const __m128i*>(even + i / 2));
    const __m128i o = _mm_loadu_si128(reinterpret_cast<const __m128i*>(odd + i / 2));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i), _mm_unpacklo_epi8(e, o));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i + 16), _mm_unpackhi_epi8(e, o));
  }
#endif
  for (; i + 1 < n; i += 2) {
    out[i] = even[i / 2];
    out[i + 1] = odd[i / 2];
  }
  if (i < n) out[i] = even[i / 2];
}

// The reverse: even bytes of raw to even[], odd ones to odd[].
void split(const std::uint8_t* raw, std::uint8_t* even, std::uint8_t* odd, std::size_t n) {
  std::size_t i = 0;
#if defined(__SSE2__)
  const __m128i low = _mm_set1_epi16(0x00FF);
  for (; i + 32 <= n; i += 32) {
    const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(raw + i));
    const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(raw + i + 16));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(even + i / 2), _mm_packus_epi16(_mm_and_si128(a, low), _mm_and_si128(b, low)));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(odd + i / 2), _mm_packus_epi16(_mm_srli_epi16(a, 8), _mm_srli_epi16(b, 8)));
  }
#endif
  for (; i + 1 < n; i += 2) {
    even[i / 2] = raw[i];
    odd[i / 2] = raw[i + 1];
  }
  if (i < n) even[i / 2] = raw[i];
}

// d[0] = t[0], d[i] = t[i] - t[i-1] + 128.
void apply_predictor(const std::uint8_t* t, std::uint8_t* d, std::size_t n) {
  d[0] = t[0];
  std::size_t i = 1;
#if defined(__SSE2__)
  const __m128i k128 = _mm_set1_epi8(char(-128));
  for (; i + 16 <= n; i += 16) {
    const __m128i cur = _mm_loadu_si128(reinterpret_cast<const __m128i*>(t + i));
    const __m128i prev = _mm_loadu_si128(reinterpret_cast<const __m128i*>(t + i - 1));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(d + i), _mm_add_epi8(_mm_sub_epi8(cur, prev), k128));
  }
#endif
  for (; i < n; ++i) d[i] = std::uint8_t(t[i] - t[i - 1] + 128);
}

}  // namespace

bool decode(const std::uint8_t* packed, std::size_t packed_size, std::uint8_t* out, std::size_t raw_size) {
  libdeflate_decompressor* d = decompressor();
  if (!d) return false;
  std::uint8_t* t = scratch(raw_size).data();
  std::size_t got = 0;
  if (libdeflate_zlib_decompress(d, packed, packed_size, t, raw_size, &got) != LIBDEFLATE_SUCCESS || got != raw_size)
    return false;
  undo_predictor(t, raw_size);
  interleave(t, t + (raw_size + 1) / 2, out, raw_size);
  return true;
}

std::size_t encode(const std::uint8_t* raw, std::size_t n, int level, std::vector<std::uint8_t>& out) {
  if (n == 0) return 0;
  level = level < 1 ? 1 : level > 9 ? 9 : level;
  libdeflate_compressor* c = compressor(level);
  if (!c) return 0;
  std::uint8_t* t = scratch(2 * n).data();  // the split bytes, then their differences
  split(raw, t, t + (n + 1) / 2, n);
  apply_predictor(t, t + n, n);
  // Only sizes below n are worth keeping: the bound passed makes libdeflate give up early.
  out.resize(n);
  return libdeflate_zlib_compress(c, t + n, n, out.data(), n - 1);  // 0 when it did not fit in n - 1 bytes
}

}  // namespace mcr::exr_zip
