#include "linalg/householder_qr.h"

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

}  // namespace

// The Householder updates are long dot products and axpys over the block's rows: built
// for AVX2 as well where the compiler and loader support it (picked at load time).
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#define MCR_QR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define MCR_QR_CLONES
#endif

MCR_QR_CLONES
int AugmentedQr::factorize(double* a, int rows, int features, int rhs, const QrOptions& opt) {
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
    for (int k = j + 1; k < cols; ++k) {
      double* c = a + std::size_t(k) * rows + r;
      const double f = dot(v, c, n) / vtv;
      for (int i = 0; i < n; ++i) c[i] -= f * v[i];
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
