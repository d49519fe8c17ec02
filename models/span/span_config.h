#pragma once
/// Configuration of the SPAN pedestrian predictor (thesis ch 5) and its mixture variant (ch 7).
/// Torch-free so the config reference and the data preparation need no LibTorch.

#include <vector>

#include "core/config.h"
#include "core/matrix_normal_head.h"

namespace foresight::span {

/// Continuous trajectory representation of the futures: o(t) = W' phi(t), t from the present.
struct TrajectoryBasisConfig {
  int num_centres = 8;         ///< m
  double gamma = 1.0;          ///< phi(t, t') = exp(-gamma (t - t')^2), 1/s^2
  double margin = 1.0;         ///< centres span [-margin, T + margin] (s): edges fit without bias
  double ridge_lambda = 1e-4;  ///< ridge penalty of the fit (thesis eq. lsuqares)
  /// Include o(0) = present position in the fit. Off by default: the anchor makes phi(0)' W = 0
  /// hold exactly, a degenerate direction of the weight distribution that the NLL exploits.
  bool anchor_at_origin = false;

  template <class A>
  void Serialize(A* a) {
    a->Visit("num_centres", &num_centres, config::Range::Closed(1, 64),
             "m, basis functions evenly spaced over the prediction horizon");
    a->Visit("gamma", &gamma, config::Range::Positive(), "RBF parameter gamma (1/s^2)");
    a->Visit("margin", &margin, config::Range::NonNegative(),
             "centres extend this far (s) before t = 0 and beyond the horizon; 0 = on [0, T]");
    a->Visit("ridge_lambda", &ridge_lambda, config::Range::NonNegative(),
             "ridge penalty lambda of the future fit");
    a->Visit("anchor_at_origin", &anchor_at_origin, config::Range::Any(),
             "fit the future together with the present position (continuity at t = 0)");
  }
};

struct NetConfig {
  std::vector<int> hidden = {100, 100, 100};  ///< widths of the ReLU layers (thesis: 3 x 100)
  int components = 1;                         ///< R; 1 is SPAN, > 1 the mixture of ch 7
  UParam u_param = UParam::kCholesky;
  bool rotate_to_heading = true;  ///< express inputs and outputs in the ego frame
  /// Model the future relative to constant velocity: o(t) = origin + v t + W' phi(t), with v the
  /// last observed step's velocity (an extension of the thesis, which has v = 0).
  bool residual_to_constant_velocity = false;

  template <class A>
  void Serialize(A* a) {
    a->Visit("hidden", &hidden, config::Range::Closed(1, 4096), "hidden layer widths (ReLU)");
    a->Visit("components", &components, config::Range::Closed(1, 32),
             "R, matrix-normal mixture components (1 = SPAN)");
    a->VisitEnum(
        "u_param", &u_param,
        config::EnumNames<UParam>{{UParam::kCholesky, "cholesky"}, {UParam::kDiagonal, "diagonal"}},
        "parameterisation of the row scale U (full Cholesky or log-diagonal)");
    a->Visit("rotate_to_heading", &rotate_to_heading, config::Range::Any(),
             "rotate each window so the observed heading is +x (predictions rotate back exactly)");
    a->Visit("residual_to_constant_velocity", &residual_to_constant_velocity, config::Range::Any(),
             "W models the deviation from constant velocity (o(t) = origin + v t + W' phi(t))");
  }
};

/// Training-set augmentation (an extension of the thesis). Every training window also enters at
/// each speed scale s (positions relative to the present times s at the same times: a walk s times
/// as fast along a path s times as large, turn radii included) and, with `mirror`, reflected about
/// the heading (ego y -> -y; about the world x axis through the present point when
/// rotate_to_heading is off). Inputs and ridge targets are linear in the positions, so a copy is
/// the sample of the transformed window, except where the ego frame's 1 mm threshold for a
/// heading would fall differently (near-standing windows). Validation and test windows are never
/// augmented.
struct AugmentConfig {
  std::vector<double> speed_scales = {};  ///< extra scales besides 1 (empty: none)
  bool mirror = false;

  template <class A>
  void Serialize(A* a) {
    a->Visit("speed_scales", &speed_scales, config::Range::Closed(0.1, 10.0),
             "each training window is added again at each of these speed scales (s != 1)");
    a->Visit("mirror", &mirror, config::Range::Any(),
             "add each training window (and its scaled copies) mirrored about its heading");
  }
  /// Training samples per original window.
  int Copies() const { return (1 + static_cast<int>(speed_scales.size())) * (mirror ? 2 : 1); }
};

}  // namespace foresight::span
