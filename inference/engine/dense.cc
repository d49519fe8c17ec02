#include "inference/engine/dense.h"

#include "core/error.h"

namespace foresight {

Mlp::Mlp(std::vector<DenseLayer> layers) : layers_(std::move(layers)) {
  FS_THROW_UNLESS(!layers_.empty(), "Mlp: no layers");
  max_width_ = static_cast<int>(layers_.front().weight.cols());
  for (std::size_t i = 0; i < layers_.size(); ++i) {
    const auto& l = layers_[i];
    FS_THROW_UNLESS(l.bias.size() == l.weight.rows(), "Mlp: layer ", i, " bias has ", l.bias.size(),
                    " entries for ", l.weight.rows(), " outputs");
    FS_THROW_UNLESS(i == 0 || l.weight.cols() == layers_[i - 1].weight.rows(), "Mlp: layer ", i,
                    " takes ", l.weight.cols(), " inputs but layer ", i - 1, " gives ",
                    layers_[i - 1].weight.rows());
    max_width_ = std::max(max_width_, static_cast<int>(l.weight.rows()));
  }
}

Mlp Mlp::Load(const h5::File& file, const std::string& prefix,
              const std::vector<std::string>& names) {
  std::vector<DenseLayer> layers;
  for (const auto& name : names) {
    DenseLayer l;
    l.weight = file.ReadMatrixF(prefix + name + "/weight");
    const Eigen::MatrixXf b = file.ReadMatrixF(prefix + name + "/bias", l.weight.rows(), 1);
    l.bias = b.col(0);
    layers.push_back(std::move(l));
  }
  try {
    return Mlp(std::move(layers));
  } catch (const Error& e) {
    Fail(file.path(), ": ", e.what());
  }
}

Mlp Mlp::LoadListed(const h5::File& file, const std::string& group, const std::string& names_attr,
                    const std::string& prefix) {
  const std::string joined = file.GetStringAttr(group, names_attr);
  std::vector<std::string> names;
  for (std::size_t start = 0;;) {
    const auto comma = joined.find(',', start);
    names.push_back(joined.substr(start, comma == std::string::npos ? comma : comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  Mlp mlp = Load(file, prefix, names);
  for (const auto& l : mlp.layers())
    FS_THROW_UNLESS(l.weight.allFinite() && l.bias.allFinite(), file.path(),
                    ": non-finite weights");
  return mlp;
}

void Mlp::SaveListed(h5::File* file, const std::string& group, const std::string& names_attr,
                     const std::string& prefix, const std::vector<std::string>& names) const {
  std::string joined;
  for (const auto& name : names) joined += (joined.empty() ? "" : ",") + name;
  file->SetAttr(group, names_attr, joined);
  Save(file, prefix, names);
}

void Mlp::Save(h5::File* file, const std::string& prefix,
               const std::vector<std::string>& names) const {
  FS_THROW_UNLESS(names.size() == layers_.size(), file->path(), ": ", names.size(),
                  " layer names for ", layers_.size(), " layers");
  for (std::size_t i = 0; i < layers_.size(); ++i) {
    file->WriteMatrix(prefix + names[i] + "/weight", layers_[i].weight);
    const Eigen::VectorXf& b = layers_[i].bias;  // 1-d [out], as documented
    file->Write(prefix + names[i] + "/bias", b.data(), {static_cast<std::size_t>(b.size())});
  }
}

Mlp::Workspace Mlp::MakeWorkspace() const {
  return {Eigen::VectorXf::Zero(max_width_), Eigen::VectorXf::Zero(max_width_)};
}

Eigen::Ref<const Eigen::VectorXf> Mlp::Forward(const Eigen::Ref<const Eigen::VectorXf>& input,
                                               Workspace* ws) const {
  const Eigen::VectorXf* src = nullptr;
  Eigen::VectorXf* dst = &ws->ping;
  for (std::size_t i = 0; i < layers_.size(); ++i) {
    const auto& l = layers_[i];
    const auto n_out = l.weight.rows();
    if (i == 0) {
      dst->head(n_out).noalias() = l.weight * input;
    } else {
      dst->head(n_out).noalias() = l.weight * src->head(l.weight.cols());
    }
    dst->head(n_out) += l.bias;
    if (i + 1 < layers_.size()) dst->head(n_out) = dst->head(n_out).cwiseMax(0.0f);
    src = dst;
    dst = (dst == &ws->ping) ? &ws->pong : &ws->ping;
  }
  return src->head(output_size());
}

}  // namespace foresight
