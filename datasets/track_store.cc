#include "datasets/track_store.h"

#include <cmath>

#include "core/error.h"
#include "core/h5.h"

namespace foresight {

void WriteTrackStore(const std::string& path, const TrackSet& set) {
  std::vector<std::int64_t> offsets{0}, ids;
  std::vector<double> time, xy;
  for (const Track& t : set.tracks) {
    ids.push_back(t.agent_id);
    for (int i = 0; i < t.size(); ++i) {
      time.push_back(t.time[static_cast<std::size_t>(i)]);
      xy.push_back(t.positions(i, 0));
      xy.push_back(t.positions(i, 1));
    }
    offsets.push_back(static_cast<std::int64_t>(time.size()));
  }
  h5::WriteAtomically(path, [&](h5::File* f) {
    f->SetAttr("/", "kind", std::string(kTrackStoreKind));
    f->SetAttr("/", "format_version", kTrackStoreVersion);
    f->SetAttr("/", "source", set.source);
    f->SetAttr("/", "seconds_per_step", set.seconds_per_step);
    f->Write("/tracks/agent_id", ids.data(), {ids.size()});
    f->Write("/tracks/offsets", offsets.data(), {offsets.size()});
    f->Write("/tracks/time", time.data(), {time.size()});
    f->Write("/tracks/xy", xy.data(), {time.size(), 2});
  });
}

TrackSet ReadTrackStore(const std::string& path) {
  h5::File f = h5::File::Open(path);
  FS_THROW_UNLESS(f.HasAttr("/", "kind") && f.GetStringAttr("/", "kind") == kTrackStoreKind, path,
                  ": not a foresight track store (attribute 'kind' != '", kTrackStoreKind, "')");
  const auto version = f.GetIntAttr("/", "format_version");
  FS_THROW_UNLESS(version == kTrackStoreVersion, path, ": track store format_version ", version,
                  " is not supported (expected ", kTrackStoreVersion, ")");
  TrackSet set;
  set.source = f.GetStringAttr("/", "source");
  set.seconds_per_step = f.GetDoubleAttr("/", "seconds_per_step");
  FS_THROW_UNLESS(std::isfinite(set.seconds_per_step) && set.seconds_per_step > 0, path,
                  ": attribute seconds_per_step is ", set.seconds_per_step,
                  "; expected a positive number of seconds");
  const auto ids = f.ReadInt("/tracks/agent_id");
  const auto offsets = f.ReadInt("/tracks/offsets");
  const auto time = f.ReadDouble("/tracks/time");
  const auto xy = f.ReadDouble("/tracks/xy");
  FS_THROW_UNLESS(offsets.Size() == ids.Size() + 1 && offsets.data.front() == 0 &&
                      offsets.data.back() == static_cast<std::int64_t>(time.Size()),
                  path, ": /tracks/offsets is inconsistent with /tracks/agent_id and /tracks/time");
  FS_THROW_UNLESS(xy.shape.size() == 2 && xy.shape[1] == 2 && xy.shape[0] == time.Size(), path,
                  ": /tracks/xy must have shape [", time.Size(), ", 2]");
  const auto num_points = static_cast<std::int64_t>(time.Size());
  for (std::size_t k = 0; k < ids.Size(); ++k) {
    const std::int64_t begin = offsets.data[k], end = offsets.data[k + 1];
    FS_THROW_UNLESS(0 <= begin && begin <= end && end <= num_points, path,
                    ": /tracks/offsets of track ", k, " is [", begin, ", ", end,
                    "), expected 0 <= begin <= end <= ", num_points);
  }
  for (std::size_t k = 0; k < ids.Size(); ++k) {
    Track t;
    t.agent_id = ids.data[k];
    const auto b = static_cast<std::size_t>(offsets.data[k]);
    const auto e = static_cast<std::size_t>(offsets.data[k + 1]);
    t.positions.resize(static_cast<Eigen::Index>(e - b), 2);
    for (std::size_t i = b; i < e; ++i) {
      FS_THROW_UNLESS(std::isfinite(time.data[i]) && std::isfinite(xy.data[2 * i]) &&
                          std::isfinite(xy.data[2 * i + 1]),
                      path, ": non-finite value in track ", k, " at point ", i - b);
      FS_THROW_UNLESS(i == b || time.data[i] > time.data[i - 1], path, ": times of track ", k,
                      " are not increasing at point ", i - b);
      t.time.push_back(time.data[i]);
      t.positions(static_cast<Eigen::Index>(i - b), 0) = xy.data[2 * i];
      t.positions(static_cast<Eigen::Index>(i - b), 1) = xy.data[2 * i + 1];
    }
    set.tracks.push_back(std::move(t));
  }
  return set;
}

}  // namespace foresight
