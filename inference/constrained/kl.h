#pragma once
/// KL divergence between two matrix-normal components (thesis ch 7, eq. formulationWhole's
/// objective), in closed form through vec(W) ~ N(vec(M), V kron U) (errata ch 5/7):
///   KL(p || p0) = 1/2 [ tr(V0^-1 V) tr(U0^-1 U) + tr(V0^-1 (M - M0)' U0^-1 (M - M0))
///                       - 2m + m ln(|V0| / |V|) + 2 ln(|U0| / |U|) ],
/// for U = diag(exp(log_u)) (component.h). Tested against the multivariate-Gaussian formula on the
/// explicit 2m x 2m Kronecker covariance, and its gradient against finite differences.

#include "inference/constrained/component.h"

namespace foresight::constrained {

/// KL(p || p0); with `gradient` not null also d KL / d p's parameters. Error when the bases differ.
double MatrixNormalKl(const ComponentParams& p, const ComponentParams& p0,
                      ComponentGradient* gradient);

}  // namespace foresight::constrained
