#include "inference/manipulation/nearest_sampler.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/error.h"

namespace foresight::manipulation {

NearestSampler::NearestSampler(const EnergyModel& model, int per_problem)
    : ContextSampler(model), per_problem_(per_problem) {
  FS_THROW_UNLESS(per_problem >= 1, "NearestSampler: per_problem ", per_problem,
                  " must be at least 1");
  const SolutionMemory& m = model.parts().memory;
  FS_THROW_UNLESS(!m.empty(),
                  "NearestSampler: the energy model has no solution memory (/memory: an artifact "
                  "of a loop run by an older build; export the run again)");
  const Eigen::Index n = m.contexts.rows();
  const Eigen::Index problems = m.contexts.cols();
  const Eigen::MatrixXd ctx = m.contexts.cast<double>();
  const Eigen::VectorXd mean = ctx.rowwise().mean();
  inv_spread_ = Eigen::VectorXd::Zero(n);
  weight_ = Eigen::VectorXd::Zero(n);
  int varying[2] = {0, 0};  // state block, encoding block
  const auto block = [](Eigen::Index i) { return i < EnergyModel::kStateContext ? 0 : 1; };
  for (Eigen::Index i = 0; i < n; ++i) {
    const double var =
        (ctx.row(i).transpose() - Eigen::VectorXd::Constant(problems, mean[i])).squaredNorm() /
        static_cast<double>(problems);
    const double spread = std::sqrt(var);
    if (spread > 1e-6) {
      inv_spread_[i] = 1.0 / spread;
      ++varying[block(i)];
    }
  }
  for (Eigen::Index i = 0; i < n; ++i)
    if (inv_spread_[i] > 0) weight_[i] = 1.0 / varying[block(i)];
  by_problem_.assign(static_cast<std::size_t>(problems), {});
  for (Eigen::Index s = 0; s < m.problem.size(); ++s)
    by_problem_[static_cast<std::size_t>(m.problem[s])].push_back(static_cast<int>(s));
  for (std::vector<int>& list : by_problem_)
    std::stable_sort(list.begin(), list.end(), [&](int a, int b) { return m.cost[a] < m.cost[b]; });
}

Eigen::VectorXd NearestSampler::Distances(const Eigen::VectorXf& context) const {
  const Eigen::MatrixXf& contexts = model_.parts().memory.contexts;
  FS_THROW_UNLESS(context.size() == contexts.rows(), "NearestSampler: a context of ",
                  context.size(), " entries, the memory's have ", contexts.rows());
  Eigen::VectorXd d(contexts.cols());
  for (Eigen::Index p = 0; p < contexts.cols(); ++p) {
    const Eigen::ArrayXd z =
        (context.cast<double>() - contexts.col(p).cast<double>()).array() * inv_spread_.array();
    d[p] = (z.square() * weight_.array()).sum();
  }
  return d;
}

void NearestSampler::Sample(const GfcsQuery& query, int intermediate_commands, int count,
                            std::mt19937_64* rng, Eigen::MatrixXd* out) {
  const Eigen::VectorXd d =
      Distances(PrepareContext("NearestSampler", query, intermediate_commands, count));
  std::vector<int> order(static_cast<std::size_t>(d.size()));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return d[a] < d[b]; });
  const SolutionMemory& m = model_.parts().memory;
  out->resize(model_.command_size(), count);
  int c = 0;
  last_problems_ = 0;
  for (int p : order) {
    if (c >= count) break;
    const std::vector<int>& list = by_problem_[static_cast<std::size_t>(p)];
    if (list.empty()) continue;
    ++last_problems_;
    for (std::size_t k = 0; k < list.size() && static_cast<int>(k) < per_problem_ && c < count; ++k)
      out->col(c++) = model_.CommandsToRadians(m.commands.col(list[k]));
  }
  last_filled_ = count - c;
  FillUniform(model_.parts().lower, model_.parts().upper, c, rng, out);
}

}  // namespace foresight::manipulation
