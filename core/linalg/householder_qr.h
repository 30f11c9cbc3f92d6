#pragma once
// Small dense least squares by augmented Householder QR (BMFR, Koskela et al. 2019, 4.1):
// the matrix [T | Z] (rows = pixels of a block, M feature columns, K right-hand sides)
// is reduced to its upper triangular R only; Q is never formed. The top-left M x M part
// of R and the top M entries of each right-hand column give the normal system
// R a = r, solved by back substitution per right-hand side.
//
// Rank deficiency: a column whose remaining norm (below the rows already used) is tiny
// relative to its original norm, or absolutely tiny, is DROPPED instead of divided by:
// it gets no Householder step and its coefficient is 0. The kept columns are then a
// full-rank basis of the same span (up to the tolerance), so flat walls, constant or
// all-zero blocks and blocks with fewer rows than columns give finite, minimal fits.
#include <cstddef>
#include <vector>

namespace mcr {

struct QrOptions {
  // A column is dependent when its remaining norm <= rel_tol * its original norm
  // or <= abs_tol * sqrt(rows).
  double rel_tol = 1e-7;
  double abs_tol = 1e-12;
};

// Column-major working matrix: rows x (features + rhs), column j at data[j * rows].
class AugmentedQr {
 public:
  // Factorises in place. `a` holds `rows` x (`features` + `rhs`) values, column-major;
  // it is overwritten (R in its top rows). Returns the number of kept feature columns.
  int factorize(double* a, int rows, int features, int rhs, const QrOptions& opt = {});

  // Coefficients for right-hand side k (size features; 0 for dropped columns).
  void solve(int k, double* coeffs) const;

  int rank() const { return rank_; }
  bool kept(int j) const { return kept_[std::size_t(j)] != 0; }

 private:
  // One body, built generic and AVX2 (util/isa.h picks).
  int factorize_body(double* a, int rows, int features, int rhs, const QrOptions& opt);
  int factorize_generic(double* a, int rows, int features, int rhs, const QrOptions& opt);
  int factorize_avx2(double* a, int rows, int features, int rhs, const QrOptions& opt);
  int features_ = 0, rhs_ = 0, rank_ = 0;
  std::vector<double> r_;    // rank x (features + rhs), row-major: row i of R restricted to used rows
  std::vector<int> pivot_col_;  // for each R row, the feature column it belongs to
  std::vector<unsigned char> kept_;
};

// Convenience: least squares min ||A x - b|| (A rows x cols column-major, b rows) by
// the same augmented QR with column dropping. Returns x (size cols).
std::vector<double> least_squares(const std::vector<double>& a, const std::vector<double>& b, int rows, int cols,
                                  const QrOptions& opt = {});

}  // namespace mcr
