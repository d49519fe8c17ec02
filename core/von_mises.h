#pragma once
/// Von Mises distributions and mixtures on the circle (thesis ch 4; errata: stable log I0).
///   p(theta | mu, kappa) = exp(kappa cos(theta - mu)) / (2 pi I0(kappa)).
/// Angles in radians; WrapAngle maps to [-pi, pi).

#include <Eigen/Core>
#include <random>

namespace foresight {

/// theta wrapped to [-pi, pi).
double WrapAngle(double theta);
/// log I0(kappa) for kappa >= 0, finite for any finite kappa (exponentially scaled form above
/// ~700).
double LogBesselI0(double kappa);
/// log I0(kappa) - kappa = log of the exponentially scaled Bessel function (errata ch 4): finite
/// for every finite kappa >= 0, -> -0.5 log(2 pi kappa) as kappa -> inf. Negative or NaN kappa is
/// an Error.
double LogBesselI0Scaled(double kappa);
/// A1(kappa) = I1(kappa) / I0(kappa), and its inverse (maximum-likelihood kappa from the mean
/// resultant length R in [0, 1); R >= 1 - 1e-12 gives a large finite cap).
double BesselRatioA1(double kappa);
double InverseA1(double r);
/// dA1/dkappa = 1 - A1/kappa - A1^2 (1/2 at kappa = 0); used by the Newton steps of InverseA1.
double BesselRatioA1Derivative(double kappa);

double VonMisesLogDensity(double theta, double mu, double kappa);

/// Mixture with weights alpha [R] (sum 1), means mu [R], concentrations kappa [R] (>= 0).
double VonMisesMixtureLogDensity(double theta, const Eigen::Ref<const Eigen::VectorXd>& alpha,
                                 const Eigen::Ref<const Eigen::VectorXd>& mu,
                                 const Eigen::Ref<const Eigen::VectorXd>& kappa);
/// Samples theta from one von Mises (Best and Fisher 1979), wrapped to [-pi, pi).
double SampleVonMises(double mu, double kappa, std::mt19937_64* rng);

/// Maximum-likelihood (mu, kappa) from weighted angles (weights >= 0, sum > 0).
struct VonMisesFit {
  double mu = 0, kappa = 0;
};
VonMisesFit FitVonMises(const Eigen::Ref<const Eigen::VectorXd>& theta,
                        const Eigen::Ref<const Eigen::VectorXd>& weight);

/// Mixture parameters for n queries with R components: row i holds query i's alpha, mu, kappa.
struct VonMisesMixtureBatch {
  Eigen::MatrixXd alpha, mu, kappa;  ///< [n x R] each
  void Resize(Eigen::Index n, Eigen::Index r) {
    alpha.resize(n, r);
    mu.resize(n, r);
    kappa.resize(n, r);
  }
};

/// Thesis ch 4 metrics over held-out headings theta [n] with their predicted mixtures:
/// AL = mean_n p(theta_n) (density, 1/rad), MRE = mean_n min_r |wrap(theta_n - mu_r)| (rad).
/// MRE uses the wrapped angular difference (the thesis prints |theta - mu|; on the circle the
/// difference must be wrapped, see the code note).
double AverageLikelihood(const VonMisesMixtureBatch& mixtures,
                         const Eigen::Ref<const Eigen::VectorXd>& theta);
double MinimumRotationError(const VonMisesMixtureBatch& mixtures,
                            const Eigen::Ref<const Eigen::VectorXd>& theta);
/// MRE over the components that carry weight: components with alpha_r < min_weight are ignored,
/// except that the heaviest component of each row (the first on ties) always counts, so every
/// row has one. Components with alpha_r <= 0 never count. min_weight = 0 is the overload above.
/// min_weight must be in [0, 1] (else an Error naming it). Issue 11: a mixture that parks a tiny
/// component on every heading should not score as well as one that predicts the heading.
double MinimumRotationError(const VonMisesMixtureBatch& mixtures,
                            const Eigen::Ref<const Eigen::VectorXd>& theta, double min_weight);

/// kappa = min(kappa, cap) for every component, in place: reports AL and MRE at several caps (the
/// cap sets the scale of AL: a spike of concentration kappa peaks at ~sqrt(kappa / (2 pi))).
/// cap must be > 0 (else an Error naming it); NaN kappas stay NaN.
void CapConcentration(VonMisesMixtureBatch* mixtures, double cap);

}  // namespace foresight
