#pragma once
// AVX2 (8-wide) versions of the SSE2 loops of BMFR's TAA (bmfr_taa.cpp), steps 1, 2 and 4
// of a row: the same float operations lane for lane (no FMA), so the same results. Each
// runs over [x, w) 8 pixels at a time and returns where it stopped; the callers' SSE2 and
// scalar loops do the rest.
#include <cstddef>
#include <cstdint>

namespace mcr::detail {

bool taa_avx2_available();

// Step 1: column statistics of rows r0, r1, r2 (offsets into the planar R, G, B); cs..mx
// as in bmfr_taa.cpp (already past their padding pixel), cu the centre row.
int taa_stats_avx2(int x, int w, bool ycocg, const float* R, const float* G, const float* B, std::size_t r0,
                   std::size_t r1, std::size_t r2, float* const cs[3], float* const cq[3], float* const mn[3],
                   float* const mx[3], float* const cu[3]);
// Step 2: the clipping box of one channel.
int taa_box_avx2(int x, int w, bool ycocg, float gamma, const float* cs, const float* cq, const float* cmn,
                 const float* cmx, const float* cur, float* blo, float* bhi);
// Step 4: clip, blend, guard.
int taa_clip_avx2(int x, int w, bool ycocg, float a, const float* const hv[3], const float* okr, const float* const lo[3],
                  const float* const hi[3], const float* cr, const float* cg, const float* cb, float* nr, float* ng,
                  float* nb);

// Step 3 with the Catmull-Rom history, a whole row (px, py, inside, outputs: that row):
// two interior pixels at a time in the two 128-bit halves, the rest by
// catmull_rom_planar().
void taa_lookup_cr_avx2(int w, int h, std::size_t n, const float* H, const float* px, const float* py,
                        const std::uint8_t* inside, float* h0, float* h1, float* h2, float* okr);

}  // namespace mcr::detail
