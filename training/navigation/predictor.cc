#include "training/navigation/predictor.h"

#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>

#include "core/error.h"
#include "core/log.h"
#include "datasets/crowd_replay.h"
#include "datasets/track_store.h"
#include "inference/engine/artifact.h"
#include "inference/prediction/span_predictor.h"
#include "training/span/eval.h"
#include "training/span/pipeline.h"

namespace foresight::nav {
namespace fs = std::filesystem;

namespace {
/// The predictor's SPAN config: train_config (or the embedded default) plus `overrides`; an Error
/// names both keys.
span::ExperimentConfig LoadTrainConfig(const PredictorConfig& p,
                                       const std::string& embedded_default,
                                       const std::vector<std::string>& overrides) {
  try {
    return p.train_config == "default"
               ? config::ExperimentConfigFromYaml<span::ExperimentConfig>(
                     embedded_default, "<embedded configs/navigation/predictor.yaml>", overrides)
               : config::LoadExperimentConfig<span::ExperimentConfig>(p.train_config, overrides);
  } catch (const Error& e) {
    Fail("predictor.train_config with predictor.train_overrides: ", e.what());
  }
}
/// An artifact this command trained (its run directory holds the recorded tracks.h5) must still be
/// what train_config and train_overrides describe: else editing them would silently keep using the
/// old predictor. Artifacts trained elsewhere are the user's choice and are not checked.
void CheckTrainedAsConfigured(const PredictorConfig& p, const std::string& embedded_default) {
  const fs::path dir = fs::path(p.artifact).parent_path();
  if (!fs::exists((dir.empty() ? fs::path(".") : dir) / "tracks.h5")) return;
  const span::ExperimentConfig trained = config::ExperimentConfigFromYaml<span::ExperimentConfig>(
      Artifact::Open(p.artifact, span::kModelType).config_yaml(), p.artifact + ":/config");
  const auto tree = [](span::ExperimentConfig c) {
    c.data = {};  // set from the recorded tracks when training
    return config::ParseYaml(config::ToYaml(c), "resolved config");
  };
  const std::string d = config::FirstDifference(
      tree(trained), tree(LoadTrainConfig(p, embedded_default, p.train_overrides)), "");
  FS_THROW_UNLESS(d.empty(), "predictor.artifact: ", p.artifact, " was trained with ", d,
                  " from predictor.train_config and predictor.train_overrides; delete its run "
                  "directory to retrain, or name another predictor.artifact");
}
}  // namespace

std::string EnsurePredictor(const ExperimentConfig& c, const std::string& embedded_default) {
  const PredictorConfig& p = c.predictor;
  if (fs::exists(p.artifact)) {
    CheckTrainedAsConfigured(p, embedded_default);
    return p.artifact;
  }
  const fs::path artifact(p.artifact);
  FS_THROW_UNLESS(artifact.filename() == "model.h5", "predictor.artifact: ", p.artifact,
                  " does not exist; to train it automatically name it <run dir>/model.h5");
  const std::string run_dir =
      artifact.parent_path().empty() ? "." : artifact.parent_path().string();
  (void)LoadTrainConfig(p, embedded_default,
                        p.train_overrides);  // refuse bad keys before recording
  fs::create_directories(run_dir);
  const std::string tracks_file = fs::absolute(fs::path(run_dir) / "tracks.h5").string();
  if (!fs::exists(tracks_file)) {
    TrackSet tracks;
    if (p.tracks == "replay") {
      tracks = ReadReplayTracks(p.replay);
    } else {
      FS_THROW_UNLESS(c.scenario.source == CrowdSource::kSimulated,
                      "predictor.tracks: 'scenario' needs a simulated ",
                      "scenario; for replays set predictor.tracks: replay and predictor.replay to "
                      "other recordings");
      tracks = RecordCrowdTracks(c.scenario, p.record_episodes, p.record_duration, c.dt,
                                 static_cast<std::uint64_t>(c.seed) + 1000003);
      std::mt19937_64 rng(static_cast<std::uint64_t>(c.seed) + 7);
      std::normal_distribution<double> noise(0.0, p.position_noise);
      if (p.position_noise > 0)
        for (Track& t : tracks.tracks)
          t.positions += t.positions.unaryExpr([&](double) { return noise(rng); });
    }
    FS_THROW_UNLESS(!tracks.tracks.empty(), "predictor: no training tracks from ", p.tracks);
    WriteTrackStore(tracks_file + ".tmp", tracks);
    fs::rename(tracks_file + ".tmp", tracks_file);
    log::Info("predictor: ", tracks.tracks.size(), " training tracks (", tracks.NumPoints(),
              " points) -> ", tracks_file);
  }
  const TrackSet stored = ReadTrackStore(tracks_file);
  std::vector<std::string> overrides = p.train_overrides;  // the data keys below win
  overrides.insert(
      overrides.end(),
      {"data.format=track_store", "data.root=", "data.train_files=[" + tracks_file + "]",
       "data.seconds_per_step=" + std::to_string(stored.seconds_per_step)});
  const span::ExperimentConfig span = LoadTrainConfig(p, embedded_default, overrides);
  const bool resume = fs::exists(run_dir + "/checkpoints/last.pt");
  std::cout << "training the SPAN predictor into " << run_dir << (resume ? " (resuming)" : "")
            << "\n";
  TrainingSummary s;
  {
    const ScopedInterruptFlag interrupt;
    TrainHooks hooks;
    hooks.interrupt = interrupt.flag();
    s = span::TrainRun(span, run_dir, resume, hooks);
  }
  WriteTrainingSummary(run_dir + "/training_summary.json", s);
  std::cout << s.BriefReport() << "\n";
  FS_THROW_UNLESS(s.reason != TerminationReason::kInterrupted,
                  "predictor training interrupted; run again to resume");
  FS_THROW_UNLESS(s.best_epoch >= 0, run_dir,
                  ": predictor training produced no usable checkpoint (", ToString(s.reason), ")");
  const std::string out = span::ExportRun(run_dir);
  const span::EvalReport r = span::Evaluate(span, out, run_dir);
  std::cout << "predictor eval (" << r.windows << " test windows): ADE " << r.model.ade << " FDE "
            << r.model.fde << " NLL " << r.model.nll << " | constant velocity ADE " << r.cv.ade
            << " FDE " << r.cv.fde << "\n";
  return out;
}

}  // namespace foresight::nav
