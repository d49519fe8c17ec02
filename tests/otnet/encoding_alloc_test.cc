// MapEncoder's query path (Distances, Encode, Nearest) allocates nothing per call once a workspace
// has been used (own binary: it replaces operator new and malloc to count allocations, in every
// thread). OpenCV's exact distance transform runs on cv::Mat headers over the workspace's buffers
// and allocates nothing itself; but it splits its passes with cv::parallel_for_, and the first time
// a worker thread of OpenCV's pool (TBB here) runs such a body, OpenCV allocates that thread's
// thread-local data (cv::theRNG's TLS slot: 3 operator new, counted 6 times with their malloc).
// Which call a worker first joins is up to the scheduler, so: serial OpenCV -> exactly zero; the
// default pool -> bounded by a one-time cost per thread, far below one allocation per call.

#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <opencv2/core.hpp>
#include <random>

#include "inference/otnet/map_encoding.h"
#include "tests/otnet/scoped_cv_threads.h"
#define FORESIGHT_ALLOC_COUNTER_MALLOC  // count Eigen's and OpenCV's malloc too
#include "tests/alloc_counter.h"        // replaces operator new: one per binary

namespace foresight::otnet {
namespace {

BinaryGrid RandomRooms(std::mt19937_64* rng) {
  BinaryGrid g(40, 40);
  for (int r = 0; r < 40; ++r)
    for (int c = 0; c < 40; ++c) g.at(r, c) = (r < 2 || c < 2 || r >= 38 || c >= 38) ? 1 : 0;
  std::uniform_int_distribution<int> pos(0, 35), size(2, 9);
  for (int k = 0; k < 5; ++k) {
    const int c0 = pos(*rng), r0 = pos(*rng), w = size(*rng), h = size(*rng);
    for (int r = r0; r < std::min(40, r0 + h); ++r)
      for (int c = c0; c < std::min(40, c0 + w); ++c) g.at(r, c) = 1;
  }
  return g;
}

struct Fixture {
  Fixture() {
    std::mt19937_64 rng(1);
    std::vector<BinaryGrid> database;
    for (int m = 0; m < 10; ++m) database.push_back(RandomRooms(&rng));
    encoder = MapEncoder(database, 4.0);
    for (int k = 0; k < 5; ++k) queries.push_back(RandomRooms(&rng));
    ws = encoder.MakeWorkspace();
    distances.resize(encoder.size());
    phi.resize(encoder.size());
  }
  /// Each query through Distances, Encode and Nearest: 15 distance transforms.
  double Exercise() {
    double sink = 0;
    for (const BinaryGrid& q : queries) {
      encoder.Distances(q, &ws, distances);
      encoder.Encode(q, &ws, phi);
      sink += distances.sum() + phi.sum() + encoder.Nearest(q, &ws);
    }
    return sink;
  }
  MapEncoder encoder;
  std::vector<BinaryGrid> queries;
  MapEncoder::Workspace ws;
  Eigen::VectorXd distances, phi;
};

TEST(MapEncoderHotPath, AllocatesNothingAfterWarmUpWithSerialOpenCv) {
  const ScopedCvThreads serial(0);  // 0: OpenCV runs parallel_for_ bodies in the caller
  Fixture fx;
  const double expected = fx.Exercise();  // warm-up
  g_allocations = 0;
  g_counting = true;
  const double sink = fx.Exercise();
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0) << "heap allocations on MapEncoder's query path";
  EXPECT_EQ(sink, expected);
#ifndef FORESIGHT_COUNTS_MALLOC
  GTEST_LOG_(INFO) << "malloc is not counted in this build (only operator new)";
#endif
}

TEST(MapEncoderHotPath, OnlyOneTimePerThreadAllocationsWithOpenCvsPool) {
  Fixture fx;
  const double expected = fx.Exercise();  // warm-up
  const int passes = 20;                  // 300 distance transforms
  g_allocations = 0;
  g_counting = true;
  double sink = 0;
  for (int p = 0; p < passes; ++p) sink += fx.Exercise();
  g_counting = false;
  // OpenCV's per-thread TLS: at most 3 operator new (6 counts) per pool thread, once.
  const long bound = 6L * std::max(1, cv::getNumThreads());
  EXPECT_LE(g_allocations.load(), bound)
      << "allocations grow with the number of calls (300 transforms, " << cv::getNumThreads()
      << " OpenCV threads)";
  std::cout << "[ info     ] OpenCV pool of " << cv::getNumThreads()
            << " threads: " << g_allocations.load()
            << " counted allocations over 300 distance transforms\n";
  EXPECT_EQ(sink, passes * expected);
}

}  // namespace
}  // namespace foresight::otnet
