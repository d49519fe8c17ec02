#pragma once
/// Nearest-neighbour directional maps: the baseline that a learned map must beat (issue 11). A
/// query answers the headings of its k nearest training samples, each a von Mises of a fixed
/// concentration:
///   p(theta | q) = (1/k) sum_{j in N_k(q)} VM(theta; theta_j, kappa),
/// with N_k(q) the k training samples nearest to q in Euclidean distance over (x, y), or over
/// (x, y, time_scale * t) when use_time (time_scale in m/s turns seconds into metres). Ties in
/// distance go to the lower training index, so the answer is deterministic. k = 1 is "the
/// nearest training heading at concentration kappa", whose AL is set by kappa (a spike peaks at
/// ~sqrt(kappa / (2 pi)) / rad): compare it with other maps at the same cap.
///
/// Search: a k-d tree (median splits on the widest coordinate, leaves of up to 8 points) built
/// once in Fit; a query visits a subtree unless the squared distance to its splitting plane
/// exceeds the current k-th best (equal distances are visited, for the tie rule). Torch-free.

#include <Eigen/Core>
#include <vector>

#include "core/von_mises.h"
#include "datasets/directional.h"

namespace foresight::directional {

struct KnnConfig {
  int k = 1;                ///< neighbours per query (1 <= k <= training samples)
  double kappa = 100;       ///< concentration of every component (> 0); the AL cap
  bool use_time = false;    ///< neighbours in (x, y, time_scale * t) instead of (x, y)
  double time_scale = 1.0;  ///< m per s when use_time (> 0)
};

class KnnMap {
 public:
  /// Stores the training samples (validated: finite, theta in [-pi, pi)) and builds the tree.
  /// Bad config (k < 1, k > n, kappa <= 0, time_scale <= 0): Error naming the field and value.
  static KnnMap Fit(const DirectionalSamples& train, const KnnConfig& config);

  /// Mixture at each query (x, y, t) [n each; t is ignored, and may be empty, unless use_time]:
  /// k components of weight 1/k, mean = the neighbours' headings (nearest first; equal distances
  /// by training index), kappa = config.kappa. Fills `out` [n x k]; does not allocate when `out`
  /// has that shape already (the search keeps its candidates in `out`). Size mismatch or a
  /// non-finite query coordinate: Error naming the query.
  void Query(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& y,
             const Eigen::Ref<const Eigen::VectorXd>& t, VonMisesMixtureBatch* out) const;

  /// Training indices of the k nearest samples of one query point, nearest first (for tests and
  /// plots; allocates). `t` is ignored unless use_time.
  std::vector<Eigen::Index> Neighbours(double x, double y, double t) const;

  const KnnConfig& config() const { return config_; }
  /// Training samples in the map.
  Eigen::Index size() const { return theta_.size(); }

 private:
  struct Node {
    Eigen::Index begin = 0, end = 0;  ///< range of order_ (tree order)
    int dim = -1;                     ///< split coordinate; -1: leaf
    double split = 0;                 ///< left: coordinate <= split; right: >= split
    int left = -1, right = -1;
  };
  /// Search state of one query: candidates (squared distance, training index) kept sorted.
  struct Candidates;

  int Build(Eigen::Index begin, Eigen::Index end);
  void Search(int node, const double* q, Candidates* c) const;
  void FindNearest(const double* q, Candidates* c) const;

  KnnConfig config_;
  int dims_ = 2;
  Eigen::MatrixXd points_;           ///< [dims x n] coordinates in tree order
  std::vector<Eigen::Index> order_;  ///< tree position -> training index
  Eigen::VectorXd theta_;            ///< [n] training headings (training order)
  std::vector<Node> nodes_;          ///< nodes_[0] is the root
};

}  // namespace foresight::directional
