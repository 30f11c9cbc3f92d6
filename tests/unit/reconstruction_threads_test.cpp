// One Reconstruction shared by several threads (pipeline/reconstruction.h): its calls are
// serialised, so N calls from 4 threads give exactly the N results of N serial calls.
// The oracle: every frame is the same static frame, so the k-th call in lock order sees the
// same history as the k-th serial call and returns its bits, whichever thread makes it;
// the multiset of results must equal the serial list. Without the lock the threads share
// bmfr's and the accumulation's buffers and this crashes or mixes results.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <thread>
#include <vector>

#include "feature_filter_testutil.h"
#include "pipeline/reconstruction.h"

namespace mcr {
namespace {

// A static shot: fixed geometry (a plane facing the camera), fixed noisy colour.
Frame static_frame(int w, int h) {
  Frame f = testutil::colour_frame(testutil::random_image(w, h, 3, 7u));
  Image pos(w, h, 3), nrm(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      pos.at(x, y, 0) = float(x) * 0.1f;
      pos.at(x, y, 1) = float(y) * 0.1f;
      pos.at(x, y, 2) = 5.0f + 0.01f * float(x % 3);
      nrm.at(x, y, 2) = 1.0f;
    }
  testutil::add_pass(f, Role::Position, std::move(pos));
  testutil::add_pass(f, Role::Normal, std::move(nrm));
  testutil::add_pass(f, Role::Albedo, testutil::random_image(w, h, 3, 8u, 0.2f, 1.0f));
  return f;
}

std::unique_ptr<Reconstruction> make_session() {
  return std::make_unique<Reconstruction>(make_committed_filter("bmfr", {}), true);  // accumulation + bmfr
}

TEST(ReconstructionThreads, SharedTemporalSessionGivesTheSerialResults) {
  const int threads = 4, per_thread = 8, n = threads * per_thread;
  const Frame frame = static_frame(48, 40);
  ExecOptions one;
  one.nthreads = 1;  // the calls race each other, not their own workers

  std::vector<std::vector<float>> serial;
  {
    auto rec = make_session();
    for (int k = 0; k < n; ++k) serial.push_back(rec->run(frame, one).storage());
  }
  // The history changes the result (else the check below could not tell orders apart).
  ASSERT_NE(serial.front(), serial.back());

  auto shared = make_session();
  std::vector<std::vector<std::vector<float>>> got(threads);
  std::vector<std::string> failures(threads);
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t)
    pool.emplace_back([&, t] {
      try {
        for (int k = 0; k < per_thread; ++k) {
          got[std::size_t(t)].push_back(shared->run(frame, one).storage());
          (void)shared->notes();  // read while other threads run
        }
      } catch (const std::exception& e) {
        failures[std::size_t(t)] = e.what();
      }
    });
  for (std::thread& th : pool) th.join();
  for (const std::string& f : failures) ASSERT_EQ(f, "");

  std::vector<std::vector<float>> all;
  for (auto& g : got)
    for (auto& r : g) {
      for (float v : r) ASSERT_TRUE(std::isfinite(v));
      all.push_back(std::move(r));
    }
  ASSERT_EQ(all.size(), serial.size());
  // Same multiset: sort both (lexicographic order on the bits) and compare.
  std::vector<std::vector<float>> expect = serial;
  std::sort(all.begin(), all.end());
  std::sort(expect.begin(), expect.end());
  EXPECT_TRUE(all == expect) << "the shared session's results are not those of serial calls";

  // reset() from another thread between runs: the next run starts a new history.
  std::thread([&] { shared->reset(); }).join();
  EXPECT_EQ(shared->run(frame, one).storage(), serial.front());
}

}  // namespace
}  // namespace mcr
