#pragma once
/// Directional grid maps (Senanayake and Ramos 2018), the baselines of thesis ch 4: the plane is
/// cut into cells; each cell holds one von Mises fitted by maximum likelihood (UM) or a mixture
/// initialised by clustering and refined by EM (MM). The "dense" variants blend the cells around a
/// query with RBF weights. Torch-free.
///
/// Cells: cells_x x cells_y rectangles of w = (x_max - x_min) / cells_x by h = (y_max - y_min) /
/// cells_y metres; cell (ix, iy) has index iy * cells_x + ix (x fastest) and centre
/// (x_min + (ix + 1/2) w, y_min + (iy + 1/2) h). A point outside the extent belongs to the nearest
/// cell (indices clamped), for training and for queries.
///
/// Fitting one cell from its headings theta_1..n (n = 0: uniform, alpha = (1, 0, ..), kappa = 0):
/// - UM: (mu, kappa) = FitVonMises (maximum likelihood), kappa capped at max_kappa.
/// - MM: an initial mixture from clustering, each cluster's share and ML von Mises, then EM (at
/// most
///   em_iterations, until the log-likelihood gains less than 1e-9 n); components whose
///   responsibilities vanish are dropped. The clustering (`mixture_init`):
///   * kDbscan (default, as the reference code of Senanayake and Ramos, see the dataset README):
///     DBSCAN on the unit vectors (cos, sin) with chord radius dbscan_eps and dbscan_min_samples
///     (scikit-learn defaults 0.5 and 5, a point counting itself) gives the number of modes and the
///     initial clusters (the `components` largest are kept; noise points only enter EM). No
///     cluster: one component from all headings.
///   * kKMeansBic: for r = 1..min(components, n), spherical k-means with r clusters (k-means++
///     seeding, seeded per cell from `seed`) then EM; the r with the lowest
///     BIC = -2 log L + (3r - 1) log n is kept.
///   * kKMeansFixed: k-means with min(components, n) clusters then EM.
/// - Every kappa is capped at max_kappa: a cell whose headings coincide (repeated, quantised
///   way-points) has ML kappa = inf, whose density would make the AL metric meaningless.
///
/// Dense variants (thesis ch 4 "dense variants", after Flow/Senanayake 2018): cells become
/// overlapping discs of radius rho = max(w, h) (the distance from a cell centre to its neighbours'
/// centres) around the cell centres; each cell is fitted as above on every training point within
/// rho of its centre. A query q (clamped into the extent) blends the non-empty cells c whose centre
/// is within rho of q with weights w_c = exp(-|q - c|^2 / (2 length_scale^2)):
///   p(theta | q) = sum_c (w_c / sum_c' w_c') sum_r alpha_cr VM(theta; mu_cr, kappa_cr),
/// returned as the union of the cells' components with alphas alpha_cr w_c / sum w (cells in the
/// window order, row by row; unused columns alpha 0). No non-empty cell in reach: uniform.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/von_mises.h"
#include "datasets/directional.h"

namespace foresight::directional {

enum class GridKind { kUnimodal, kMultimodal };
/// How MM cells find their initial mixture (see above).
enum class GridMixtureInit { kDbscan, kKMeansBic, kKMeansFixed };

struct GridConfig {
  GridKind kind = GridKind::kUnimodal;
  int cells_x = 10, cells_y = 10;
  Eigen::Vector4d extent = Eigen::Vector4d(0, 10, 0, 10);  ///< x_min, x_max, y_min, y_max (m)
  int components = 5;                                      ///< MM only
  bool dense = false;
  double length_scale = 1.0;  ///< m, RBF blending of the dense variant
  std::uint64_t seed = 0;     ///< clustering initialisation
  double max_kappa = 100.0;   ///< cap on every fitted concentration (see above)
  GridMixtureInit mixture_init = GridMixtureInit::kDbscan;  ///< MM initialisation
  double dbscan_eps = 0.5;     ///< MM kDbscan: neighbourhood radius, chord between unit vectors
  int dbscan_min_samples = 5;  ///< MM kDbscan: neighbours (self included) of a core point
  int em_iterations = 20;      ///< MM: EM iterations (the reference code's max_iter)
};

class GridMap {
 public:
  /// Fits every cell; cells without data answer the uniform distribution on the circle (kappa 0).
  static GridMap Fit(const DirectionalSamples& train, const GridConfig& config);
  const GridConfig& config() const { return config_; }
  /// Mixture at each (x, y) [n]: fills `out` (Resize'd to n x components; unused components alpha
  /// 0). Queries outside the extent use the nearest cell. The number of columns is
  /// output_components(). Does not allocate when `out` already has that shape. Sizes of x and y
  /// differ or a non-finite coordinate: Error.
  void Query(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& y,
             VonMisesMixtureBatch* out) const;

  /// Columns of Query's output: R = 1 (UM) or components (MM); dense: R times the number of
  /// cells of the blending window, (2 ceil(rho / w) + 1) (2 ceil(rho / h) + 1).
  int output_components() const { return cell_components() * window_cells_; }
  /// Columns per cell: 1 (UM) or components (MM).
  int cell_components() const { return static_cast<int>(cells_.alpha.cols()); }
  int num_cells() const { return config_.cells_x * config_.cells_y; }
  /// Index of the cell holding (x, y), clamped into the grid.
  int CellIndex(double x, double y) const;
  Eigen::Vector2d CellCentre(int cell) const;
  /// Number of training samples that fitted each cell [num_cells()].
  const std::vector<int>& cell_counts() const { return counts_; }
  /// Fitted mixtures per cell [num_cells() x cell_components()].
  const VonMisesMixtureBatch& cells() const { return cells_; }

 private:
  GridConfig config_;
  VonMisesMixtureBatch cells_;  ///< row = cell (row-major over x then y), R columns
  std::vector<int> counts_;     ///< training samples per cell
  double cell_w_ = 1, cell_h_ = 1, radius_ = 1;  ///< m; radius_: dense disc radius
  int window_x_ = 0, window_y_ = 0;  ///< dense: half-width of the blending window in cells
  int window_cells_ = 1;             ///< cells per blending window (1 unless dense)
};

}  // namespace foresight::directional
