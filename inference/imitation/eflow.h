#pragma once
/// Euclideanizing Flows (Rana, Li, Fox, Boots, Ramos, Ratliff, "Euclideanizing Flows: Diffeomorphic
/// Reduction for Learning Stable Dynamical Systems", L4DC 2020), the thesis's baseline "Eflow"
/// (ch 8, "Baseline Methods"): the torch-free engine of a net trained by
/// models/imitation/eflow_net.h.
///
/// psi = L_{L-1} o ... o L_0, affine coupling layers. Layer l changes one coordinate b = l mod d
/// and keeps the others, a = (0..d-1 without b) in ascending order, fixed:
///   y_a = x_a,  y_b = x_b exp(s_l(x_a)) + t_l(x_a),
///   s_l(u) = sigma_l' r_l(u),  t_l(u) = tau_l' r_l(u),
///   r_l(u) = sqrt(2/F) cos(Omega_l u + beta_l)   (random Fourier features, F per layer),
/// with Omega_l [F x (d-1)], beta_l [F] fixed at training time and sigma_l, tau_l [F] learned.
/// Its Jacobian is the product of the block-triangular layer Jacobians, J = J_{L-1} ... J_0, with
///   dy_b/dx_b = exp(s),  dy_b/dx_a = x_b exp(s) ds/du + dt/du,
///   ds/du = -sqrt(2/F) sum_k sigma_k sin(Omega_k u + beta_k) Omega_k'   (likewise dt/du with tau),
/// and its inverse is exact, layer by layer: x_b = (y_b - t(y_a)) exp(-s(y_a)).
///
/// The system is the same natural-gradient attractor as the thesis's (rbf_flow.h, errata: solve
/// with J, never form G^-1):
///   f(x) = -speed * J(x)^-1 (z - z_e) / ||z - z_e||,  z = psi(x),  z_e = psi(x_goal),
/// and 0 at z = z_e.
///
/// Model/workspace contract: the model is immutable after Load; every method is const and
/// thread-safe. Internal buffers live on the stack (d <= kMaxDimension); the only allocations are
/// the returned vectors (and *J when its size changes).

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace foresight::imitation {

inline constexpr const char* kEFlowModelType = "diffeo_eflow";

/// One affine coupling layer (see the file comment).
struct EFlowCouplingLayer {
  int transformed = 0;        ///< b, the coordinate the layer changes
  Eigen::MatrixXd omega;      ///< Omega [F x (d-1)], columns in ascending order of the fixed a
  Eigen::VectorXd phase;      ///< beta [F], radians
  Eigen::VectorXd scale;      ///< sigma [F], readout of s
  Eigen::VectorXd translate;  ///< tau [F], readout of t
};

class EFlowModel {
 public:
  static constexpr int kMaxDimension = 8;

  EFlowModel() = default;
  /// @param dimension d in [2, kMaxDimension]; @param layers L >= 1, all with the same F >= 1,
  /// layer l changing coordinate l mod d; @param goal [d] the attractor x_goal; @param speed > 0.
  /// Every value finite. An Error naming `source` and the offending layer and field otherwise.
  EFlowModel(int dimension, std::vector<EFlowCouplingLayer> layers, Eigen::VectorXd goal,
             double speed, const std::string& source = "eflow model");

  /// Loads a "diffeo_eflow" artifact; every shape and value is checked (an Error naming the file
  /// and the field otherwise).
  static EFlowModel Load(const std::string& path);
  /// Writes the artifact atomically (the schema: the file comment of eflow.cc).
  void Save(const std::string& path, const std::string& config_yaml, std::int64_t seed) const;

  /// Forward, Inverse and Velocity answer a finite state with finite numbers or throw an Error
  /// naming the model's source: finite weights can still overflow double range for some states
  /// (e.g. an edited artifact), and that must not pass as an answer.
  /// z = psi(x) [d]; with J not null also J = d psi/dx [d x d].
  Eigen::VectorXd Forward(const Eigen::VectorXd& x, Eigen::MatrixXd* J = nullptr) const;
  /// x = psi^-1(z) (exact).
  Eigen::VectorXd Inverse(const Eigen::VectorXd& z) const;
  /// f(x) (file comment).
  Eigen::VectorXd Velocity(const Eigen::VectorXd& x) const;
  /// "Eflow with a repulsor" (the thesis's baseline 4): f(x) overlaid with a push down the
  /// occupancy gradient,
  ///   x_dot = f(x) - beta * grad_x p(o = 1 | x),
  /// i.e. gradient descent on the potential beta * p(o = 1 | x) added to the learned field
  /// (Khatib-style). beta >= 0 [length^2 / time] scales the push; grad p [d] in 1/length comes from
  /// the occupancy map (e.g. inference/imitation/occupancy_field.h). The overlay has NO stability
  /// guarantee (the thesis notes so): it can create spurious equilibria where f(x) = beta grad p,
  /// and a goal inside occupied space is no longer reached. Non-finite grad_p or a negative or
  /// non-finite beta is an Error.
  Eigen::VectorXd VelocityWithRepulsor(const Eigen::VectorXd& x, const Eigen::VectorXd& grad_p,
                                       double beta) const;

  int dimension() const { return dimension_; }
  int num_layers() const { return static_cast<int>(layers_.size()); }
  int num_features() const {
    return layers_.empty() ? 0 : static_cast<int>(layers_[0].phase.size());
  }
  const std::vector<EFlowCouplingLayer>& layers() const { return layers_; }
  const Eigen::VectorXd& goal() const { return goal_; }
  const Eigen::VectorXd& goal_image() const { return goal_image_; }  ///< z_e = psi(goal)
  double speed() const { return speed_; }

 private:
  int dimension_ = 0;
  std::vector<EFlowCouplingLayer> layers_;
  Eigen::VectorXd goal_, goal_image_;
  double speed_ = 1;
  std::string source_;  ///< the artifact's path (named by the errors of the queries)

  /// An Error naming source_ when a finite `x` gave a non-finite `what`.
  void CheckAnswer(bool finite, const Eigen::VectorXd& x, const char* what) const;
};

}  // namespace foresight::imitation
