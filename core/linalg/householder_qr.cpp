#include "linalg/householder_qr.h"

#include "util/isa.h"

#include <algorithm>
#include <cmath>

namespace mcr {

namespace {

inline __attribute__((always_inline)) double dot(const double* a, const double* b, int n) {
  // 16 independent partial sums (4 AVX2 / 8 SSE2 registers): the sum is bound by the
  // add latency otherwise.
  double s[16] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  int i = 0;
  for (; i + 16 <= n; i += 16)
    for (int k = 0; k < 16; ++k) s[k] += a[i + k] * b[i + k];
  for (int k = 0; i < n; ++i, ++k) s[k] += a[i] * b[i];
  for (int k = 0; k < 8; ++k) s[k] += s[k + 8];
  for (int k = 0; k < 4; ++k) s[k] += s[k + 4];
  return (s[0] + s[1]) + (s[2] + s[3]);
}

// Norm without overflow for huge entries (1e200 squared would be inf): the plain sum
// of squares first, the scaled one only when that over- or underflows.
inline __attribute__((always_inline)) double safe_norm(const double* a, int n) {
  const double s = dot(a, a, n);
  if (std::isfinite(s) && (s > 1e-280 || s == 0.0)) return std::sqrt(s);
  double m = 0;
  for (int i = 0; i < n; ++i) m = std::max(m, std::fabs(a[i]));
  if (m == 0 || !std::isfinite(m)) return m;
  double t = 0;
  for (int i = 0; i < n; ++i) {
    const double v = a[i] / m;
    t += v * v;
  }
  return m * std::sqrt(t);
}

// 4 doubles, loaded and stored unaligned (GCC vector extension: 2 SSE2 or 1 AVX
// register).
typedef double v4d __attribute__((vector_size(32), aligned(8)));

// f[q] = v . c[q] over n entries, q < nk <= 8: 4-wide partial sums per column, one sweep.
template <int nk>
inline __attribute__((always_inline)) void reflect_dots(const double* v, double* const* c, int n, double* f) {
  v4d s[nk];
  for (int q = 0; q < nk; ++q) s[q] = v4d{0, 0, 0, 0};
  int i = 0;
  for (; i + 4 <= n; i += 4) {
    const v4d vv = *reinterpret_cast<const v4d*>(v + i);
    for (int q = 0; q < nk; ++q) s[q] += vv * *reinterpret_cast<const v4d*>(c[q] + i);
  }
  for (int q = 0; q < nk; ++q) {
    double t = (s[q][0] + s[q][1]) + (s[q][2] + s[q][3]);
    for (int k = i; k < n; ++k) t += v[k] * c[q][k];
    f[q] = t;
  }
}

// c[q] -= f[q] v over n entries, q < nk <= 8, one sweep.
template <int nk>
inline __attribute__((always_inline)) void reflect_update(const double* v, double* const* c, int n, const double* f) {
  int i = 0;
  for (; i + 4 <= n; i += 4) {
    const v4d vv = *reinterpret_cast<const v4d*>(v + i);
    for (int q = 0; q < nk; ++q) {
      v4d* cq = reinterpret_cast<v4d*>(c[q] + i);
      *cq -= f[q] * vv;
    }
  }
  for (; i < n; ++i)
    for (int q = 0; q < nk; ++q) c[q][i] -= f[q] * v[i];
}

}  // namespace

// The Householder updates are long dot products and axpys over the block's rows: built
// for AVX2 as well (util/isa.h; no FMA: the same bits).
MCR_ALWAYS_INLINE int AugmentedQr::factorize_body(double* a, int rows, int features, int rhs, const QrOptions& opt) {
  features_ = features;
  rhs_ = rhs;
  rank_ = 0;
  const int cols = features + rhs;
  kept_.assign(std::size_t(features), 0);
  pivot_col_.clear();
  r_.clear();
  double original_small[64];
  std::vector<double> original_big;
  double* original = original_small;
  if (features > 64) {
    original_big.resize(std::size_t(features));
    original = original_big.data();
  }
  for (int j = 0; j < features; ++j) original[j] = safe_norm(a + std::size_t(j) * rows, rows);
  const double abs_floor = opt.abs_tol * std::sqrt(double(std::max(rows, 1)));

  int r = 0;  // next row to use = number of kept columns so far
  for (int j = 0; j < features && r < rows; ++j) {
    double* v = a + std::size_t(j) * rows + r;
    const int n = rows - r;
    const double norm = safe_norm(v, n);
    if (!(norm > opt.rel_tol * original[j]) || !(norm > abs_floor) || !std::isfinite(norm)) continue;
    // Householder vector v = x + sign(x0) |x| e0, H = I - 2 v v^T / (v^T v).
    const double alpha = v[0] >= 0 ? -norm : norm;
    v[0] -= alpha;
    // v^T v = 2 norm (norm + |x0|) = -2 alpha v0 after the update
    const double vtv = -alpha * v[0];  // half of v^T v: (norm^2 + |x0| norm)
    // Applied to every later column, up to 8 at a time: one sweep for their dot products
    // with v, one for the updates (v read once per sweep, not once per column).
    for (int k0 = j + 1; k0 < cols; k0 += 8) {
      const int nk = std::min(8, cols - k0);
      double* c[8];
      for (int q = 0; q < nk; ++q) c[q] = a + std::size_t(k0 + q) * rows + r;
      double f[8];
      switch (nk) {
#define MCR_REFLECT(K)                                \
  case K:                                             \
    reflect_dots<K>(v, c, n, f);                      \
    for (int q = 0; q < K; ++q) f[q] /= vtv;          \
    reflect_update<K>(v, c, n, f);                    \
    break;
        MCR_REFLECT(1)
        MCR_REFLECT(2)
        MCR_REFLECT(3)
        MCR_REFLECT(4)
        MCR_REFLECT(5)
        MCR_REFLECT(6)
        MCR_REFLECT(7)
        default:
        MCR_REFLECT(8)
#undef MCR_REFLECT
      }
    }
    // Column j now reads (alpha, 0, ..., 0) below row r.
    v[0] = alpha;
    for (int i = 1; i < n; ++i) v[i] = 0;
    kept_[std::size_t(j)] = 1;
    pivot_col_.push_back(j);
    ++r;
  }
  rank_ = r;
  // Copy the used rows of R (row i, all columns) out of the column-major matrix.
  r_.assign(std::size_t(rank_) * cols, 0.0);
  for (int i = 0; i < rank_; ++i)
    for (int k = 0; k < cols; ++k) r_[std::size_t(i) * cols + k] = a[std::size_t(k) * rows + i];
  return rank_;
}
MCR_TARGET_AVX2 int AugmentedQr::factorize_avx2(double* a, int rows, int features, int rhs, const QrOptions& opt) {
  return factorize_body(a, rows, features, rhs, opt);
}
int AugmentedQr::factorize_generic(double* a, int rows, int features, int rhs, const QrOptions& opt) {
  return factorize_body(a, rows, features, rhs, opt);
}
int AugmentedQr::factorize(double* a, int rows, int features, int rhs, const QrOptions& opt) {
  return isa_at_least(Isa::Avx2) ? factorize_avx2(a, rows, features, rhs, opt)
                                 : factorize_generic(a, rows, features, rhs, opt);
}

void AugmentedQr::solve(int k, double* coeffs) const {
  const int cols = features_ + rhs_;
  std::fill(coeffs, coeffs + features_, 0.0);
  // Rows of R are upper triangular in the kept columns: row i has its pivot at
  // pivot_col_[i]; later kept columns are pivot_col_[i+1..].
  for (int i = rank_ - 1; i >= 0; --i) {
    const double* row = r_.data() + std::size_t(i) * cols;
    double s = row[features_ + k];
    for (int m = i + 1; m < rank_; ++m) s -= row[pivot_col_[std::size_t(m)]] * coeffs[pivot_col_[std::size_t(m)]];
    const double d = row[pivot_col_[std::size_t(i)]];
    coeffs[pivot_col_[std::size_t(i)]] = s / d;  // d != 0: dropped columns never get a row
  }
}

std::vector<double> least_squares(const std::vector<double>& a, const std::vector<double>& b, int rows, int cols,
                                  const QrOptions& opt) {
  std::vector<double> m(std::size_t(rows) * (cols + 1));
  std::copy(a.begin(), a.begin() + std::size_t(rows) * cols, m.begin());
  std::copy(b.begin(), b.begin() + rows, m.begin() + std::size_t(rows) * cols);
  AugmentedQr qr;
  qr.factorize(m.data(), rows, cols, 1, opt);
  std::vector<double> x(static_cast<std::size_t>(cols));
  qr.solve(0, x.data());
  return x;
}

}  // namespace mcr
