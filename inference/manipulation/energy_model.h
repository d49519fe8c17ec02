#pragma once
/// The learned GFCS sampler's energy model, torch-free (thesis ch 9, self-supervised GFCS; errata:
/// good command sequences have LOW energy). E_theta(x_c, u) is a ReLU MLP over
/// [context x_c, u]: x_c = [Normalise(q_0), qd_0 / velocity_scale, Normalise(q_goal), encoding]
/// (21 + encoding_size), u = the n intermediate commands normalised to [-1, 1]^{7n}
/// (Normalise(q) = 2 (q - lower) / (upper - lower) - 1 per joint), encoding = the environment
/// encoder applied to the standardised basis point set distances (bps.h).
///
///   const EnergyModel model = EnergyModel::Load("energy.h5");   // immutable, share
///   auto ws = model.MakeWorkspace(200);                          // one per caller
///   const Eigen::VectorXf enc = model.EncodeWorld(world);        // once per problem
///   Eigen::VectorXf ctx; model.Context(query, enc, &ctx);
///   model.EnergyAndGradient(ctx, u, &E, &G, &ws);                // no allocation
///
/// Artifact (model_type "gfcs_energy", docs/artifact_schema.md conventions):
///   /model attrs intermediate_commands (int), velocity_scale, bps_spacing, bps_max_distance
///         (double), encoder_layers, energy_layers (int: number of dense layers)
///   /model/bps_lower, /model/bps_upper  float64 [3]   lattice bounds (m)
///   /model/joint_lower, /model/joint_upper float64 [7] joint limits (rad)
///   /normalisation/bps_mean, /normalisation/bps_std float32 [N_R]
///   /weights/encoder/linear<i>/{weight [out x in], bias [out]}, i = 0 .. encoder_layers - 1
///   /weights/energy/linear<i>/{weight, bias}, i = 0 .. energy_layers - 1 (the first layer's
///         input is [context, u] in that order)
///   /memory (optional: the loop's solutions, for the nearest-neighbour sampler)
///         contexts float32 [P x context]  one per solved training problem
///         problem  int64 [S]              row of `contexts` each solution solved
///         commands float32 [S x 7n]       the solution's normalised commands
///         cost     float32 [S]            its GFCOP cost (s)
///
/// Batched evaluation: the first layer's context part W1[:, :context] x_c + b1 is computed once
/// per call, then each layer is one GEMM over the P particles (float, Eigen's GEMM kernels with a
/// cache-blocking buffer held in the workspace, so nothing is allocated); the gradient dE/du
/// comes from a hand-written backward pass through the ReLU layers (ReLU'(0) = 0, as LibTorch).

#include <Eigen/Core>
#include <chrono>
#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "core/config.h"
#include "inference/engine/dense.h"
#include "inference/manipulation/bps.h"
#include "inference/manipulation/gfcs.h"
#include "inference/manipulation/joint_types.h"
#include "inference/manipulation/world.h"

namespace foresight::manipulation {

inline constexpr const char* kEnergyModelType = "gfcs_energy";

/// Command sequences that solved the loop's training problems, with those problems' contexts: what
/// the nearest-neighbour sampler (nearest_sampler.h) retrieves from. Empty: no memory.
struct SolutionMemory {
  Eigen::MatrixXf contexts;  ///< [context_size x P] one column per solved training problem
  Eigen::VectorXi problem;   ///< [S] the column of `contexts` each solution solved
  Eigen::MatrixXf commands;  ///< [7n x S] normalised commands, in [-1, 1]
  Eigen::VectorXf cost;      ///< [S] GFCOP cost (s)
  bool empty() const { return problem.size() == 0; }
};

struct EnergyModelParts {
  BpsLattice lattice;
  Eigen::VectorXf bps_mean, bps_std;  ///< [N_R] encoder input normalisation: (d - mean) / std
  Mlp encoder;                        ///< N_R -> encoding (ReLU between layers, none after last)
  Mlp energy;                         ///< [context, u] -> 1
  JointVector lower = JointVector::Constant(-1), upper = JointVector::Constant(1);  ///< rad
  double velocity_scale = 1;      ///< qd0 / velocity_scale in the context (rad/s)
  int intermediate_commands = 1;  ///< n
  SolutionMemory memory;          ///< optional (empty: the artifact has no /memory)
};

class EnergyModel {
 public:
  static constexpr int kStateContext = 3 * kDof;  ///< 21: start, start velocity, goal

  /// Per-caller buffers for EnergyAndGradient with up to max_particles particles. Move-only.
  struct Workspace {
    struct Blocking;  ///< GEMM cache-blocking buffers (Eigen internal)
    Workspace();
    Workspace(Workspace&&) noexcept;
    Workspace& operator=(Workspace&&) noexcept;
    ~Workspace();
    int max_particles = 0;
    Eigen::VectorXf first;                ///< [width_1] W1[:, :context] x_c + b1
    std::vector<Eigen::MatrixXf> hidden;  ///< [width_l x max_particles] ReLU outputs
    Eigen::MatrixXf delta_a, delta_b;     ///< [max width x max_particles] backward signals
    std::unique_ptr<Blocking> blocking;
  };

  /// Checks shapes and values (Error naming the mismatch): a valid lattice, bps_mean/bps_std of
  /// size N_R with std finite and positive, encoder N_R -> k, energy (21 + k + 7n) -> 1, finite
  /// weights, finite limits with lower < upper, velocity_scale > 0, n >= 1; a memory, if any,
  /// with contexts of context_size rows, problem indices in range, finite costs and finite
  /// commands of 7n rows in [-1, 1].
  explicit EnergyModel(EnergyModelParts parts);
  /// Reads a "gfcs_energy" artifact; errors name the file and the dataset or attribute.
  static EnergyModel Load(const std::string& artifact_path);
  /// Writes the artifact (atomically) with the common header (config YAML, seed).
  void Save(const std::string& path, const std::string& config_yaml, std::int64_t seed) const;

  int encoding_size() const { return parts_.encoder.output_size(); }
  int context_size() const { return kStateContext + encoding_size(); }
  int command_size() const { return kDof * parts_.intermediate_commands; }
  int intermediate_commands() const { return parts_.intermediate_commands; }
  const EnergyModelParts& parts() const { return parts_; }

  Workspace MakeWorkspace(int max_particles) const;

  /// encoder((EncodeBps(world) - mean) / std) [encoding_size]. Allocates (once per problem).
  Eigen::VectorXf EncodeWorld(const World& world) const;
  /// [context_size] the context of `q` with the world encoding (resized when needed).
  void Context(const GfcsQuery& q, const Eigen::VectorXf& encoding, Eigen::VectorXf* context) const;

  /// Energies and their gradients for P particles.
  /// @param context [context_size]
  /// @param u [command_size x P] normalised commands, P <= ws->max_particles
  /// @param energy [P] E (resized when its size differs)
  /// @param grad [command_size x P] dE/du (resized when its shape differs); may be null
  /// No allocation once the outputs have their sizes.
  void EnergyAndGradient(const Eigen::VectorXf& context, const Eigen::Ref<const Eigen::MatrixXf>& u,
                         Eigen::VectorXf* energy, Eigen::MatrixXf* grad, Workspace* ws) const;

  /// 2 (q - lower) / (upper - lower) - 1.
  JointVector Normalise(const JointVector& q) const;
  JointVector Denormalise(const JointVector& u) const;
  /// [7n] normalised commands -> radians, and back.
  Eigen::VectorXd CommandsToRadians(const Eigen::Ref<const Eigen::VectorXf>& u) const;
  Eigen::VectorXf RadiansToCommands(const Eigen::Ref<const Eigen::VectorXd>& y) const;

 private:
  void ValidateMemory() const;

  EnergyModelParts parts_;
  int max_width_ = 0;
};

// ---------------------------------------------------------------------------------------------
/// Which SGLD particles LearnedSampler returns when it runs more chains than it needs.
enum class SgldPick {
  kLowestEnergy,  ///< the lowest-energy survivors (the shipped sampler)
  kRandom,        ///< survivors drawn uniformly without replacement: samples of SGLD's distribution
};

/// Stochastic gradient Langevin dynamics on the energy (errata: descends it).
struct SgldParams {
  int particles = 200;             ///< chains run in parallel
  int steps = 50;                  ///< Langevin steps
  double step_scale = 0.01;        ///< sigma2_k = step_scale (1 + k)^-0.5
  double max_dropped_share = 0.5;  ///< more non-finite particles than this share: Error
  /// Threads sharing each step's energy and gradient evaluation (the particles split into
  /// contiguous blocks). The noise is drawn on the calling thread in the same order, and each
  /// particle's evaluation does not depend on its block (tested), so the result is the same for
  /// any count. Used by LearnedSampler; RunSgld with one workspace runs on the calling thread.
  int threads = 1;
  /// LearnedSampler only (RunSgld ignores it; not a config key here: the plan harness sets it per
  /// method, methods[].uniform_share): the share of each requested batch drawn uniformly
  /// in the joint limits instead of from SGLD, rounded to the nearest count. 0 is the thesis (the
  /// whole first batch learned). A share above 0 is the defensive mixture of learned sampling
  /// for planning (Ichter, Harrison and Pavone, ICRA 2018, keep uniform samples beside learned
  /// ones): where the model's modes miss a problem the uniform part still explores.
  double uniform_share = 0.0;
  /// LearnedSampler only (like uniform_share, set per method: methods[].sgld_pick): which of the
  /// survivors fill the learned part of the batch. The lowest-energy ones concentrate on the
  /// model's modes (where those miss a problem, the whole batch misses it); random ones keep the
  /// spread of the SGLD distribution.
  SgldPick pick = SgldPick::kLowestEnergy;

  template <class A>
  void Serialize(A* a) {
    a->Visit("particles", &particles, config::Range::Closed(1, 1000000), "SGLD chains");
    a->Visit("steps", &steps, config::Range::Closed(0, 1000000), "SGLD steps");
    a->Visit("step_scale", &step_scale, config::Range::Positive(),
             "sigma2_k = step_scale (1 + k)^-0.5 (normalised command units^2)");
    a->Visit("max_dropped_share", &max_dropped_share, config::Range::Closed(0, 1),
             "largest share of particles that may become non-finite");
    a->Visit("threads", &threads, config::Range::Closed(1, 256),
             "threads sharing each SGLD step's evaluation (the same result for any count)");
  }
};

/// sigma2_k = step_scale (1 + k)^-0.5, the variance of step k's noise (twice its gradient step).
double SgldStepVariance(const SgldParams& params, int k);

struct SgldResult {
  Eigen::MatrixXf u;       ///< [7n x survivors] final particles, energy ascending
  Eigen::VectorXf energy;  ///< [survivors] their final energies
  int dropped = 0;         ///< particles dropped for non-finite energy or gradient
};

/// Particles start uniform in [-1, 1]^{7n}; step k = 0 .. steps-1:
///   u <- clamp(u - (sigma2_k / 2) dE/du + sqrt(sigma2_k) N(0, I), -1, 1).
/// A particle whose energy or gradient is non-finite (at any step or at the end) is dropped; more
/// than max_dropped_share * particles dropped throws Error (count, share, limit). Deterministic
/// for a given rng state. `ws` must hold at least params.particles particles (else Error).
/// `start` [7n x particles] (finite, in [-1, 1]; else Error): the particles' starting points
/// instead of uniform draws (which then draw nothing from rng).
SgldResult RunSgld(const EnergyModel& model, const Eigen::VectorXf& context,
                   const SgldParams& params, std::mt19937_64* rng, EnergyModel::Workspace* ws,
                   const Eigen::MatrixXf* start = nullptr);
/// The same on `workspaces->size()` threads (the calling one and size - 1 started per step), each
/// workspace holding at least SgldBlockCapacity(particles, size) particles; params.threads is not
/// read. The particles are split into blocks that start at multiples of 8, so that every
/// particle's evaluation is the one it gets undivided: the result equals RunSgld's on one thread.
SgldResult RunSgld(const EnergyModel& model, const Eigen::VectorXf& context,
                   const SgldParams& params, std::mt19937_64* rng,
                   std::vector<EnergyModel::Workspace>* workspaces,
                   const Eigen::MatrixXf* start = nullptr);
/// The most particles one of `threads` workspaces receives from RunSgld.
int SgldBlockCapacity(int particles, int threads);

// ---------------------------------------------------------------------------------------------
/// A sampler that reads a problem through the energy model's context (the learned sampler and its
/// nearest-neighbour baseline): SetWorld encodes the world once per problem, and PrepareContext
/// checks a Sample call and gives the query's context.
class ContextSampler : public CommandSampler {
 public:
  /// Computes the world encoding once (EnergyModel::EncodeWorld).
  void SetWorld(const World& world);
  /// The same with an encoding computed already (another sampler's encoding(); Error if its
  /// size is not the model's).
  void SetEncoding(const Eigen::VectorXf& encoding);
  const Eigen::VectorXf& encoding() const { return encoding_; }

 protected:
  /// `model` must outlive the sampler.
  explicit ContextSampler(const EnergyModel& model) : model_(model) {}
  /// Error naming `who` when intermediate_commands != the model's n, SetWorld was not called or
  /// count < 0; else the context of `query` in the current world.
  const Eigen::VectorXf& PrepareContext(const char* who, const GfcsQuery& query,
                                        int intermediate_commands, int count);

  const EnergyModel& model_;

 private:
  Eigen::VectorXf encoding_, context_;
  bool has_world_ = false;
};

// ---------------------------------------------------------------------------------------------
/// The learned GFCS sampler: SGLD on the energy model, the lowest-energy particles in radians,
/// on params.threads threads. Call SetWorld once per problem before Sample. Not thread-safe (one
/// per caller).
class LearnedSampler : public ContextSampler {
 public:
  /// `model` must outlive the sampler.
  LearnedSampler(const EnergyModel& model, SgldParams params);
  std::string name() const override { return "learned"; }
  /// Runs SGLD with max(particles, learned) particles, learned = count - round(uniform_share
  /// count); `out` [7n x count] holds `learned` survivors in radians (the lowest-energy ones, or
  /// with params.pick = kRandom a uniform draw without replacement from `rng`, in energy order),
  /// then uniform draws in the joint limits. When fewer than `learned` particles survive (allowed
  /// by max_dropped_share), uniform draws fill their places too (counted in last_filled(), which
  /// does not count the configured uniform share).
  /// Error when intermediate_commands != the model's n or SetWorld was not called.
  void Sample(const GfcsQuery& query, int intermediate_commands, int count, std::mt19937_64* rng,
              Eigen::MatrixXd* out) override;

  /// SGLD's particles start at `start`'s candidates for the query (e.g. the nearest sampler's: the
  /// energy model refines retrieved solutions) instead of uniform draws; null: uniform (thesis).
  /// `start` must outlive the sampler's use and have its world set by the caller.
  void SetStart(CommandSampler* start) { start_ = start; }
  const SgldResult& last_result() const { return last_; }
  int last_dropped() const { return last_.dropped; }
  int last_filled() const { return last_filled_; }
  double last_seconds() const { return last_seconds_; }  ///< wall time of the last Sample

 private:
  SgldParams params_;
  CommandSampler* start_ = nullptr;
  Eigen::MatrixXd start_radians_;
  Eigen::MatrixXf start_u_;
  std::vector<EnergyModel::Workspace> ws_;  ///< one per SGLD thread
  SgldResult last_;
  std::vector<int> picked_;  ///< survivor indices (kRandom), reused between calls
  int last_filled_ = 0;
  double last_seconds_ = 0;
};

}  // namespace foresight::manipulation
