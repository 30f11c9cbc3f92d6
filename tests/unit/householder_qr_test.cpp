// Augmented Householder QR with column dropping, against Eigen's ColPivHouseholderQR
// (well-conditioned) and closed forms (rank-deficient blocks).
#include "linalg/householder_qr.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <vector>

namespace mcr {
namespace {

// Column-major rows x cols.
using Cols = std::vector<double>;

std::vector<double> fit_values(const Cols& a, const Cols& b, int rows, int cols, const std::vector<double>& x) {
  std::vector<double> y(std::size_t(rows), 0.0);
  for (int j = 0; j < cols; ++j)
    for (int i = 0; i < rows; ++i) y[std::size_t(i)] += a[std::size_t(j) * rows + i] * x[std::size_t(j)];
  (void)b;
  return y;
}

TEST(HouseholderQr, MatchesEigenOnWellConditionedRandomBlocks) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const int rows = 64 + trial * 48, cols = 1 + trial % 13;
    Cols a(std::size_t(rows) * cols), b(static_cast<std::size_t>(rows));
    for (double& v : a) v = u(rng);
    for (double& v : b) v = 3.0 * u(rng);
    const std::vector<double> x = least_squares(a, b, rows, cols);
    Eigen::Map<const Eigen::MatrixXd> A(a.data(), rows, cols);
    Eigen::Map<const Eigen::VectorXd> B(b.data(), rows);
    const Eigen::VectorXd want = A.colPivHouseholderQr().solve(B);
    for (int j = 0; j < cols; ++j)
      EXPECT_NEAR(x[std::size_t(j)], want(j), 1e-4 * std::max(1.0, std::fabs(want(j)))) << "trial " << trial << " col " << j;
  }
}

TEST(HouseholderQr, SeveralRightHandSidesShareR) {
  const int rows = 100, cols = 5;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Cols m(std::size_t(rows) * (cols + 3));
  for (double& v : m) v = u(rng);
  const Cols copy = m;
  AugmentedQr qr;
  EXPECT_EQ(qr.factorize(m.data(), rows, cols, 3), cols);
  for (int k = 0; k < 3; ++k) {
    std::vector<double> x(cols);
    qr.solve(k, x.data());
    Eigen::Map<const Eigen::MatrixXd> A(copy.data(), rows, cols);
    Eigen::Map<const Eigen::VectorXd> B(copy.data() + std::size_t(cols + k) * rows, rows);
    const Eigen::VectorXd want = A.colPivHouseholderQr().solve(B);
    for (int j = 0; j < cols; ++j) EXPECT_NEAR(x[std::size_t(j)], want(j), 1e-9);
  }
}

// A BMFR-like block: constant column + features; the right-hand side given.
struct Block {
  int rows;
  int cols;
  Cols a;
  Cols b;
};

// Features of a flat wall: normal constant (columns 0 after scaling), position linear
// in pixel x, y (w_x, w_y, w_z all affine in the pixel coordinates: dependent).
Block flat_wall(double eps, unsigned seed) {
  const int side = 32, rows = side * side, cols = 10;
  Block k{rows, cols, Cols(std::size_t(rows) * cols, 0.0), Cols(std::size_t(rows))};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) {
      const int i = y * side + x;
      const double sx = 2.0 * x / (side - 1) - 1.0, sy = 2.0 * y / (side - 1) - 1.0;
      const double f[10] = {1, 0, 0, 0, sx, sy, 0.5 * sx + 0.5 * sy, sx * sx, sy * sy, (0.5 * sx + 0.5 * sy) * (0.5 * sx + 0.5 * sy)};
      for (int j = 0; j < cols; ++j) k.a[std::size_t(j) * rows + i] = f[j] + (j > 0 ? eps * u(rng) : 0.0);
      k.b[std::size_t(i)] = 0.3 + 0.2 * sx - 0.1 * sy;  // true fit: linear
    }
  return k;
}

void expect_all_finite(const std::vector<double>& v) {
  for (double x : v) ASSERT_TRUE(std::isfinite(x));
}

// Up to small feature noise the fit, synthesised with the clean features, is the clean plane.
TEST(HouseholderQr, FlatWallWithSmallNoiseFitsTheCleanPlane) {
  for (double eps : {0.0, 1e-4, 0.01}) {
    Block k = flat_wall(eps, 11);
    const std::vector<double> x = least_squares(k.a, k.b, k.rows, k.cols);
    expect_all_finite(x);
    // Synthesis with the noise-free features.
    const Block clean = flat_wall(0.0, 11);
    const std::vector<double> y = fit_values(clean.a, clean.b, clean.rows, clean.cols, x);
    double err = 0;
    for (int i = 0; i < k.rows; ++i) err = std::max(err, std::fabs(y[std::size_t(i)] - clean.b[std::size_t(i)]));
    EXPECT_LT(err, 1e-2 + 2 * eps) << "eps " << eps;
  }
}

// eps = 1 disturbs the fit (the paper's "visibly too bright and dark blocks"): no closed form,
// but the noisy block has full rank, so no column is dropped and the fit is Eigen's least
// squares on the noisy features: the same fitted values, and the same coefficients.
TEST(HouseholderQr, FullRankNoisyWallIsTheLeastSquaresFit) {
  const Block k = flat_wall(1.0, 11);
  const std::vector<double> x = least_squares(k.a, k.b, k.rows, k.cols);
  Eigen::Map<const Eigen::MatrixXd> A(k.a.data(), k.rows, k.cols);
  Eigen::Map<const Eigen::VectorXd> B(k.b.data(), k.rows);
  const Eigen::VectorXd want = A.colPivHouseholderQr().solve(B);
  for (int j = 0; j < k.cols; ++j) EXPECT_NEAR(x[std::size_t(j)], want(j), 1e-9) << "col " << j;
  const std::vector<double> y = fit_values(k.a, k.b, k.rows, k.cols, x);
  const Eigen::VectorXd fit = A * want;
  double worst = 0, moved = 0;
  for (int i = 0; i < k.rows; ++i) {
    worst = std::max(worst, std::fabs(y[std::size_t(i)] - fit(i)));
    moved = std::max(moved, std::fabs(fit(i)));
  }
  EXPECT_LT(worst, 1e-10);
  EXPECT_GT(moved, 0.1);  // the fit is not trivially zero
}

TEST(HouseholderQr, DropsTheDependentColumnsOfACleanWall) {
  // Without noise the three zero normal columns and the dependent position column are dropped.
  Block k = flat_wall(0.0, 1);
  Cols m = k.a;
  m.insert(m.end(), k.b.begin(), k.b.end());
  AugmentedQr qr;
  const int rank = qr.factorize(m.data(), k.rows, k.cols, 1);
  EXPECT_EQ(rank, 6);  // 1, sx, sy, sx^2, sy^2, sx*sy (hidden in the last square)
  EXPECT_FALSE(qr.kept(1));
  EXPECT_FALSE(qr.kept(6));
}

TEST(HouseholderQr, ConstantAndZeroBlocksGiveTheMean) {
  for (double eps : {0.0, 1e-4, 1.0}) {
    for (double value : {0.0, 0.75, 1e30}) {
      Block k = flat_wall(eps, 5);
      std::fill(k.b.begin(), k.b.end(), value);
      const std::vector<double> x = least_squares(k.a, k.b, k.rows, k.cols);
      expect_all_finite(x);
      const Block clean = flat_wall(0.0, 5);
      const std::vector<double> y = fit_values(clean.a, clean.b, clean.rows, clean.cols, x);
      for (double v : y) ASSERT_NEAR(v, value, 1e-9 * std::max(1.0, value)) << "eps " << eps << " value " << value;
    }
  }
  // All-zero features too.
  Cols a(100 * 10, 0.0), b(100, 0.0);
  for (int i = 0; i < 100; ++i) a[std::size_t(i)] = 1.0;
  const std::vector<double> x = least_squares(a, b, 100, 10);
  for (double v : x) EXPECT_EQ(v, 0.0);
}

TEST(HouseholderQr, OneValidPixelGivesItsValue) {
  for (double eps : {0.0, 1e-4, 1.0}) {
    Cols a(10, 0.0), b{0.42};
    a[0] = 1.0;
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int j = 1; j < 10; ++j) a[std::size_t(j)] = u(rng) * 0.5 + eps * u(rng);
    const std::vector<double> x = least_squares(a, b, 1, 10);
    expect_all_finite(x);
    EXPECT_NEAR(x[0], 0.42, 1e-12);  // only the constant column is kept
    for (int j = 1; j < 10; ++j) EXPECT_EQ(x[std::size_t(j)], 0.0);
  }
}

TEST(HouseholderQr, FewerRowsThanColumnsStaysFinite) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int rows = 1; rows < 10; ++rows) {
    Cols a(std::size_t(rows) * 10), b(static_cast<std::size_t>(rows));
    for (double& v : a) v = u(rng);
    for (double& v : b) v = u(rng);
    const std::vector<double> x = least_squares(a, b, rows, 10);
    expect_all_finite(x);
    // Interpolates the data.
    const std::vector<double> y = fit_values(a, b, rows, 10, x);
    for (int i = 0; i < rows; ++i) EXPECT_NEAR(y[std::size_t(i)], b[std::size_t(i)], 1e-8);
  }
}

TEST(HouseholderQr, TinyNoiseNeverDividesByZero) {
  // Two identical columns plus eps-scaled noise: eps = 0 must drop one, small eps keeps
  // both but stays finite.
  for (double eps : {0.0, 1e-12, 1e-8, 1e-4, 1.0}) {
    const int rows = 256;
    Cols a(std::size_t(rows) * 3), b(static_cast<std::size_t>(rows));
    std::mt19937 rng(2);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int i = 0; i < rows; ++i) {
      const double s = u(rng);
      a[std::size_t(i)] = 1.0;
      a[std::size_t(rows + i)] = s + eps * u(rng);
      a[std::size_t(2 * rows + i)] = s + eps * u(rng);
      b[std::size_t(i)] = 2.0 * s + 1.0;
    }
    const std::vector<double> x = least_squares(a, b, rows, 3);
    expect_all_finite(x);
    EXPECT_NEAR(x[0], 1.0, 1e-3 + eps);
    EXPECT_NEAR(x[1] + x[2], 2.0, 1e-3 + 2 * eps);
  }
}

}  // namespace
}  // namespace mcr
