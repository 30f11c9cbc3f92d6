#pragma once
// The feature columns of BMFR's phase II fit (bmfr_fit.cpp), in bmfr_fit_features.cpp:
// which raw channels each feature set fits, the scaling of a block's column to [-1, 1]
// over its finite pixels, and the AVX2 gather of the default set's block rows.
#include <cstddef>
#include <string>
#include <vector>

#include "image/image.h"

namespace mcr::bmfr {

// Raw (unscaled) feature channels per feature set. The fitted columns are then
// [1, raw scaled to [-1,1] ..., squares of the scaled positions rescaled to [-1,1]].
struct FeatureLayout {
  bool squares = true;            // w^2 columns
  bool albedo = false;            // + albedo RGB
  bool albedo_luminance = false;  // + the albedo's luminance (one column; not with `albedo`)
  bool depth = false;             // + depth
  unsigned dropped = 0;           // bit m: fitted column m left out (constant_columns)
  int raw() const { return 6 + (albedo ? 3 : 0) + (albedo_luminance ? 1 : 0) + (depth ? 1 : 0); }
  int columns() const { return 1 + raw() + (squares ? 3 : 0); }
  // The matrix column of raw channel c.
  int column_of_raw(int c) const { return c < 6 ? 1 + c : 1 + c + (squares ? 3 : 0); }
};

// The fitted columns of passes constant over the whole frame, as FeatureLayout::dropped
// bits, with a note per pass in `notes`. A pass whose finite pixels all lie within
// 0.49e-5 |v| of the first one, channel by channel (kernels/feature_activity.h), has in
// every block a range under 1e-5 of its magnitude, which the fit's column scaling
// turns into a zero column, one the QR then drops (coefficient 0): leaving those
// columns out of every block's matrix gives the same fit (exactly with epsilon = 0;
// with epsilon > 0 the other columns keep their noise, only the noise the zero
// columns would carry is gone), with a smaller QR. A constant position drops its
// squares too. Passes with no finite value are not dropped: their pixels are left
// out of the fit anyway.
// `alb` serves both albedo features (its luminance is constant when its channels are).
unsigned constant_columns(const FeatureLayout& lay, const Image& nrm, const Image& pos, const Image* alb,
                          const Image* dep, int nthreads, std::vector<std::string>& notes);

FeatureLayout layout_of(const std::string& set);  // the `features` parameter's value

// Rec. 709 luminance of an albedo pixel in float (the albedo_luminance feature), summed
// in this order by the scalar and the AVX2 gather alike.
inline float albedo_luminance(float r, float g, float b) { return 0.2126f * r + 0.7152f * g + 0.0722f * b; }

// Min and max of src over the pixels with mask 1 (+inf / -inf when none). Exact: the
// order of a min/max does not matter.
void masked_min_max(const float* src, const float* mask, int np, float& lo, float& hi);

// dst = mask ? clamp((src - lo) * sc - 1, -1, 1) : 0 (src finite where mask is 1).
void scale_masked(const float* src, const float* mask, int np, float lo, float sc, float* dst);

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define MCR_FIT_GATHER_AVX2 1

// The default feature set's gather (normal and position, 3 channels each, and, when arow
// is given, the luminance of an RGB albedo; no other extras) of block row y for pixels
// [0, n8), n8 a multiple of 8, p the first pixel's index in the block: the loop in
// fit_block 8 pixels at a time (the same values and operations; deinterleaved by
// shuffles). Returns the new count of fitted rows.
__attribute__((target("avx2"))) int gather_row_avx2(const float* nrow, const float* prow, const float* arow,
                                                     const float* irow, const float* vrow, int n8, int p,
                                                     std::size_t snp, float* raw, float* fin, float* zp, int* rows,
                                                     int W);
#endif

}  // namespace mcr::bmfr
