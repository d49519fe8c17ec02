// The OTNet engine's hot paths allocate nothing once the workspace exists (own binary: it replaces
// the global operator new, and malloc, to count allocations): PredictFromFeatures, ConditionOnStart
// and Generate (with rejection), and Predict (whose map encoding calls OpenCV's distance transform,
// measured here to allocate nothing either once the workspace has seen a map of this size).
// OpenCV runs serially here: the first time a worker of its thread pool (TBB) joins a transform it
// allocates that thread's TLS, at a moment up to the scheduler (3 counts, seen in 3 of 40 runs on
// one machine); encoding_alloc_test bounds that one-time cost with the pool on.

#include <gtest/gtest.h>

#include <random>

#include "inference/otnet/otnet_model.h"
#include "tests/otnet/scoped_cv_threads.h"
#define FORESIGHT_ALLOC_COUNTER_MALLOC  // count Eigen's malloc too
#include "tests/alloc_counter.h"        // replaces operator new: one per binary

namespace foresight::otnet {
namespace {

constexpr int kSide = 40;

BinaryGrid Room(int variant) {
  BinaryGrid g(kSide, kSide);
  for (int r = 0; r < kSide; ++r)
    for (int c = 0; c < kSide; ++c)
      g.at(r, c) = (r == 0 || c == 0 || r == kSide - 1 || c == kSide - 1) ? 1 : 0;
  for (int r = 8 + 5 * variant; r < 14 + 5 * variant; ++r)
    for (int c = 20; c < 24 + variant; ++c) g.at(r, c) = 1;
  return g;
}

Mlp RandomMlp(int in, int hidden, int out, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> n01;
  auto layer = [&](int rows, int cols) {
    DenseLayer l;
    l.weight = Eigen::MatrixXf(rows, cols);
    l.bias = Eigen::VectorXf(rows);
    for (Eigen::Index i = 0; i < l.weight.size(); ++i) l.weight.data()[i] = 0.3f * n01(rng);
    for (Eigen::Index i = 0; i < l.bias.size(); ++i) l.bias[i] = 0.3f * n01(rng);
    return l;
  };
  return Mlp({layer(hidden, in), layer(out, hidden)});
}

// The thesis's sizes: M = 15, Q = 4; a database of 4 maps.
OtnetModel Model(MixtureFamily family) {
  const OtnetHead head{4, 30};
  return OtnetModel(MapEncoder({Room(0), Room(1), Room(2), Room(3)}, 50.0),
                    TrajectoryBasis(15, 100.0, 1e-3), RandomMlp(4, 32, head.Total(), 3), family, 4);
}

// Means that put every component's trajectories inside the room (the network's are random).
void PlaceMixture(const OtnetModel& model, Mixture* m) {
  // All from (5, 5); component 1 ends inside Room(4)'s block, so rejection is exercised.
  const double ends[4][2] = {{32, 8}, {24, 31}, {8, 32}, {32, 20}};
  for (int q = 0; q < m->components(); ++q) {
    Eigen::MatrixX2d line(10, 2);
    for (int i = 0; i < 10; ++i)
      line.row(i) << 5 + (ends[q][0] - 5) * i / 9.0, 5 + (ends[q][1] - 5) * i / 9.0;
    m->mean.row(q) = model.basis().Fit(line).transpose();
  }
  m->scale *= 0.3;
}

TEST(OtnetAlloc, HotPathsAllocateNothingAfterSetUp) {
#ifndef FORESIGHT_COUNTS_MALLOC
  GTEST_SKIP() << "malloc is not counted in this build (neither glibc nor AddressSanitizer)";
#endif
  const ScopedCvThreads serial(0);  // 0: OpenCV runs parallel_for_ bodies in the caller
  for (const MixtureFamily family : {MixtureFamily::kNormal, MixtureFamily::kLaplace}) {
    const OtnetModel model = Model(family);
    OtnetModel::Workspace ws = model.MakeWorkspace(50, 100);
    const BinaryGrid map = Room(4);
    const Eigen::Vector2d start(5.5, 5.25);
    std::mt19937_64 rng(1);
    GenerateOptions options;
    options.count = 50;
    options.points = 100;
    options.max_attempts = 400;

    // Warm-up of every call, then the counted runs.
    model.Predict(map, &ws);
    Eigen::VectorXd phi = ws.phi;
    Mixture placed = ws.mixture;
    PlaceMixture(model, &placed);
    model.ConditionOnStart(placed, start, ComponentSelection::kAll, &ws.conditioned);
    model.Generate(map, ws.conditioned, options, &rng, &ws);

    g_allocations = 0;
    g_counting = true;
    model.Predict(map, &ws);
    g_counting = false;
    const long predict_allocations = g_allocations.load();
    RecordProperty(std::string("predict_allocations_") + ToString(family),
                   static_cast<int>(predict_allocations));
    EXPECT_EQ(predict_allocations, 0) << ToString(family) << ": Predict (encoder + network)";

    GenerateStats stats[4];
    g_allocations = 0;
    g_counting = true;
    model.PredictFromFeatures(phi, &ws, &ws.mixture);
    model.ConditionOnStart(placed, start, ComponentSelection::kAll, &ws.conditioned);
    stats[0] = model.Generate(map, ws.conditioned, options, &rng, &ws);
    model.ConditionOnStart(placed, start, ComponentSelection::kNearest, &ws.conditioned);
    stats[1] = model.Generate(map, ws.conditioned, options, &rng, &ws);
    stats[2] = model.Generate(map, placed, options, &rng, &ws);  // unconditioned
    options.reject_collisions = false;
    stats[3] = model.Generate(map, placed, options, &rng, &ws);
    options.reject_collisions = true;
    g_counting = false;
    EXPECT_EQ(g_allocations.load(), 0) << ToString(family);
    for (const GenerateStats& s : stats) {
      EXPECT_GT(s.accepted, 0);
      EXPECT_EQ(s.accepted + s.rejected, s.attempts);
    }
    EXPECT_GT(stats[0].rejected + stats[1].rejected + stats[2].rejected, 0);  // rejection ran
  }
}

}  // namespace
}  // namespace foresight::otnet
