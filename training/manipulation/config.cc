#include "training/manipulation/config.h"

#include <set>

#include "core/error.h"

namespace foresight::manipulation {

std::vector<PlanMethodConfig> DefaultPlanMethods() {
  return {{"GF", PlanMethodKind::kFabric, 1, 1.2},
          {"Bi-EST", PlanMethodKind::kBiEst, 1, 60},
          {"BIT* (1.2s)", PlanMethodKind::kBitStar, 1, 1.2},
          {"BIT* (6s)", PlanMethodKind::kBitStar, 1, 6},
          {"RRT-Connect", PlanMethodKind::kRrtConnect, 1, 60},
          {"GFCS (1 batch)", PlanMethodKind::kGfcs, 1, 1.2},
          {"GFCS (5 batches)", PlanMethodKind::kGfcs, 5, 1.2}};
}

void ExperimentConfig::Validate(const std::string& path) const {
  FS_THROW_UNLESS(model == "manipulation", path, ": model: '", model, "', expected 'manipulation'");
  FS_THROW_UNLESS(!methods.empty(), path, ": methods: empty list");
  std::set<std::string> names;
  for (const PlanMethodConfig& m : methods) {
    FS_THROW_UNLESS(!m.name.empty(), path, ": methods: a method has an empty name");
    FS_THROW_UNLESS(names.insert(m.name).second, path, ": methods: '", m.name, "' listed twice");
  }
  FS_THROW_UNLESS(problems.first <= problems.last, path, ": problems: first (", problems.first,
                  ") is after last (", problems.last, ")");
  FS_THROW_UNLESS(problems.source != ProblemSource::kMotionBenchMaker || !problems.family.empty(),
                  path, ": problems.family: empty");
  if (problems.source == ProblemSource::kSynthetic)
    problems.scene.Validate(path + ": problems.scene");
  FS_THROW_UNLESS(!robot.empty(), path, ": robot: empty (a folder or 'builtin')");
  for (const PlanMethodConfig& m : methods)
    FS_THROW_UNLESS(m.sampler == GfcsSamplerKind::kUniform || !energy_model.empty(), path,
                    ": methods: '", m.name, "' uses the ",
                    m.sampler == GfcsSamplerKind::kLearned ? "learned" : "nearest",
                    " sampler, but energy_model (the artifact) is empty");
  // Options of the learned sampler: set only on a gfcs method with sampler: learned.
  for (const PlanMethodConfig& m : methods) {
    const bool learned = m.kind == PlanMethodKind::kGfcs && m.sampler == GfcsSamplerKind::kLearned;
    const auto learned_only = [&](bool set, const auto&... what) {
      FS_THROW_UNLESS(!set || learned, path, ": methods: '", m.name, "' sets ", what...,
                      ", which only a gfcs method with sampler: learned uses");
    };
    learned_only(m.uniform_share != 0, "uniform_share ", m.uniform_share);
    learned_only(m.sgld_pick != SgldPick::kLowestEnergy, "sgld_pick: random");
    learned_only(m.sgld_init != SgldInit::kUniform, "sgld_init: memory");
    FS_THROW_UNLESS(m.nearest_per_problem == 0 || m.sampler == GfcsSamplerKind::kNearest ||
                        m.nearest_share > 0 || m.sgld_init == SgldInit::kMemory,
                    path, ": methods: '", m.name, "' sets nearest_per_problem ",
                    m.nearest_per_problem,
                    ", which only the nearest sampler, a nearest_share or sgld_init: memory uses");
  }
  for (const PlanMethodConfig& m : methods) {
    if (m.nearest_share == 0) continue;
    FS_THROW_UNLESS(m.kind == PlanMethodKind::kGfcs && m.sampler != GfcsSamplerKind::kNearest, path,
                    ": methods: '", m.name, "' sets nearest_share ", m.nearest_share,
                    ", which only a gfcs method with sampler: uniform or learned uses");
    FS_THROW_UNLESS(!energy_model.empty(), path, ": methods: '", m.name,
                    "' sets nearest_share, but energy_model (the artifact with the solution "
                    "memory) is empty");
  }
  FS_THROW_UNLESS(fabric.t_max >= fabric.dt, path, ": fabric.t_max (", fabric.t_max,
                  ") is below fabric.dt (", fabric.dt, ")");
}

}  // namespace foresight::manipulation
