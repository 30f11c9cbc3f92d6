#include "io/exr_zip.h"

#include <libdeflate.h>

#include <memory>

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

}  // namespace

bool decode(const std::uint8_t* packed, std::size_t packed_size, std::uint8_t* out, std::size_t raw_size) {
  libdeflate_decompressor* d = decompressor();
  if (!d) return false;
  std::uint8_t* t = scratch(raw_size).data();
  std::size_t got = 0;
  if (libdeflate_zlib_decompress(d, packed, packed_size, t, raw_size, &got) != LIBDEFLATE_SUCCESS || got != raw_size)
    return false;
  for (std::size_t i = 1; i < raw_size; ++i) t[i] = std::uint8_t(t[i - 1] + t[i] - 128);
  const std::uint8_t* even = t;
  const std::uint8_t* odd = t + (raw_size + 1) / 2;
  std::size_t i = 0;
  for (; i + 1 < raw_size; i += 2) {
    out[i] = *even++;
    out[i + 1] = *odd++;
  }
  if (i < raw_size) out[i] = *even;
  return true;
}

std::size_t encode(const std::uint8_t* raw, std::size_t n, int level, std::vector<std::uint8_t>& out) {
  if (n == 0) return 0;
  level = level < 1 ? 1 : level > 9 ? 9 : level;
  libdeflate_compressor* c = compressor(level);
  if (!c) return 0;
  std::uint8_t* t = scratch(n).data();
  std::uint8_t* even = t;
  std::uint8_t* odd = t + (n + 1) / 2;
  std::size_t i = 0;
  for (; i + 1 < n; i += 2) {
    *even++ = raw[i];
    *odd++ = raw[i + 1];
  }
  if (i < n) *even = raw[i];
  for (std::size_t k = n - 1; k > 0; --k) t[k] = std::uint8_t(t[k] - t[k - 1] + 128);
  // Only sizes below n are worth keeping: the bound passed makes libdeflate give up early.
  out.resize(n);
  const std::size_t size = libdeflate_zlib_compress(c, t, n, out.data(), n - 1);
  return size;  // 0 when it did not fit in n - 1 bytes
}

}  // namespace mcr::exr_zip
