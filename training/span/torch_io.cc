#include "training/span/torch_io.h"

#include "core/error.h"
#include "inference/engine/artifact.h"
#include "inference/prediction/span_predictor.h"

namespace foresight::span {

LoadedNet LoadNetFromArtifact(const std::string& artifact) {
  const Artifact art = Artifact::Open(artifact, kModelType);
  LoadedNet out;
  out.config =
      config::ExperimentConfigFromYaml<ExperimentConfig>(art.config_yaml(), artifact + ":/config");
  out.layout.basis = out.config.basis.num_centres;
  out.layout.components = out.config.network.components;
  out.layout.u_param = out.config.network.u_param;
  out.net = Net(2 * out.config.windows.observed, out.config.network, out.layout);
  torch::NoGradGuard no_grad;
  for (auto& item : out.net->named_parameters()) {
    const std::string key = item.key();
    const std::string name =
        "/weights/" + key.substr(0, key.rfind('.')) + "/" + key.substr(key.rfind('.') + 1);
    const auto a = art.file().ReadFloat(name);
    FS_THROW_UNLESS(static_cast<std::int64_t>(a.Size()) == item.value().numel(), artifact, ": ",
                    name, " has ", a.Size(), " values, the model needs ", item.value().numel());
    item.value().copy_(
        torch::from_blob(const_cast<float*>(a.data.data()), item.value().sizes(), torch::kFloat32));
  }
  out.net->eval();
  return out;
}

}  // namespace foresight::span
