#pragma once
/// Output layout of the matrix-normal mixture head (thesis ch 5 for R = 1, ch 7 for R > 1),
/// shared by the LibTorch model (models/span) and the Eigen engine (inference/prediction).
///
/// Per component r, in this order (raw network outputs z):
///   [0]                 alpha logit              alpha = softmax(z)
///   [1, 1 + 2m)         M row-major (m x 2)      identity
///   U block             cholesky: m(m+1)/2 entries of L_U, rows in order (i, j <= i);
///                                 diagonal entries exp(clamp(z)), off-diagonal identity
///                       diagonal: m entries, diag(L_U) = exp(clamp(z))
///   V block (3)         L_V = [[exp(clamp(z0)), 0], [z1, exp(clamp(z2))]]
/// U = L_U L_U', V = L_V L_V' are positive definite by construction.

namespace foresight {

enum class UParam { kCholesky, kDiagonal };

struct HeadLayout {
  int basis = 8;       ///< m, number of trajectory basis functions
  int components = 1;  ///< R
  UParam u_param = UParam::kCholesky;

  /// Bounds on the log-diagonal of the Cholesky factors: exp stays finite, and the scales cannot
  /// collapse onto directions the ridge targets happen to pin down (NLL -> -inf otherwise).
  static constexpr double kLogDiagMin = -5.0;
  static constexpr double kLogDiagMax = 8.0;

  int UBlock() const { return u_param == UParam::kCholesky ? basis * (basis + 1) / 2 : basis; }
  int PerComponent() const { return 1 + 2 * basis + UBlock() + 3; }
  int Total() const { return components * PerComponent(); }
  int AlphaOffset(int r) const { return r * PerComponent(); }
  int MeanOffset(int r) const { return r * PerComponent() + 1; }
  int UOffset(int r) const { return r * PerComponent() + 1 + 2 * basis; }
  int VOffset(int r) const { return UOffset(r) + UBlock(); }
};

inline const char* UParamName(UParam u) { return u == UParam::kCholesky ? "cholesky" : "diagonal"; }

}  // namespace foresight
