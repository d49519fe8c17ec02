#include "training/gfcs/config.h"

#include <set>

#include "core/error.h"

namespace foresight::gfcs {

void ExperimentConfig::Validate(const std::string& path) const {
  FS_THROW_UNLESS(model == "gfcs", path, ": model: '", model, "', expected 'gfcs'");
  FS_THROW_UNLESS(!robot.empty(), path, ": robot: empty (a folder or 'builtin')");
  FS_THROW_UNLESS(!train_problems.empty(), path, ": train_problems: empty list");
  FS_THROW_UNLESS(gfcs.commands >= 2, path, ": gfcs.commands: ", gfcs.commands,
                  ", the learned sampler needs at least one intermediate command (2)");
  const auto check_set = [&](const manipulation::ProblemsConfig& p, const std::string& key) {
    FS_THROW_UNLESS(p.first <= p.last, path, ": ", key, ": first (", p.first, ") is after last (",
                    p.last, ")");
    FS_THROW_UNLESS(p.source != manipulation::ProblemSource::kMotionBenchMaker || !p.family.empty(),
                    path, ": ", key, ".family: empty");
    if (p.source == manipulation::ProblemSource::kSynthetic)
      p.scene.Validate(path + ": " + key + ".scene");
  };
  for (std::size_t i = 0; i < train_problems.size(); ++i)
    check_set(train_problems[i], "train_problems[" + std::to_string(i) + "]");
  for (std::size_t i = 0; i < eval.problems.size(); ++i)
    check_set(eval.problems[i], "eval.problems[" + std::to_string(i) + "]");
  // Held-out means held out: no MotionBenchMaker problem both trains and tests.
  for (const manipulation::ProblemsConfig& t : train_problems)
    for (const manipulation::ProblemsConfig& e : eval.problems)
      if (t.source == manipulation::ProblemSource::kMotionBenchMaker &&
          e.source == manipulation::ProblemSource::kMotionBenchMaker && t.family == e.family)
        FS_THROW_UNLESS(t.last < e.first || e.last < t.first, path, ": eval.problems: ", e.family,
                        " ", e.first, "-", e.last, " overlaps the training problems ", t.first, "-",
                        t.last);
  FS_THROW_UNLESS(lattice.lower.x() < lattice.upper.x() && lattice.lower.y() < lattice.upper.y() &&
                      lattice.lower.z() < lattice.upper.z(),
                  path, ": lattice: lower must be below upper on every axis");
  FS_THROW_UNLESS(!eval.batches.empty(), path, ": eval.batches: empty list");
  std::set<int> budgets;
  for (int b : eval.batches) {
    FS_THROW_UNLESS(b >= 1 && b <= 1000, path, ": eval.batches: ", b, " is outside [1, 1000]");
    FS_THROW_UNLESS(budgets.insert(b).second, path, ": eval.batches: ", b, " listed twice");
  }
  std::set<std::string> names;
  for (const manipulation::PlanMethodConfig& m : eval.baselines) {
    FS_THROW_UNLESS(m.kind != manipulation::PlanMethodKind::kGfcs, path, ": eval.baselines: '",
                    m.name, "' is GFCS (GFCS rows come from eval.batches)");
    FS_THROW_UNLESS(names.insert(m.name).second, path, ": eval.baselines: '", m.name,
                    "' listed twice");
    FS_THROW_UNLESS(m.name.rfind("GFCS uniform (", 0) != 0 && m.name.rfind("GFCS learned ", 0) != 0,
                    path, ": eval.baselines: '", m.name, "' is the name of a generated GFCS row");
    FS_THROW_UNLESS(m.uniform_share == 0, path, ": eval.baselines: '", m.name,
                    "' sets uniform_share (only the learned GFCS rows use it: eval.uniform_share)");
  }
  FS_THROW_UNLESS(fabric.t_max >= fabric.dt, path, ": fabric.t_max (", fabric.t_max,
                  ") is below fabric.dt (", fabric.dt, ")");
}

}  // namespace foresight::gfcs
