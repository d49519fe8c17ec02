#pragma once
/// Dense layers and ReLU MLPs evaluated with Eigen in float, without allocation after set-up.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/h5.h"

namespace foresight {

struct DenseLayer {
  Eigen::MatrixXf weight;  ///< [out x in]
  Eigen::VectorXf bias;    ///< [out]
};

/// Layers with ReLU between them and none after the last.
class Mlp {
 public:
  struct Workspace {
    Eigen::VectorXf ping, pong;
  };

  Mlp() = default;
  explicit Mlp(std::vector<DenseLayer> layers);
  /// Reads `<prefix><name>/weight` and `<prefix><name>/bias` for each name, checking shapes chain.
  static Mlp Load(const h5::File& file, const std::string& prefix,
                  const std::vector<std::string>& names);
  /// Writes what Load reads: `<prefix><names[i]>/weight` [out x in] and `/bias` [out] (float).
  void Save(h5::File* file, const std::string& prefix, const std::vector<std::string>& names) const;
  /// The network of an artifact whose layer names (evaluation order) are the comma-separated string
  /// attribute `names_attr` of `group` (e.g. /model dense_layers); weights under `prefix`. A
  /// non-finite weight is an Error naming the file.
  static Mlp LoadListed(const h5::File& file, const std::string& group,
                        const std::string& names_attr, const std::string& prefix);
  /// Writes what LoadListed reads.
  void SaveListed(h5::File* file, const std::string& group, const std::string& names_attr,
                  const std::string& prefix, const std::vector<std::string>& names) const;

  int input_size() const { return static_cast<int>(layers_.front().weight.cols()); }
  int output_size() const { return static_cast<int>(layers_.back().weight.rows()); }
  const std::vector<DenseLayer>& layers() const { return layers_; }

  Workspace MakeWorkspace() const;
  /// @param input [input_size]. @return a view of the output [output_size] inside `ws`.
  Eigen::Ref<const Eigen::VectorXf> Forward(const Eigen::Ref<const Eigen::VectorXf>& input,
                                            Workspace* ws) const;

 private:
  std::vector<DenseLayer> layers_;
  int max_width_ = 0;
};

}  // namespace foresight
