#include "models/otnet/otnet_net.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "core/error.h"

namespace foresight::otnet {

namespace {

using RowMajorF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

OtnetHead HeadOf(const OtnetNetOptions& o) { return OtnetHead{o.components, o.weights}; }

}  // namespace

OtnetNetImpl::OtnetNetImpl(const OtnetNetOptions& options) : options_(options) {
  FS_THROW_UNLESS(options.inputs >= 1, "OtnetNet: inputs (database size) must be >= 1, got ",
                  options.inputs);
  FS_THROW_UNLESS(!options.hidden.empty(), "OtnetNet: hidden must list at least one layer width");
  for (std::size_t i = 0; i < options.hidden.size(); ++i)
    FS_THROW_UNLESS(options.hidden[i] >= 1, "OtnetNet: hidden[", i, "] must be >= 1, got ",
                    options.hidden[i]);
  FS_THROW_UNLESS(options.components >= 1, "OtnetNet: components must be >= 1, got ",
                  options.components);
  FS_THROW_UNLESS(options.weights >= 2 && options.weights % 2 == 0,
                  "OtnetNet: weights (2M) must be even and >= 2, got ", options.weights);
  FS_THROW_UNLESS(std::isfinite(options.dropout) && options.dropout >= 0 && options.dropout < 1,
                  "OtnetNet: dropout must be in [0, 1), got ", options.dropout);
  const OtnetHead head = HeadOf(options);
  int width = options.inputs;
  const int k = static_cast<int>(options.hidden.size());
  for (int i = 0; i <= k; ++i) {
    const int out = i < k ? options.hidden[i] : head.Total();
    linears_.push_back(register_module("layer" + std::to_string(i), torch::nn::Linear(width, out)));
    width = out;
  }
  if (options.dropout > 0)
    dropout_ = register_module("dropout", torch::nn::Dropout(options.dropout));
  // A sensible initial mixture: uniform alpha, unit scales (standardised targets) and component
  // means drawn N(0, 1) so they start apart; small head weights keep phi's influence small at
  // first, so that every map starts from roughly this mixture.
  torch::NoGradGuard no_grad;
  torch::nn::Linear& last = linears_.back();
  last->weight.mul_(0.1);
  last->bias.zero_();
  last->bias.narrow(0, head.MeanOffset(0), head.components * head.weights)
      .copy_(torch::randn({head.components * head.weights}));
}

torch::Tensor OtnetNetImpl::forward(const torch::Tensor& phi) {
  FS_THROW_UNLESS(phi.dim() == 2 && phi.size(1) == options_.inputs, "OtnetNet: phi must be [B, ",
                  options_.inputs, "], got ", phi.sizes());
  torch::Tensor h = phi.to(torch::kFloat32);
  for (std::size_t i = 0; i < linears_.size(); ++i) {
    h = linears_[i]->forward(h);
    if (i + 1 < linears_.size()) {
      h = torch::relu(h);
      if (dropout_) h = dropout_->forward(h);
    }
  }
  return h;
}

MixtureOutputs OtnetNetImpl::Split(const torch::Tensor& raw) const {
  const OtnetHead head = HeadOf(options_);
  FS_THROW_UNLESS(raw.dim() == 2 && raw.size(1) == head.Total(),
                  "OtnetNet::Split: raw must be [B, ", head.Total(), "], got ", raw.sizes());
  const std::int64_t b = raw.size(0), q = head.components, w = head.weights;
  MixtureOutputs out;
  out.logits = raw.narrow(1, head.LogitOffset(), q);
  out.mean = raw.narrow(1, head.MeanOffset(0), q * w).reshape({b, q, w});
  out.log_scale = raw.narrow(1, head.LogScaleOffset(0), q * w)
                      .reshape({b, q, w})
                      .clamp(OtnetHead::kLogScaleMin, OtnetHead::kLogScaleMax);
  return out;
}

torch::Tensor MixtureNegLogLikelihood(const MixtureOutputs& out, const torch::Tensor& w,
                                      MixtureFamily family) {
  FS_THROW_UNLESS(out.logits.defined() && out.logits.dim() == 2,
                  "MixtureNegLogLikelihood: logits must be [B, Q], got ",
                  out.logits.defined() ? out.logits.sizes() : torch::IntArrayRef{});
  const std::int64_t b = out.logits.size(0), q = out.logits.size(1);
  FS_THROW_UNLESS(w.defined() && w.dim() == 2 && w.size(0) == b,
                  "MixtureNegLogLikelihood: w must be [", b, ", 2M], got ",
                  w.defined() ? w.sizes() : torch::IntArrayRef{});
  const std::int64_t m2 = w.size(1);
  const auto check = [&](const torch::Tensor& t, const char* name) {
    FS_THROW_UNLESS(
        t.defined() && t.dim() == 3 && t.size(0) == b && t.size(1) == q && t.size(2) == m2,
        "MixtureNegLogLikelihood: ", name, " must be [", b, ", ", q, ", ", m2, "], got ",
        t.defined() ? t.sizes() : torch::IntArrayRef{});
  };
  check(out.mean, "mean");
  check(out.log_scale, "log_scale");
  // Thesis eq. lossF per trajectory, in the log domain: log alpha_q by log-softmax, the
  // mean-field component log-density (eq. NormalAss; Laplace alike) as a sum over the 2M weights,
  // and -logsumexp over q, so that far-away targets neither underflow nor give inf.
  const torch::Tensor log_alpha = torch::log_softmax(out.logits, 1);  // [B, Q]
  const torch::Tensor z =
      (w.to(out.mean.scalar_type()).unsqueeze(1) - out.mean) * torch::exp(-out.log_scale);
  torch::Tensor log_density;  // [B, Q, 2M]
  if (family == MixtureFamily::kNormal)
    log_density = -0.5 * z.square() - out.log_scale - 0.5 * std::log(2 * M_PI);
  else
    log_density = -z.abs() - out.log_scale - std::log(2.0);
  return -torch::logsumexp(log_alpha + log_density.sum(2), 1);
}

OtnetNormalisation OtnetNormalisation::Fit(const Eigen::MatrixXd& phi, const Eigen::MatrixXd& w) {
  FS_THROW_UNLESS(phi.rows() >= 1 && phi.cols() >= 1,
                  "OtnetNormalisation::Fit: phi must be [maps x D] with maps, D >= 1, got ",
                  phi.rows(), " x ", phi.cols());
  FS_THROW_UNLESS(w.rows() >= 1 && w.cols() >= 1,
                  "OtnetNormalisation::Fit: w must be [N x 2M] with N, 2M >= 1, got ", w.rows(),
                  " x ", w.cols());
  FS_THROW_UNLESS(phi.allFinite(), "OtnetNormalisation::Fit: phi contains a non-finite value");
  FS_THROW_UNLESS(w.allFinite(), "OtnetNormalisation::Fit: w contains a non-finite value");
  const auto moments = [](const Eigen::MatrixXd& x, Eigen::VectorXd* mean, Eigen::VectorXd* std) {
    *mean = x.colwise().mean().transpose();
    // Population std (divide by the row count), floored so constant columns stay finite.
    *std = ((x.rowwise() - mean->transpose()).array().square().colwise().sum() /
            static_cast<double>(x.rows()))
               .sqrt()
               .max(1e-6)
               .transpose();
  };
  OtnetNormalisation n;
  moments(phi, &n.input_mean, &n.input_std);
  moments(w, &n.weight_mean, &n.weight_std);
  return n;
}

Mlp ExportMlp(OtnetNet& net, const OtnetNormalisation& norm) {
  const OtnetNetOptions& o = net->options();
  const OtnetHead head = HeadOf(o);
  FS_THROW_UNLESS(norm.input_mean.size() == o.inputs && norm.input_std.size() == o.inputs,
                  "ExportMlp: the input normalisation has ", norm.input_mean.size(), " means and ",
                  norm.input_std.size(), " stds for ", o.inputs, " inputs");
  FS_THROW_UNLESS(norm.weight_mean.size() == o.weights && norm.weight_std.size() == o.weights,
                  "ExportMlp: the weight normalisation has ", norm.weight_mean.size(),
                  " means and ", norm.weight_std.size(), " stds for ", o.weights, " weights");
  FS_THROW_UNLESS(norm.input_mean.allFinite() && norm.weight_mean.allFinite() &&
                      (norm.input_std.array() > 0).all() && (norm.weight_std.array() > 0).all() &&
                      norm.input_std.allFinite() && norm.weight_std.allFinite(),
                  "ExportMlp: the normalisation needs finite means and finite stds > 0");
  const std::vector<torch::nn::Linear> linears = net->linears();
  std::vector<DenseLayer> layers;
  for (const torch::nn::Linear& l : linears) {
    const torch::Tensor wt = l->weight.detach().to(torch::kFloat32).contiguous();
    const torch::Tensor bt = l->bias.detach().to(torch::kFloat32).contiguous();
    DenseLayer d;
    d.weight = Eigen::Map<const RowMajorF>(wt.data_ptr<float>(), wt.size(0), wt.size(1));
    d.bias = Eigen::Map<const Eigen::VectorXf>(bt.data_ptr<float>(), bt.size(0));
    layers.push_back(std::move(d));
  }
  // Fold in double, round once to float.
  {  // First layer on raw phi: W' = W diag(1/s_phi), b' = b - W (m_phi / s_phi).
    DenseLayer& first = layers.front();
    const Eigen::MatrixXd w = first.weight.cast<double>();
    const Eigen::VectorXd shift = norm.input_mean.cwiseQuotient(norm.input_std);
    first.bias = (first.bias.cast<double>() - w * shift).cast<float>();
    first.weight = (w * norm.input_std.cwiseInverse().asDiagonal()).cast<float>();
  }
  {  // Head: mu = s_w mu_hat + m_w; log s = log s_hat + log s_w (per weight j, every component).
    DenseLayer& last = layers.back();
    for (int q = 0; q < head.components; ++q)
      for (int j = 0; j < head.weights; ++j) {
        const int r = head.MeanOffset(q) + j;
        const double s = norm.weight_std[j];
        last.weight.row(r) = (s * last.weight.row(r).cast<double>()).cast<float>();
        last.bias[r] = static_cast<float>(s * last.bias[r] + norm.weight_mean[j]);
        const int g = head.LogScaleOffset(q) + j;
        last.bias[g] = static_cast<float>(last.bias[g] + std::log(s));
      }
  }
  return Mlp(std::move(layers));
}

}  // namespace foresight::otnet
