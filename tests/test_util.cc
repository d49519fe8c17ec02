#include "tests/test_util.h"

#include <fstream>
#include <iterator>

#include "core/h5.h"
#include "inference/engine/artifact.h"
#include "inference/prediction/span_predictor.h"

namespace foresight::testing {

void WriteText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void Truncate(const std::string& path, std::size_t bytes) { std::filesystem::resize_file(path, bytes); }

std::string SharedDataDir() {
  const char* src = std::getenv("FORESIGHT_SOURCE_DIR");
  const std::filesystem::path root = src ? src : ".";
  const auto dir = root / ".." / "shared" / "data";
  return std::filesystem::exists(dir) ? std::filesystem::canonical(dir).string() : "";
}

void WriteRandomSpanArtifact(const std::string& path, const RandomSpanSpec& s) {
  HeadLayout layout{s.basis, s.components, s.u_param};
  std::mt19937_64 rng(s.seed);
  std::normal_distribution<float> n01;
  h5::File f = h5::File::Create(path);
  Artifact::WriteHeader(&f, kSpanModelType, "model: span_predictor\n", 0);
  f.SetAttr("/model", "observed", static_cast<std::int64_t>(s.observed));
  f.SetAttr("/model", "predicted", static_cast<std::int64_t>(s.predicted));
  f.SetAttr("/model", "seconds_per_step", s.seconds_per_step);
  f.SetAttr("/model", "rotate_to_heading", static_cast<std::int64_t>(s.rotate));
  f.SetAttr("/model", "residual_to_constant_velocity", static_cast<std::int64_t>(s.residual_cv));
  f.SetAttr("/model", "basis_size", static_cast<std::int64_t>(s.basis));
  f.SetAttr("/model", "components", static_cast<std::int64_t>(s.components));
  f.SetAttr("/model", "u_param", std::string(UParamName(s.u_param)));
  f.SetAttr("/model", "basis_gamma", 1.0);
  f.WriteMatrix("/model/basis_centres", Eigen::VectorXd::LinSpaced(s.basis, 0.0, s.predicted * s.seconds_per_step));
  f.WriteMatrix("/normalisation/input_mean", Eigen::VectorXd::Zero(2 * s.observed));
  f.WriteMatrix("/normalisation/input_std", Eigen::VectorXd::Constant(2 * s.observed, 2.0));
  std::vector<int> widths{2 * s.observed};
  widths.insert(widths.end(), s.hidden.begin(), s.hidden.end());
  widths.push_back(layout.Total());
  std::string names;
  for (std::size_t i = 0; i + 1 < widths.size(); ++i) {
    const std::string name = i + 2 == widths.size() ? "head" : "mlp." + std::to_string(2 * i);
    names += (names.empty() ? "" : ",") + name;
    Eigen::MatrixXf w(widths[i + 1], widths[i]);
    for (Eigen::Index k = 0; k < w.size(); ++k) w.data()[k] = n01(rng) / std::sqrt(static_cast<float>(widths[i]));
    if (name == "head") w *= 0.1f;
    Eigen::VectorXf b(widths[i + 1]);
    for (Eigen::Index k = 0; k < b.size(); ++k) b[k] = 0.1f * n01(rng);
    f.WriteMatrix("/weights/" + name + "/weight", w);
    f.WriteMatrix("/weights/" + name + "/bias", b);
  }
  f.SetAttr("/model", "dense_layers", names);
}

}  // namespace foresight::testing
