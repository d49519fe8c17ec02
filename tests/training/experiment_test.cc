// The experiment contract (training/experiment.h): lookups, one-line errors for missing steps, and
// every kind of this build dispatched through train, export and eval on a tiny config, and bench
// targets (config, run directory, artifact) resolved to their kind.

#include "training/experiment.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <regex>

#include "inference/engine/artifact.h"
#include "tests/test_util.h"
#include "training/kinds.h"
#include "training/run_dir.h"

namespace foresight {
namespace {
namespace fs = std::filesystem;

/// The toy kind of docs/architecture.md: it "trains" by writing its config's number into a file.
struct ToyConfig {
  std::string model = "toy";
  double value = 1;
  template <class A>
  void Serialize(A* a) {
    a->Visit("model", &model, config::Range::Any(), "model type (toy)");
    a->Visit("value", &value, config::Range::Any(), "the number the toy writes");
  }
  void Validate(const std::string& source) const {
    FS_THROW_UNLESS(value >= 0, source, ": key 'value' (", value, ") must be >= 0");
  }
};

/// The toy's bench options, and what its bench saw last (the toy prints nothing).
struct ToyBenchOptions {
  int repeats = 3;
  template <class A>
  void Serialize(A* a) {
    a->Visit("repeats", &repeats, config::Range::Closed(1, 10), "timed runs");
  }
};
struct ToyBenchSeen {
  BenchRequest::Target what;
  std::string config_value;
  int repeats;
};
ToyBenchSeen& LastToyBench() {
  static ToyBenchSeen seen{};
  return seen;
}
void RunToyBench(const BenchRequest& req, const ToyBenchOptions& o) {
  LastToyBench() = {req.what, std::to_string(LoadBenchConfig<ToyConfig>(req).value), o.repeats};
}

ExperimentKind ToyKind() {
  ExperimentKind k;
  k.tag = "toy";
  k.summary = "A toy method";
  k.reference = [] { return config::ReferenceTable<ToyConfig>(); };
  k.train = [](const TrainRequest& req) {
    const auto c = LoadRequestConfig<ToyConfig>(req, "model: toy\n", "toy default");
    StartRunDirectory(req.run_dir, config::ToYaml(c), req.resume,
                      RunDirectoryRules{{"model.txt"}, false});
    testing::WriteText(req.run_dir + "/model.txt", std::to_string(c.value));
  };
  k.evaluate = [](const std::string& run_dir, const std::vector<std::string>& overrides) {
    const auto c = LoadRunConfig<ToyConfig>(run_dir, overrides);
    return "{\"value\": " + testing::ReadText(run_dir + "/model.txt") +
           ", \"config\": " + std::to_string(c.value) + "}";
  };
  SetBench<ToyBenchOptions>(&k, RunToyBench);
  return k;
}

TEST(Experiment, RegistryDispatchesByModelTag) {
  testing::TempDir dir;
  ExperimentRegistry r;
  r.Add(ToyKind());
  r.SetDefault("toy");
  testing::WriteText(dir.File("toy.yaml"), "model: toy\nvalue: 3\n");
  EXPECT_EQ(&r.ForConfig(dir.File("toy.yaml")), &r.kinds()[0]);
  EXPECT_EQ(&r.ForConfig("default"), &r.kinds()[0]);

  TrainRequest req{dir.File("toy.yaml"), {"value=4"}, dir.File("run"), false, true};
  r.ForConfig(req.config).train(req);
  const ExperimentKind& kind = r.ForRun(req.run_dir);
  EXPECT_EQ(kind.tag, "toy");
  EXPECT_EQ(kind.evaluate(req.run_dir, {}), "{\"value\": 4.000000, \"config\": 4.000000}");
  testing::ExpectErrorContains([&] { kind.NoSuchStep("export"); }, {"'toy' has no export step"});
  testing::ExpectErrorContains([&] { kind.train(req); },
                               {"already holds a run (model.txt)", "new or empty"});
  req.resume = true;
  testing::ExpectErrorContains([&] { kind.train(req); }, {"--resume", "cannot be continued"});
  EXPECT_NE(r.ReferenceMarkdown().find("| `value` | number | `1.0` |"), std::string::npos)
      << r.ReferenceMarkdown();
  EXPECT_NE(r.ReferenceMarkdown().find("| `repeats` | integer | `3` |"), std::string::npos)
      << "the bench options are in the reference: " << r.ReferenceMarkdown();

  // bench: a config target and a run directory reach the same kind; options are strict.
  BenchRequest bench{dir.File("toy.yaml"), BenchRequest::Target::kArtifact, {"value=5"}, {}, false};
  r.ForBenchTarget(&bench).bench(bench);
  EXPECT_EQ(LastToyBench().what, BenchRequest::Target::kConfig);
  EXPECT_EQ(LastToyBench().config_value, "5.000000");
  EXPECT_EQ(LastToyBench().repeats, 3);
  bench = BenchRequest{req.run_dir, BenchRequest::Target::kConfig, {}, {"repeats=7"}, true};
  r.ForBenchTarget(&bench).bench(bench);
  EXPECT_EQ(LastToyBench().what, BenchRequest::Target::kRunDir);
  EXPECT_EQ(LastToyBench().config_value, "4.000000") << "a run's bench reads the run's config";
  EXPECT_EQ(LastToyBench().repeats, 7);
  bench.options = {"nope=1"};
  testing::ExpectErrorContains([&] { kind.bench(bench); }, {"bench options", "nope"});
  bench.options = {"repeats=0"};
  testing::ExpectErrorContains([&] { kind.bench(bench); }, {"bench options", "repeats"});
  bench.options = {};
  EXPECT_EQ(BenchArtifact(bench, "model.txt"), req.run_dir + "/model.txt");
  testing::ExpectErrorContains([&] { (void)BenchArtifact(bench, "model.h5"); },
                               {"model.h5", "not found"});
  bench.overrides = {"value=2"};
  testing::ExpectErrorContains([&] { (void)BenchArtifact(bench, "model.txt"); },
                               {"value=2", "only bench.key=value"});
  bench = BenchRequest{dir.File("nowhere"), BenchRequest::Target::kConfig, {}, {}, false};
  testing::ExpectErrorContains([&] { (void)r.ForBenchTarget(&bench); },
                               {"nowhere", "no such file"});
}

TEST(Experiment, LookupErrorsNameTheSourceAndTheKnownKinds) {
  testing::TempDir dir;
  ExperimentRegistry r;
  r.Add(ToyKind());
  testing::WriteText(dir.File("other.yaml"), "model: teleport\n");
  testing::ExpectErrorContains(
      [&] { r.ForConfig(dir.File("other.yaml")); },
      {dir.File("other.yaml"), "no experiment kind 'teleport'", "known: toy"});
  testing::WriteText(dir.File("untagged.yaml"), "value: 3\n");
  testing::ExpectErrorContains([&] { r.ForConfig(dir.File("untagged.yaml")); },
                               {"untagged.yaml", "'model'"});
  testing::ExpectErrorContains([&] { r.ForRun(dir.path()); }, {dir.path(), "not a run directory"});
  testing::ExpectErrorContains([&] { r.ForConfig("default"); }, {"no default config"});
  testing::ExpectErrorContains([&] { r.Add(ToyKind()); }, {"'toy' is registered twice"});
  testing::WriteText(dir.File("bad.yaml"), "model: toy\nvalue: -1\n");
  testing::ExpectErrorContains(
      [&] { config::LoadExperimentConfig<ToyConfig>(dir.File("bad.yaml")); },
      {"bad.yaml", "'value'", "-1"});
}

/// `json` with the values of wall-time keys ("time...", "..._s", "...seconds") masked: those are
/// measured, every other figure must repeat exactly.
std::string WithoutWallTimes(const std::string& json) {
  static const std::regex wall(
      R"re(("[a-z_]*(time|seconds|_s)[a-z_0-9]*"\s*:\s*)(\{[^}]*\}|[-+0-9.eE]+|null))re");
  return std::regex_replace(json, wall, "$1<wall time>");
}

/// A tiny config per kind of this build; a new kind adds its own here (the test fails without).
const std::map<std::string, std::string>& TinyConfigs() {
  static const std::map<std::string, std::string> configs{
      {"span_predictor",
       "model: span_predictor\ndata: {synthetic: {num_tracks: 120}}\nnetwork: {hidden: [16, 16]}\n"
       "basis: {num_centres: 5}\ntrain: {epochs: 2, batch_size: 64, progress: none}\neval: "
       "{plot_tracks: 0}\n"},
      {"occupancy.",
       "model: occupancy.fast_bhm\ndata:\n  format: synthetic\n  synthetic: {width: 10, height: 8, "
       "num_robots: 2, "
       "scans_per_robot: 30, max_range: 10}\nfeatures: {x_min: -1, x_max: 11, y_min: -1, y_max: 9, "
       "spacing: 0.5}\n"
       "grid: {x_min: -1, x_max: 11, y_min: -1, y_max: 9, resolution: 0.1, max_range: 10.0}\n"},
      {"directional",
       "model: directional\ndata: {format: crossing, crossing: {num_tracks: 80, duration: 60}}\n"
       "features: {x_min: 0, x_max: 10, y_min: 0, y_max: 10, cells_x: 4, cells_y: 4, length_scale: "
       "2.5, t_min: 0, "
       "t_max: 60, time_points: 3, time_length_scale: 15}\nnetwork: {components: 2, hidden: 8, "
       "spatial_epochs: 2}\n"
       "train: {epochs: 2, batch_size: 128, progress: none}\neval: {folds: 2, max_folds: 1, plots: "
       "false}\n"},
      {"navigation", "model: navigation\n"},
      {"manipulation", "model: manipulation\nrobot: builtin\nproblems: {source: synthetic}\n"},
      {"gfcs",
       "model: gfcs\nrobot: builtin\ntrain_problems: [{source: synthetic, synthetic_count: 3}]\n"
       "lattice: {spacing: 0.6}\nautoencoder: {encoding: 4, hidden: 8, train: {epochs: 2, "
       "batch_size: 2, progress: none}}\nenergy: {hidden: 8, layers: 2}\nloop: {train_every: 2, "
       "adam_steps: 3, negatives: 3, negative_sgld: {steps: 3}, batches: 2, batch_size: 6}\n"
       "sampler: {particles: 6, steps: 3}\neval: {problems: [{source: synthetic, synthetic_seed: "
       "100, "
       "synthetic_count: 2}], batch_size: 6, batches: [1], baselines: []}\n"},
      {"diffeo",
       "model: diffeo\ndata: {source: synthetic, synthetic_demos: 3, synthetic_points: 40, "
       "downsample: 1, held_out: [2]}\nflow: {spacing: 0.1, gamma: 200, cutoff_radius: 0.3, steps: "
       "4}\ntrain: {epochs: 2, batch_size: 32, progress: none}\neflow: {layers: 2, features: 8, "
       "train: {epochs: 2, batch_size: 32, progress: none}}\nobstacle: {times: [0.002, 0.004], "
       "repulsor_gains: [0.1, 1]}\neval: {max_steps: 300, grid: 2, plots: false}\n"},
      {"otnet",
       "model: otnet\ndata: {source: synthetic, synthetic_maps: 12, synthetic_trajectories: 8, "
       "val_fraction: 0.25, test_fraction: 0.25}\notnet: {basis: 6, components: 2, hidden: [8]}\n"
       "train: {epochs: 2, batch_size: 16, progress: none}\neval: {generated: 5, points: 20, "
       "plots: false}\n"},
      {"constrained",
       "model: constrained\ndata: {source: synthetic, max_maps: 4, synthetic_tracks: 12}\n"
       "split: {by_scene: true, val_fraction: 0.25, test_fraction: 0.25}\n"
       "windows: {observed: 6, predicted: 6, stride: 3}\nbasis: {num_centres: 4}\n"
       "network: {hidden: [16], components: 2, u_param: diagonal}\n"
       "train: {epochs: 2, batch_size: 32, progress: none}\nktm: {references: 8}\n"
       "naive: {hidden: [16]}\neval: {max_windows: 6, accuracy_windows: 2, accuracy_samples: "
       "500, plot_windows: 1, plot_samples: 3}\n"},
  };
  return configs;
}

TEST(Experiment, EveryBuiltinKindRunsThroughTrainExportAndEval) {
  const ExperimentRegistry registry = BuiltinKinds();
  ASSERT_FALSE(registry.kinds().empty());
  for (const ExperimentKind& kind : registry.kinds()) {
    SCOPED_TRACE(kind.tag);
    const auto tiny = TinyConfigs().find(kind.tag);
    ASSERT_NE(tiny, TinyConfigs().end())
        << "add a tiny config for kind '" << kind.tag << "' to this test";
    testing::TempDir dir;
    const std::string config = dir.File("tiny.yaml"), run = dir.File("run");
    testing::WriteText(config, tiny->second);
    const ExperimentKind& found = registry.ForConfig(config);
    EXPECT_EQ(&found, &kind);
    EXPECT_FALSE(kind.summary.empty());
    ASSERT_TRUE(kind.reference) << "every kind documents its config";
    if (!kind.train) {
      // A kind without steps says so in one line for each (navigation is run by `navigate`,
      // manipulation by `plan`).
      EXPECT_FALSE(kind.export_run || kind.evaluate);
      testing::ExpectErrorContains([&] { kind.NoSuchStep("train"); },
                                   {"'" + kind.tag + "' has no train step"});
      BenchRequest b{config, BenchRequest::Target::kRunDir, {}, {}, false};
      EXPECT_EQ(&registry.ForBenchTarget(&b), &kind);
      EXPECT_EQ(b.what, BenchRequest::Target::kConfig);
      continue;
    }
    kind.train(TrainRequest{config, {}, run, false, true});
    EXPECT_EQ(&registry.ForRun(run), &kind) << "the run directory names its kind";
    ASSERT_TRUE(kind.export_run && kind.evaluate) << "a trained kind exports and evaluates";
    const std::string artifact = kind.export_run(run);
    EXPECT_TRUE(fs::exists(artifact)) << artifact;
    EXPECT_EQ(h5::File::Open(artifact).GetStringAttr("/", "kind"), kArtifactKind);
    // bench finds the kind from the run and from its artifact (the config stored in it); the
    // benches themselves print figures and run in tests/cli_test.sh.
    for (const std::string& target : {run, artifact}) {
      BenchRequest b{target, BenchRequest::Target::kConfig, {}, {}, false};
      EXPECT_EQ(&registry.ForBenchTarget(&b), &kind) << target;
    }
    const std::string first = testing::ReadText(run + "/eval.json");
    const std::string json = kind.evaluate(run, {});
    EXPECT_FALSE(json.empty());
    EXPECT_EQ(json, testing::ReadText(run + "/eval.json")) << "eval writes what it returns";
    EXPECT_EQ(WithoutWallTimes(json), WithoutWallTimes(first))
        << "evaluating the exported artifact again gives the same figures";
    // Where the data lives may differ at evaluation (data.root); the figures do not, and the
    // run's config.yaml stays the one it was trained with.
    const std::string config_before = testing::ReadText(run + "/config.yaml");
    EXPECT_EQ(WithoutWallTimes(kind.evaluate(run, {"data.root=" + dir.path()})),
              WithoutWallTimes(first));
    EXPECT_EQ(testing::ReadText(run + "/config.yaml"), config_before);
    EXPECT_TRUE(fs::exists(run + "/config.yaml") && fs::exists(run + "/log.txt"));
  }
}

}  // namespace
}  // namespace foresight
