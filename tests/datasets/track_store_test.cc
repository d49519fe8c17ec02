#include "datasets/track_store.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/h5.h"
#include "datasets/synthetic_pedestrians.h"
#include "datasets/windows.h"
#include "tests/test_util.h"

namespace foresight {
namespace {

TEST(TrackStore, RoundTripsTracks) {
  testing::TempDir dir;
  SyntheticPedestrianConfig cfg;
  cfg.num_tracks = 20;
  const TrackSet set = GenerateSyntheticPedestrians(cfg);
  const std::string path = dir.File("tracks.h5");
  WriteTrackStore(path, set);
  const TrackSet back = ReadTrackStore(path);
  ASSERT_EQ(back.tracks.size(), set.tracks.size());
  EXPECT_EQ(back.source, set.source);
  for (std::size_t k = 0; k < set.tracks.size(); ++k) {
    EXPECT_EQ(back.tracks[k].agent_id, set.tracks[k].agent_id);
    EXPECT_EQ(back.tracks[k].time, set.tracks[k].time);
    EXPECT_EQ(back.tracks[k].positions, set.tracks[k].positions);
  }
}

TEST(TrackStore, RejectsForeignAndCorruptFiles) {
  testing::TempDir dir;
  {
    h5::File f = h5::File::Create(dir.File("other.h5"));
    f.SetAttr("/", "kind", std::string("something.else"));
  }
  testing::ExpectErrorContains([&] { ReadTrackStore(dir.File("other.h5")); },
                               {"other.h5", "not a foresight track store"});
  SyntheticPedestrianConfig cfg;
  cfg.num_tracks = 200;
  WriteTrackStore(dir.File("t.h5"), GenerateSyntheticPedestrians(cfg));
  testing::Truncate(dir.File("t.h5"), 4000);
  EXPECT_THROW(ReadTrackStore(dir.File("t.h5")), Error);
}

/// A track store of three tracks over five points whose offsets are `offsets`.
void WriteStoreWithOffsets(const std::string& path, const std::vector<std::int64_t>& offsets) {
  const std::vector<std::int64_t> ids{1, 2, 3};
  const std::vector<double> time{0, 0.4, 0.8, 1.2, 1.6}, xy(10, 0.0);
  h5::File f = h5::File::Create(path);
  f.SetAttr("/", "kind", std::string(kTrackStoreKind));
  f.SetAttr("/", "format_version", kTrackStoreVersion);
  f.SetAttr("/", "source", std::string("test"));
  f.SetAttr("/", "seconds_per_step", 0.4);
  f.Write("/tracks/agent_id", ids.data(), {ids.size()});
  f.Write("/tracks/offsets", offsets.data(), {offsets.size()});
  f.Write("/tracks/time", time.data(), {time.size()});
  f.Write("/tracks/xy", xy.data(), {time.size(), 2});
}

// Issue 18, defect 6: a store with a negative or NaN time step is refused, naming the file.
TEST(TrackStore, RejectsANonPositiveTimeStep) {
  testing::TempDir dir;
  SyntheticPedestrianConfig cfg;
  cfg.num_tracks = 3;
  TrackSet set = GenerateSyntheticPedestrians(cfg);
  for (const double step : {-1.0, 0.0, std::nan("")}) {
    set.seconds_per_step = step;
    WriteTrackStore(dir.File("bad.h5"), set);
    testing::ExpectErrorContains([&] { ReadTrackStore(dir.File("bad.h5")); },
                                 {"bad.h5", "seconds_per_step"});
  }
}

TEST(TrackStore, RejectsOffsetsOutsideThePoints) {
  testing::TempDir dir;
  const std::string path = dir.File("offsets.h5");
  WriteStoreWithOffsets(path, {0, 2, 2, 5});
  EXPECT_EQ(ReadTrackStore(path).tracks[1].size(), 0);  // an empty track is allowed
  WriteStoreWithOffsets(path, {0, 7, 3, 5});            // track 0 runs past the last point
  testing::ExpectErrorContains([&] { ReadTrackStore(path); },
                               {path, "/tracks/offsets", "track 0", "[0, 7)"});
  WriteStoreWithOffsets(path, {0, -2, 4, 5});
  testing::ExpectErrorContains([&] { ReadTrackStore(path); }, {path, "track 0", "[0, -2)"});
  WriteStoreWithOffsets(path, {0, 3, 2, 5});
  testing::ExpectErrorContains([&] { ReadTrackStore(path); }, {path, "track 1", "[3, 2)"});
}

TEST(Synthetic, IsDeterministicAndPlausible) {
  SyntheticPedestrianConfig cfg;
  cfg.num_tracks = 50;
  const TrackSet a = GenerateSyntheticPedestrians(cfg), b = GenerateSyntheticPedestrians(cfg);
  ASSERT_EQ(a.tracks.size(), 50u);
  for (std::size_t k = 0; k < a.tracks.size(); ++k) {
    EXPECT_EQ(a.tracks[k].positions, b.tracks[k].positions);
    const auto& p = a.tracks[k].positions;
    for (int i = 1; i < p.rows(); ++i) {
      const double speed = (p.row(i) - p.row(i - 1)).norm() / cfg.seconds_per_step;
      EXPECT_LT(speed, 1.2 * cfg.speed_max + 0.5) << "track " << k;
    }
  }
  cfg.seed = 2;
  EXPECT_NE(GenerateSyntheticPedestrians(cfg).tracks[0].positions, a.tracks[0].positions);
}

TEST(Windows, CutsEveryWindowAndSplitsDeterministically) {
  TrackSet set;
  set.seconds_per_step = 0.4;
  for (int k = 0; k < 3; ++k) {
    Track t;
    t.agent_id = k;
    const int n = 20 + k;
    t.positions.resize(n, 2);
    for (int i = 0; i < n; ++i) {
      t.time.push_back(0.4 * i);
      t.positions.row(i) << i, k;
    }
    set.tracks.push_back(t);
  }
  const WindowSet w = MakeWindows(set, WindowConfig{8, 12, 1});
  EXPECT_EQ(w.size(), 1 + 2 + 3);
  EXPECT_EQ(w.Past(1, 0), Eigen::Vector2d(0, 1));
  EXPECT_EQ(w.Future(5, 11), Eigen::Vector2d(21, 2));
  const TrackSplit s1 = SplitTracks(set, 0.34, 0.34, 7), s2 = SplitTracks(set, 0.34, 0.34, 7);
  EXPECT_EQ(s1.train.tracks.size() + s1.val.tracks.size() + s1.test.tracks.size(), 3u);
  EXPECT_EQ(s1.val.tracks[0].agent_id, s2.val.tracks[0].agent_id);
  set.tracks[0].time[5] += 0.1;  // not uniformly sampled
  testing::ExpectErrorContains(
      [&] {
        MakeWindows(set, WindowConfig{8, 12, 1});
      },
      {"not sampled every 0.4 s"});
}

}  // namespace
}  // namespace foresight
