#include "datasets/crowd_replay.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <random>
#include <sstream>

#include "core/error.h"
#include "core/parse.h"
#include "datasets/data_root.h"

namespace foresight {
namespace {

struct Sample {
  double t, x, y;
  int line;
};

double Field(const std::string& text, const std::string& path, int line, const char* what) {
  std::string trimmed = text;
  while (!trimmed.empty() && std::isspace(static_cast<unsigned char>(trimmed.back())))
    trimmed.pop_back();
  std::size_t start = 0;
  while (start < trimmed.size() && std::isspace(static_cast<unsigned char>(trimmed[start])))
    ++start;
  trimmed = trimmed.substr(start);
  const std::optional<double> v = ParseDouble(trimmed);
  FS_THROW_UNLESS(v && std::isfinite(*v), path, ":", line, ": ", what, " '", trimmed,
                  "' is not a finite number");
  return *v;
}

/// Sorted samples per id -> raw tracks; a time given twice for one id is an error.
TrackSet ToTracks(std::map<std::int64_t, std::vector<Sample>> by_id, const std::string& path,
                  double nominal_step) {
  TrackSet set;
  set.source = path;
  set.seconds_per_step = nominal_step;
  for (auto& [id, samples] : by_id) {
    std::stable_sort(samples.begin(), samples.end(),
                     [](const Sample& a, const Sample& b) { return a.t < b.t; });
    Track tr;
    tr.agent_id = id;
    tr.positions.resize(static_cast<Eigen::Index>(samples.size()), 2);
    for (std::size_t i = 0; i < samples.size(); ++i) {
      if (i > 0)
        FS_THROW_UNLESS(samples[i].t > samples[i - 1].t, path, ":", samples[i].line, ": agent ", id,
                        " has two samples at time ", samples[i].t, " (also line ",
                        samples[i - 1].line, ")");
      tr.time.push_back(samples[i].t);
      tr.positions(static_cast<Eigen::Index>(i), 0) = samples[i].x;
      tr.positions(static_cast<Eigen::Index>(i), 1) = samples[i].y;
    }
    set.tracks.push_back(std::move(tr));
  }
  FS_THROW_UNLESS(!set.tracks.empty(), path, ": no tracks");
  return set;
}

OccupancyRaster EmptyRaster(const Eigen::Vector4d& extent, double resolution) {
  FS_THROW_UNLESS(std::isfinite(resolution) && resolution > 0,
                  "occupancy raster: resolution must be positive, got ", resolution);
  FS_THROW_UNLESS(extent[1] > extent[0] && extent[3] > extent[2],
                  "occupancy raster: empty extent [", extent[0], ", ", extent[1], ", ", extent[2],
                  ", ", extent[3], "]");
  OccupancyRaster r;
  r.extent = extent;
  r.resolution = resolution;
  const auto cols =
      static_cast<Eigen::Index>(std::ceil((extent[1] - extent[0]) / resolution - 1e-9));
  const auto rows =
      static_cast<Eigen::Index>(std::ceil((extent[3] - extent[2]) / resolution - 1e-9));
  r.cells.setZero(rows, cols);
  return r;
}

/// Marks the cell of world point (x, y) occupied (ignored outside the raster).
void Mark(OccupancyRaster* r, double x, double y) {
  const double c = std::floor((x - r->extent[0]) / r->resolution);
  const double row = std::floor((r->extent[3] - y) / r->resolution);
  if (c < 0 || row < 0 || c >= r->cells.cols() || row >= r->cells.rows()) return;
  r->cells(static_cast<Eigen::Index>(row), static_cast<Eigen::Index>(c)) = 1;
}

cv::Mat ReadGrey(const std::string& path) {
  FS_THROW_UNLESS(std::filesystem::exists(path), path, ": obstacle image not found");
  cv::Mat img = cv::imread(path, cv::IMREAD_GRAYSCALE);
  FS_THROW_UNLESS(!img.empty() && img.type() == CV_8UC1, path, ": cannot read as an 8-bit image");
  return img;
}

/// Ids and frames are integers; beyond 2^53 a double no longer holds every integer (and the
/// conversions to integer types would overflow).
constexpr double kMaxInteger = 9007199254740992.0;  // 2^53

}  // namespace

TrackSet ReadThorTracks(const std::string& path) {
  std::ifstream in(path);
  FS_THROW_UNLESS(in.good(), path, ": cannot open THOR csv");
  std::map<std::int64_t, std::vector<Sample>> by_id;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) f.push_back(cell);
    FS_THROW_UNLESS(
        f.size() == 6, path, ":", number,
        ": expected 6 comma-separated fields (time, person_id, x, y, velocity, motion_angle), got ",
        f.size());
    const double t = Field(f[0], path, number, "time");
    const double id = Field(f[1], path, number, "person_id");
    FS_THROW_UNLESS(id == std::floor(id) && std::abs(id) <= kMaxInteger, path, ":", number,
                    ": person_id '", f[1], "' is not an integer in [-2^53, 2^53]");
    by_id[static_cast<std::int64_t>(id)].push_back(
        {t, Field(f[2], path, number, "x"), Field(f[3], path, number, "y"), number});
  }
  return ToTracks(std::move(by_id), path, 0.4);
}

TrackSet ReadEthObsmat(const std::string& path, double annotation_step) {
  FS_THROW_UNLESS(annotation_step > 0, "ReadEthObsmat: annotation_step must be positive");
  std::ifstream in(path);
  FS_THROW_UNLESS(in.good(), path, ": cannot open ETH obsmat file");
  struct Row {
    double frame;
    std::int64_t id;
    double x, y;
    int line;
  };
  std::vector<Row> rows;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    std::istringstream is(line);
    std::vector<std::string> f;
    for (std::string t; is >> t;) f.push_back(t);
    if (f.empty()) continue;
    FS_THROW_UNLESS(f.size() == 8, path, ":", number,
                    ": expected 8 fields (frame ped_id pos_x pos_z pos_y v_x v_z v_y), got ",
                    f.size());
    const double frame = Field(f[0], path, number, "frame");
    const double id = Field(f[1], path, number, "ped_id");
    FS_THROW_UNLESS(id == std::floor(id) && frame == std::floor(frame) &&
                        std::abs(id) <= kMaxInteger && std::abs(frame) <= kMaxInteger,
                    path, ":", number, ": frame '", f[0], "' and ped_id '", f[1],
                    "' must be integers in [-2^53, 2^53]");
    rows.push_back({frame, static_cast<std::int64_t>(id), Field(f[2], path, number, "pos_x"),
                    Field(f[4], path, number, "pos_y"), number});
  }
  FS_THROW_UNLESS(!rows.empty(), path, ": no observations");
  // Frame step: the most common positive frame difference of consecutive observations of one agent.
  std::map<std::int64_t, std::vector<double>> frames;
  for (const Row& r : rows) frames[r.id].push_back(r.frame);
  std::map<long long, int> votes;
  for (auto& [id, fs] : frames) {
    std::sort(fs.begin(), fs.end());
    for (std::size_t i = 1; i < fs.size(); ++i)
      if (fs[i] > fs[i - 1]) ++votes[static_cast<long long>(fs[i] - fs[i - 1])];
  }
  long long frame_step = 1;
  int best = 0;
  for (const auto& [d, n] : votes)
    if (n > best) best = n, frame_step = d;
  const double seconds_per_frame = annotation_step / static_cast<double>(frame_step);
  std::map<std::int64_t, std::vector<Sample>> by_id;
  for (const Row& r : rows) by_id[r.id].push_back({r.frame * seconds_per_frame, r.x, r.y, r.line});
  return ToTracks(std::move(by_id), path, annotation_step);
}

TrackSet ResampleTracks(const TrackSet& raw, double step, double max_gap) {
  FS_THROW_UNLESS(std::isfinite(step) && step > 0, "ResampleTracks: step must be positive, got ",
                  step);
  TrackSet out;
  out.source = raw.source;
  out.seconds_per_step = step;
  for (const Track& tr : raw.tracks) {
    // Split at long gaps, then interpolate each piece on the global grid k * step.
    std::size_t begin = 0;
    for (std::size_t end = 1; end <= tr.time.size(); ++end) {
      if (end < tr.time.size() && tr.time[end] - tr.time[end - 1] <= max_gap) continue;
      const double t_first = tr.time[begin], t_last = tr.time[end - 1];
      const auto k0 = static_cast<long long>(std::ceil(t_first / step - 1e-9));
      const auto k1 = static_cast<long long>(std::floor(t_last / step + 1e-9));
      if (k1 - k0 + 1 >= 2) {
        Track piece;
        piece.agent_id = tr.agent_id;
        piece.positions.resize(k1 - k0 + 1, 2);
        std::size_t s = begin;
        for (long long k = k0; k <= k1; ++k) {
          const double t = std::clamp(static_cast<double>(k) * step, t_first, t_last);
          while (s + 1 < end && tr.time[s + 1] < t) ++s;
          const std::size_t s1 = std::min(s + 1, end - 1);
          const double span = tr.time[s1] - tr.time[s];
          const double w = span > 0 ? std::clamp((t - tr.time[s]) / span, 0.0, 1.0) : 0.0;
          const Eigen::Index row = k - k0;
          piece.positions.row(row) = (1 - w) * tr.positions.row(static_cast<Eigen::Index>(s)) +
                                     w * tr.positions.row(static_cast<Eigen::Index>(s1));
          piece.time.push_back(static_cast<double>(k) * step);
        }
        out.tracks.push_back(std::move(piece));
      }
      begin = end;
    }
  }
  return out;
}

Eigen::Matrix3d ReadHomography(const std::string& path) {
  std::ifstream in(path);
  FS_THROW_UNLESS(in.good(), path, ": cannot open homography file");
  Eigen::Matrix3d H;
  std::string line;
  int row = 0;
  for (int number = 1; std::getline(in, line); ++number) {
    std::istringstream is(line);
    std::vector<std::string> f;
    for (std::string t; is >> t;) f.push_back(t);
    if (f.empty()) continue;
    FS_THROW_UNLESS(row < 3 && f.size() == 3, path, ":", number, ": expected 3 rows of 3 numbers");
    for (int c = 0; c < 3; ++c) H(row, c) = Field(f[c], path, number, "entry");
    ++row;
  }
  FS_THROW_UNLESS(row == 3, path, ": expected 3 rows of 3 numbers, got ", row);
  FS_THROW_UNLESS(std::abs(H.determinant()) > 1e-15, path, ": homography is singular");
  return H;
}

OccupancyRaster ThorMapRaster(const std::string& image_path, const Eigen::Vector4d& extent,
                              double resolution) {
  const cv::Mat img = ReadGrey(image_path);
  constexpr double kPixel = 0.01, kXMin = -11.0,
                   kYMax = 13.5;  // README: 0.01 m/px, x in [-11, 12], y <= 13.5
  OccupancyRaster r = EmptyRaster(extent, resolution);
  for (Eigen::Index row = 0; row < r.cells.rows(); ++row)
    for (Eigen::Index c = 0; c < r.cells.cols(); ++c) {
      const double x = extent[0] + (static_cast<double>(c) + 0.5) * resolution;
      const double y = extent[3] - (static_cast<double>(row) + 0.5) * resolution;
      const double pr = std::floor((kYMax - y) / kPixel), pc = std::floor((x - kXMin) / kPixel);
      if (pr < 0 || pc < 0 || pr >= img.rows || pc >= img.cols) r.cells(row, c) = 1;
    }
  for (int pr = 0; pr < img.rows; ++pr) {
    const std::uint8_t* px = img.ptr<std::uint8_t>(pr);
    for (int pc = 0; pc < img.cols; ++pc)
      if (px[pc] <= 128) Mark(&r, kXMin + (pc + 0.5) * kPixel, kYMax - (pr + 0.5) * kPixel);
  }
  return r;
}

OccupancyRaster EthMapRaster(const std::string& image_path, const Eigen::Matrix3d& H,
                             const Eigen::Vector4d& extent, double resolution) {
  const cv::Mat img = ReadGrey(image_path);
  const Eigen::Matrix3d H_inv = H.inverse();
  OccupancyRaster r = EmptyRaster(extent, resolution);
  for (Eigen::Index row = 0; row < r.cells.rows(); ++row)
    for (Eigen::Index c = 0; c < r.cells.cols(); ++c) {
      const Eigen::Vector3d w(extent[0] + (static_cast<double>(c) + 0.5) * resolution,
                              extent[3] - (static_cast<double>(row) + 0.5) * resolution, 1.0);
      const Eigen::Vector3d p = H_inv * w;
      const double pr = p[0] / p[2], pc = p[1] / p[2];
      if (!(pr >= 0 && pc >= 0 && pr < img.rows && pc < img.cols)) r.cells(row, c) = 1;
    }
  // Thin outlines: sample each obstacle pixel at sub-pixel offsets so no cell is skipped.
  for (int pr = 0; pr < img.rows; ++pr) {
    const std::uint8_t* px = img.ptr<std::uint8_t>(pr);
    for (int pc = 0; pc < img.cols; ++pc) {
      if (px[pc] <= 128) continue;
      for (double dr : {0.25, 0.75})
        for (double dc : {0.25, 0.75}) {
          const Eigen::Vector3d w = H * Eigen::Vector3d(pr + dr, pc + dc, 1.0);
          Mark(&r, w[0] / w[2], w[1] / w[2]);
        }
    }
  }
  return r;
}

// --------------------------------------------------------------------------------------------
TrackSet ReadReplayTracks(const ReplayConfig& replay) {
  const std::string file = ResolveDataFile(replay.root, replay.file);
  TrackSet raw;
  if (replay.format == "thor")
    raw = ReadThorTracks(file);
  else if (replay.format == "eth_obsmat")
    raw = ReadEthObsmat(file);
  else
    Fail("replay.format: unknown track format '", replay.format, "' (expected thor or eth_obsmat)");
  return ResampleTracks(raw, replay.step, 1.0);
}

OccupancyRaster ReplayOccupancy(const CrowdScenarioConfig& s, double resolution) {
  const ReplayConfig& rc = s.replay;
  const Eigen::Vector4d extent(s.extent[0], s.extent[1], s.extent[2], s.extent[3]);
  const std::string image = ResolveDataFile(rc.root, rc.map_image);
  if (rc.format == "thor") return ThorMapRaster(image, extent, resolution);
  if (rc.format == "eth_obsmat") {
    const std::string h =
        rc.homography.empty()
            ? (std::filesystem::path(ResolveDataFile(rc.root, rc.file)).parent_path() / "H.txt")
                  .string()
            : ResolveDataFile(rc.root, rc.homography);
    return EthMapRaster(image, ReadHomography(h), extent, resolution);
  }
  Fail("replay.format: unknown track format '", rc.format, "' (expected thor or eth_obsmat)");
}

ReplayCrowd::ReplayCrowd(const CrowdScenarioConfig& scenario, std::uint64_t seed) {
  scenario.Validate("crowd scenario '" + scenario.name + "'");
  Init(ReadReplayTracks(scenario.replay), scenario.replay, scenario.pedestrian_radius, seed);
}

ReplayCrowd::ReplayCrowd(const TrackSet& resampled, const ReplayConfig& replay, double radius,
                         std::uint64_t seed) {
  Init(resampled, replay, radius, seed);
}

void ReplayCrowd::Init(const TrackSet& tracks, const ReplayConfig& rc, double radius,
                       std::uint64_t seed) {
  step_ = rc.step;
  duration_ = rc.duration;
  FS_THROW_UNLESS(!tracks.tracks.empty(), "replay: ", tracks.source,
                  " has no track of two or more samples");
  double t_first = tracks.tracks.front().time.front(), t_last = t_first;
  for (const Track& tr : tracks.tracks) {
    t_first = std::min(t_first, tr.time.front());
    t_last = std::max(t_last, tr.time.back());
  }
  const double room = t_last - t_first - rc.duration;
  FS_THROW_UNLESS(room >= 0, "replay: ", tracks.source, " covers ", t_last - t_first,
                  " s, shorter than replay.duration = ", rc.duration, " s");
  std::mt19937_64 rng(seed);
  const double offset = std::uniform_real_distribution<double>(0.0, 1.0)(rng) * room;
  for (int w = 0; w < rc.overlays; ++w) {
    const double shift = room > 0 ? std::fmod(offset + w * rc.overlay_spacing, room) : 0.0;
    const double start = std::round((t_first + shift) / step_) * step_;  // on the grid
    window_starts_.push_back(start);
    for (const Track& tr : tracks.tracks) {
      // Grid samples of the track inside [start, start + duration].
      int i0 = -1, i1 = -1;
      for (int i = 0; i < tr.size(); ++i) {
        if (tr.time[i] < start - 1e-9 || tr.time[i] > start + rc.duration + 1e-9) continue;
        if (i0 < 0) i0 = i;
        i1 = i;
      }
      if (i0 < 0 || i1 - i0 + 1 < 2) continue;
      Piece p;
      p.t0 = tr.time[i0] - start;
      p.positions = tr.positions.middleRows(i0, i1 - i0 + 1);
      pieces_.push_back(std::move(p));
      CrowdAgent a;
      a.id = static_cast<std::int64_t>(agents_.size());
      a.radius = radius;
      agents_.push_back(a);
    }
  }
  Update();
}

void ReplayCrowd::Update() {
  for (std::size_t i = 0; i < pieces_.size(); ++i) {
    const Piece& p = pieces_[i];
    CrowdAgent& a = agents_[i];
    const Eigen::Index n = p.positions.rows();
    const double u = (time_ - p.t0) / step_;
    a.active = u >= -1e-9 && u <= static_cast<double>(n - 1) + 1e-9;
    const Eigen::Index k =
        std::clamp<Eigen::Index>(static_cast<Eigen::Index>(std::floor(u)), 0, n - 2);
    const double w = std::clamp(u - static_cast<double>(k), 0.0, 1.0);
    a.position = ((1 - w) * p.positions.row(k) + w * p.positions.row(k + 1)).transpose();
    a.velocity = ((p.positions.row(k + 1) - p.positions.row(k)) / step_).transpose();
    if (!a.active) a.velocity.setZero();
  }
}

void ReplayCrowd::Step(double dt, const RobotAgent&) {
  FS_THROW_UNLESS(std::isfinite(dt) && dt > 0,
                  "Crowd::Step: dt must be a positive finite number, got ", dt);
  time_ += dt;
  Update();
}

}  // namespace foresight
