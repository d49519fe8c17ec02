#include "training/gfcs/loop.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <thread>

#include "core/error.h"
#include "core/file_io.h"
#include "core/log.h"
#include "inference/manipulation/fabric.h"
#include "inference/manipulation/gfcs.h"
#include "training/distributed.h"
#include "training/run_dir.h"

namespace foresight::gfcs {
namespace fs = std::filesystem;
using manipulation::EnergyModel;
using manipulation::JointVector;

namespace {

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

/// A seed for stream `what` of counter `k` (and `j`): splitmix64 of the combination, so streams
/// of neighbouring counters are unrelated.
std::uint64_t StreamSeed(std::int64_t seed, std::uint64_t what, std::uint64_t k,
                         std::uint64_t j = 0) {
  std::uint64_t z = static_cast<std::uint64_t>(seed) ^ (what * 0x9E3779B97F4A7C15ull) ^
                    (k * 0xBF58476D1CE4E5B9ull) ^ (j * 0x94D049BB133111EBull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
constexpr std::uint64_t kNegativeStream = 1, kBatchStream = 2, kFailureStream = 3;
/// Moves k distinct entries of `v`, drawn uniformly, to its first k places (a partial
/// Fisher-Yates shuffle; the draws of `rng` are the same for any element type).
template <class T>
void ShuffleHead(std::vector<T>* v, int k, std::mt19937_64* rng) {
  for (int i = 0; i < k; ++i) {
    std::uniform_int_distribution<int> pick(i, static_cast<int>(v->size()) - 1);
    std::swap((*v)[static_cast<std::size_t>(i)], (*v)[static_cast<std::size_t>(pick(*rng))]);
  }
}
/// The rendezvous store's flag by which an interrupted rank stops the others between solves.
constexpr const char* kStopFlag = "gfcs_loop_stop";

// --- Byte packing of positives (the rank gather and nothing else) ---------------------------

void PutInt(std::string* s, std::int64_t v) { s->append(reinterpret_cast<const char*>(&v), 8); }
std::int64_t GetInt(const std::string& s, std::size_t* at) {
  FS_THROW_UNLESS(*at + 8 <= s.size(), "gfcs loop: truncated gather message");
  std::int64_t v;
  std::memcpy(&v, s.data() + *at, 8);
  *at += 8;
  return v;
}

/// What one rank contributes to a block: its solves, their positives and (loop.failure_negatives)
/// their sampler's labelled failures.
struct BlockResult {
  int solves = 0, solved = 0, dropped = 0, sampler_failures = 0;
  std::vector<Positive> positives, failures;
};

void PackList(std::string* s, const std::vector<Positive>& list) {
  PutInt(s, static_cast<std::int64_t>(list.size()));
  for (const Positive& p : list) {
    PutInt(s, p.problem);
    PutInt(s, p.solve);
    float cost = p.cost;
    s->append(reinterpret_cast<const char*>(&cost), sizeof cost);
    PutInt(s, p.u.size());
    s->append(reinterpret_cast<const char*>(p.u.data()), sizeof(float) * p.u.size());
  }
}

std::vector<Positive> UnpackList(const std::string& s, std::size_t* at) {
  std::vector<Positive> list;
  const std::int64_t n = GetInt(s, at);
  FS_THROW_UNLESS(n >= 0, "gfcs loop: a gather message with ", n, " entries");
  for (std::int64_t i = 0; i < n; ++i) {
    Positive p;
    p.problem = static_cast<int>(GetInt(s, at));
    p.solve = static_cast<int>(GetInt(s, at));
    FS_THROW_UNLESS(*at + sizeof(float) <= s.size(), "gfcs loop: truncated gather message");
    std::memcpy(&p.cost, s.data() + *at, sizeof(float));
    *at += sizeof(float);
    const std::int64_t d = GetInt(s, at);
    FS_THROW_UNLESS(d >= 0 && *at + sizeof(float) * d <= s.size(),
                    "gfcs loop: truncated gather message");
    p.u.resize(d);
    std::memcpy(p.u.data(), s.data() + *at, sizeof(float) * d);
    *at += sizeof(float) * d;
    list.push_back(std::move(p));
  }
  return list;
}

std::string Pack(const BlockResult& r) {
  std::string s;
  PutInt(&s, r.solves);
  PutInt(&s, r.solved);
  PutInt(&s, r.dropped);
  PutInt(&s, r.sampler_failures);
  PackList(&s, r.positives);
  PackList(&s, r.failures);
  return s;
}

BlockResult Unpack(const std::string& s) {
  BlockResult r;
  std::size_t at = 0;
  r.solves = static_cast<int>(GetInt(s, &at));
  r.solved = static_cast<int>(GetInt(s, &at));
  r.dropped = static_cast<int>(GetInt(s, &at));
  r.sampler_failures = static_cast<int>(GetInt(s, &at));
  r.positives = UnpackList(s, &at);
  r.failures = UnpackList(s, &at);
  return r;
}

// --- Tensors <-> Eigen ------------------------------------------------------------------------

torch::Tensor ToTensor(const Eigen::VectorXf& v) {
  return torch::from_blob(const_cast<float*>(v.data()), {v.size()}, torch::kFloat32).clone();
}
Eigen::VectorXf ToVector(const torch::Tensor& t) {
  const torch::Tensor c = t.contiguous().to(torch::kFloat32);
  return Eigen::Map<const Eigen::VectorXf>(c.data_ptr<float>(), c.numel());
}
/// Columns of `m` [rows x cols] as the rows of a [cols x rows] tensor, and back (same memory
/// layout: column-major rows x cols is row-major cols x rows).
torch::Tensor ColumnsTensor(const Eigen::MatrixXf& m) {
  return torch::from_blob(const_cast<float*>(m.data()), {m.cols(), m.rows()}, torch::kFloat32)
      .clone();
}
Eigen::MatrixXf TensorColumns(const torch::Tensor& t) {
  const torch::Tensor c = t.contiguous().to(torch::kFloat32);
  FS_THROW_UNLESS(c.dim() == 2, "loop checkpoint: expected a 2-D tensor, got ", c.dim(), "-D");
  return Eigen::Map<const Eigen::MatrixXf>(c.data_ptr<float>(), c.size(1), c.size(0));
}
torch::Tensor Int64Tensor(const std::vector<std::int64_t>& v) {
  return torch::tensor(v, torch::kInt64);
}

/// A fresh tensor per key: InputArchive::read into a defined tensor re-points it in place.
torch::Tensor Read(torch::serialize::InputArchive* a, const std::string& key) {
  torch::Tensor t;
  a->read(key, t);
  return t;
}

// --- Positives <-> the buffer tensors of a checkpoint --------------------------------------------

void WritePositives(torch::serialize::OutputArchive* a, const std::string& key,
                    const std::vector<Positive>& list, int dim) {
  std::vector<std::int64_t> problem, solve;
  torch::Tensor cost = torch::zeros({static_cast<std::int64_t>(list.size())}, torch::kFloat32);
  torch::Tensor u = torch::zeros({static_cast<std::int64_t>(list.size()), dim}, torch::kFloat32);
  for (std::size_t i = 0; i < list.size(); ++i) {
    problem.push_back(list[i].problem);
    solve.push_back(list[i].solve);
    cost[static_cast<std::int64_t>(i)] = list[i].cost;
    u[static_cast<std::int64_t>(i)] = ToTensor(list[i].u);
  }
  a->write(key + ".problem", Int64Tensor(problem));
  a->write(key + ".solve", Int64Tensor(solve));
  a->write(key + ".cost", cost);
  a->write(key + ".u", u);
}

std::vector<Positive> ReadPositives(torch::serialize::InputArchive* a, const std::string& key) {
  const torch::Tensor problem = Read(a, key + ".problem"), solve = Read(a, key + ".solve"),
                      cost = Read(a, key + ".cost"), u = Read(a, key + ".u");
  std::vector<Positive> out(static_cast<std::size_t>(problem.size(0)));
  for (std::size_t i = 0; i < out.size(); ++i) {
    const auto k = static_cast<std::int64_t>(i);
    out[i].problem = static_cast<int>(problem[k].item<std::int64_t>());
    out[i].solve = static_cast<int>(solve[k].item<std::int64_t>());
    out[i].cost = cost[k].item<float>();
    out[i].u = ToVector(u[k]);
  }
  return out;
}

/// The solution memory of a checkpoint: every positive, and the contexts of all training problems
/// [context x problems] in `*contexts`. Error naming `source` for a checkpoint of an older build.
std::vector<Positive> ReadMemory(torch::serialize::InputArchive* a, const std::string& source,
                                 Eigen::MatrixXf* contexts) {
  torch::Tensor t;
  FS_THROW_UNLESS(a->try_read("memory.u", t), source,
                  ": the checkpoint has no solution memory (written by an older build); train the "
                  "run again");
  *contexts = TensorColumns(Read(a, "memory.contexts"));
  return ReadPositives(a, "memory");
}

/// The exported solution memory: the training problems that have a positive (in index order)
/// with their contexts [context x problems], and every positive.
manipulation::SolutionMemory MakeMemory(const std::vector<Positive>& positives,
                                        const Eigen::MatrixXf& contexts) {
  std::map<int, int> column;  // training problem -> column of the memory's contexts
  for (const Positive& p : positives) column.emplace(p.problem, 0);
  manipulation::SolutionMemory m;
  m.contexts.resize(contexts.rows(), static_cast<Eigen::Index>(column.size()));
  int k = 0;
  for (auto& [problem, col] : column) {
    FS_THROW_UNLESS(problem >= 0 && problem < contexts.cols(), "gfcs loop: a positive of problem ",
                    problem, " outside the ", contexts.cols(), " training problems");
    col = k;
    m.contexts.col(k++) = contexts.col(problem);
  }
  const auto n = static_cast<Eigen::Index>(positives.size());
  m.problem.resize(n);
  m.cost.resize(n);
  m.commands.resize(positives.empty() ? 0 : positives.front().u.size(), n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Positive& p = positives[static_cast<std::size_t>(i)];
    m.problem[i] = column.at(p.problem);
    m.cost[i] = p.cost;
    m.commands.col(i) = p.u;
  }
  return m;
}

torch::Tensor TextTensor(const std::string& s) {
  return torch::from_blob(const_cast<char*>(s.data()), {static_cast<std::int64_t>(s.size())},
                          torch::kUInt8)
      .clone();
}
std::string TensorText(const torch::Tensor& t) {
  const torch::Tensor c = t.contiguous();
  return std::string(reinterpret_cast<const char*>(c.data_ptr<std::uint8_t>()),
                     static_cast<std::size_t>(c.numel()));
}

/// The first line where two YAML texts differ (the key a foreign checkpoint disagrees on).
std::string FirstDifference(const std::string& a, const std::string& b) {
  std::istringstream sa(a), sb(b);
  std::string la, lb;
  while (true) {
    const bool ga = static_cast<bool>(std::getline(sa, la));
    const bool gb = static_cast<bool>(std::getline(sb, lb));
    if (!ga && !gb) return "";
    if (!ga || !gb || la != lb)
      return "'" + (ga ? la : std::string("<end>")) + "' here, '" +
             (gb ? lb : std::string("<end>")) + "' in the checkpoint";
  }
}

void WriteMlp(torch::serialize::OutputArchive* a, const std::string& key, const Mlp& mlp) {
  a->write(key + ".layers", Int64Tensor({static_cast<std::int64_t>(mlp.layers().size())}));
  for (std::size_t i = 0; i < mlp.layers().size(); ++i) {
    const DenseLayer& l = mlp.layers()[i];
    const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> w = l.weight;
    a->write(key + ".w" + std::to_string(i),
             torch::from_blob(const_cast<float*>(w.data()), {w.rows(), w.cols()}, torch::kFloat32)
                 .clone());
    a->write(key + ".b" + std::to_string(i), ToTensor(l.bias));
  }
}

Mlp ReadMlp(torch::serialize::InputArchive* a, const std::string& key) {
  const torch::Tensor n = Read(a, key + ".layers");
  std::vector<DenseLayer> layers;
  for (std::int64_t i = 0; i < n[0].item<std::int64_t>(); ++i) {
    const torch::Tensor w = Read(a, key + ".w" + std::to_string(i));
    const torch::Tensor b = Read(a, key + ".b" + std::to_string(i));
    DenseLayer l;
    const torch::Tensor wc = w.contiguous();
    l.weight =
        Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
            wc.data_ptr<float>(), wc.size(0), wc.size(1));
    l.bias = ToVector(b);
    layers.push_back(std::move(l));
  }
  return Mlp(std::move(layers));
}

/// Everything a checkpoint holds besides the network and the optimiser.
struct LoopState {
  int block_start = 0;  ///< first solve of the current block
  int rank_next = 0;    ///< this rank's next solve (>= block_start)
  int solves = 0, solved = 0, rounds = 0, dropped = 0, sampler_failures = 0;
  double last_loss = 0;
  std::vector<Positive> buffer;
  /// every positive the loop found, in solve order (the buffer keeps only the last ones): the
  /// exported solution memory of the nearest-neighbour sampler
  std::vector<Positive> memory;
  /// the sampler's first-batch candidates that did not reach the goal, up to
  /// loop.failure_negatives per solve, in solve order (empty when that is 0)
  std::vector<Positive> failures;
  BlockResult pending;  ///< this rank's results in the current block
};

int CommandSize(const ExperimentConfig& c) { return manipulation::kDof * (c.gfcs.commands - 1); }

EnergyNet MakeNet(const ExperimentConfig& c, int context_size) {
  return EnergyNet(context_size, CommandSize(c), c.energy.hidden, c.energy.layers);
}

/// Commands in radians [7n] -> normalised [-1, 1] and back, joint by joint.
Eigen::VectorXf Normalise(const Eigen::VectorXd& q, const manipulation::JointLimits& l) {
  Eigen::VectorXf u(q.size());
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    const int j = static_cast<int>(i % manipulation::kDof);
    u[i] = static_cast<float>(2 * (q[i] - l.lower[j]) / (l.upper[j] - l.lower[j]) - 1);
  }
  return u;
}

class Loop {
 public:
  Loop(const ExperimentConfig& c, const std::string& config_yaml,
       const manipulation::RobotModel& robot, const Encoding& encoding,
       const std::vector<TrainingProblem>& problems, const std::string& run_dir)
      : c_(c),
        yaml_(config_yaml),
        robot_(robot),
        encoding_(encoding),
        problems_(problems),
        run_dir_(run_dir),
        group_(dist::DefaultGroup()),
        net_(MakeNet(c, static_cast<int>(problems.front().context.size()))),
        adam_(net_->parameters(), torch::optim::AdamOptions(c.loop.learning_rate)) {}

  LoopStats Run(bool resume, const std::atomic<bool>* interrupt);
  Mlp Energy() const { return net_->net()->ToMlp(); }
  manipulation::SolutionMemory Memory() const { return MakeMemory(st_.memory, Contexts()); }

 private:
  int Total() const { return c_.loop.passes * static_cast<int>(problems_.size()); }
  Eigen::MatrixXf Contexts() const;
  std::string Serialize(bool with_pending) const;
  void Deserialize(const std::string& bytes, const std::string& source);
  void Save();
  void Resume(bool resume);
  void RebuildSampler();
  void Solve(int s);
  void FinishBlock(int block_end);
  void TrainRound();
  std::string Where(int s) const;

  const ExperimentConfig& c_;
  const std::string& yaml_;
  const manipulation::RobotModel& robot_;
  const Encoding& encoding_;
  const std::vector<TrainingProblem>& problems_;
  std::string run_dir_;
  std::shared_ptr<dist::Group> group_;
  EnergyNet net_;
  torch::optim::Adam adam_;
  LoopState st_;
  LoopStats stats_;
  std::unique_ptr<EnergyModel> engine_;
  std::unique_ptr<manipulation::LearnedSampler> sampler_;
  int walk_from_ = 0;  ///< where this invocation's walk over the current block starts
  std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
};

Eigen::MatrixXf Loop::Contexts() const {
  Eigen::MatrixXf out(problems_.front().context.size(),
                      static_cast<Eigen::Index>(problems_.size()));
  for (std::size_t p = 0; p < problems_.size(); ++p)
    out.col(static_cast<Eigen::Index>(p)) = problems_[p].context;
  return out;
}

std::string Loop::Where(int s) const {
  const TrainingProblem& p = problems_[static_cast<std::size_t>(s) % problems_.size()];
  return p.family + " #" + std::to_string(p.problem.index);
}

std::string Loop::Serialize(bool with_pending) const {
  torch::serialize::OutputArchive a;
  a.write("config_yaml", TextTensor(yaml_));
  a.write("world_size", Int64Tensor({group_->size()}));
  a.write("counters",
          Int64Tensor({st_.block_start, with_pending ? st_.rank_next : st_.block_start, st_.solves,
                       st_.solved, st_.rounds, st_.dropped, Total(), st_.sampler_failures}));
  a.write("last_loss", torch::tensor({st_.last_loss}, torch::kFloat64));
  const BlockResult none;
  const BlockResult& pending = with_pending ? st_.pending : none;
  a.write("pending.counts",
          Int64Tensor({pending.solves, pending.solved, pending.dropped, pending.sampler_failures}));
  WritePositives(&a, "buffer", st_.buffer, CommandSize(c_));
  WritePositives(&a, "memory", st_.memory, CommandSize(c_));
  a.write("memory.contexts", ColumnsTensor(Contexts()));
  WritePositives(&a, "pending", pending.positives, CommandSize(c_));
  WritePositives(&a, "failures", st_.failures, CommandSize(c_));
  WritePositives(&a, "pending.failures", pending.failures, CommandSize(c_));
  a.write("encoding.bps_mean", ToTensor(encoding_.bps_mean));
  a.write("encoding.bps_std", ToTensor(encoding_.bps_std));
  WriteMlp(&a, "encoding.encoder", encoding_.encoder);
  torch::serialize::OutputArchive net, adam;
  net_->save(net);
  adam_.save(adam);
  a.write("net", net);
  a.write("adam", adam);
  std::ostringstream os;
  a.save_to(os);
  return os.str();
}

void Loop::Save() {
  WriteFileAtomically(LoopCheckpointPath(run_dir_, group_->rank()), Serialize(true));
}

void Loop::Deserialize(const std::string& bytes, const std::string& source) {
  torch::serialize::InputArchive a;
  try {
    std::istringstream in(bytes);
    a.load_from(in);
  } catch (const std::exception& e) {
    Fail(source, ": cannot read the loop checkpoint (", std::string(e.what()).substr(0, 120), ")");
  }
  const std::string diff = FirstDifference(yaml_, TensorText(Read(&a, "config_yaml")));
  FS_THROW_UNLESS(diff.empty(), source, ": the checkpoint is from another config (", diff, ")");
  torch::Tensor t = Read(&a, "world_size");
  FS_THROW_UNLESS(t[0].item<std::int64_t>() == group_->size(), source, ": written by a run of ",
                  t[0].item<std::int64_t>(), " ranks, this one has ", group_->size(),
                  " (resume with the same WORLD_SIZE)");
  t = Read(&a, "counters");
  st_.block_start = static_cast<int>(t[0].item<std::int64_t>());
  st_.rank_next = static_cast<int>(t[1].item<std::int64_t>());
  st_.solves = static_cast<int>(t[2].item<std::int64_t>());
  st_.solved = static_cast<int>(t[3].item<std::int64_t>());
  st_.rounds = static_cast<int>(t[4].item<std::int64_t>());
  st_.dropped = static_cast<int>(t[5].item<std::int64_t>());
  FS_THROW_UNLESS(t.size(0) == 8 && t[6].item<std::int64_t>() == Total(), source,
                  ": the checkpoint's loop has another number of solves (the training problems "
                  "changed under the same config?)");
  st_.sampler_failures = static_cast<int>(t[7].item<std::int64_t>());
  st_.last_loss = Read(&a, "last_loss")[0].item<double>();
  t = Read(&a, "pending.counts");
  st_.pending.solves = static_cast<int>(t[0].item<std::int64_t>());
  st_.pending.solved = static_cast<int>(t[1].item<std::int64_t>());
  st_.pending.dropped = static_cast<int>(t[2].item<std::int64_t>());
  st_.pending.sampler_failures = static_cast<int>(t[3].item<std::int64_t>());
  st_.buffer = ReadPositives(&a, "buffer");
  st_.pending.positives = ReadPositives(&a, "pending");
  st_.failures = ReadPositives(&a, "failures");
  st_.pending.failures = ReadPositives(&a, "pending.failures");
  Eigen::MatrixXf contexts;
  st_.memory = ReadMemory(&a, source, &contexts);
  const Eigen::MatrixXf here = Contexts();
  FS_THROW_UNLESS(
      contexts.rows() == here.rows() && contexts.cols() == here.cols() && contexts.isApprox(here),
      source, ": the checkpoint's training problems differ from this run's");
  for (const auto* list :
       {&st_.buffer, &st_.pending.positives, &st_.memory, &st_.failures, &st_.pending.failures})
    for (const Positive& p : *list)
      FS_THROW_UNLESS(p.problem >= 0 && p.problem < static_cast<int>(problems_.size()) &&
                          p.u.size() == CommandSize(c_),
                      source, ": a positive of problem ", p.problem, " (", p.u.size(),
                      " values) does not fit the ", problems_.size(), " training problems");
  FS_THROW_UNLESS(
      ToVector(Read(&a, "encoding.bps_mean")).isApprox(encoding_.bps_mean) &&
          ReadMlp(&a, "encoding.encoder").layers().size() == encoding_.encoder.layers().size(),
      source, ": the checkpoint's problem encoding differs from this run's");
  torch::serialize::InputArchive net, adam;
  a.read("net", net);
  a.read("adam", adam);
  net_->load(net);
  adam_.load(adam);
}

/// Brings every rank to one consistent state before the loop continues. A rank can be one block
/// behind another (killed between a block's gather and its checkpoint) or have no checkpoint at
/// all; such a rank takes the shared state (buffer, network, optimiser, counters) of the most
/// advanced rank and redoes its solves of that block. Then every rank walks the block from the
/// least advanced rank's position (solves it already did are not repeated).
void Loop::Resume(bool resume) {
  const std::string path = LoopCheckpointPath(run_dir_, group_->rank());
  const bool have = resume && fs::exists(path);
  if (have) Deserialize(ReadText(path), path);
  std::string mine;
  PutInt(&mine, have ? st_.block_start : -1);
  PutInt(&mine, have ? st_.rank_next : -1);
  const std::vector<std::string> all = group_->AllGatherBytes(mine);
  int leader = -1, lead_block = -1;
  std::vector<std::int64_t> block(all.size()), next(all.size());
  for (std::size_t r = 0; r < all.size(); ++r) {
    std::size_t at = 0;
    block[r] = GetInt(all[r], &at);
    next[r] = GetInt(all[r], &at);
    if (block[r] > lead_block) {
      lead_block = static_cast<int>(block[r]);
      leader = static_cast<int>(r);
    }
  }
  if (lead_block < 0) {  // nobody has a checkpoint: a fresh start (same seed, same network)
    walk_from_ = 0;
    return;
  }
  bool behind = false;
  for (std::int64_t b : block) behind = behind || b != lead_block;
  if (behind) {
    const std::string shared =
        group_->BroadcastBytes(group_->rank() == leader ? Serialize(false) : std::string(), leader);
    if (block[static_cast<std::size_t>(group_->rank())] != lead_block) {
      log::Info("rank ", group_->rank(), " was behind (block at solve ",
                block[static_cast<std::size_t>(group_->rank())] + 1, "); taking rank ", leader,
                "'s state at solve ", lead_block + 1);
      Deserialize(shared, "rank " + std::to_string(leader) + "'s loop state");
      st_.pending = BlockResult{};
      st_.rank_next = st_.block_start;
      next[static_cast<std::size_t>(group_->rank())] = st_.block_start;
    }
  }
  // Ranks that were behind redo their block from its start; the others continue where they were.
  walk_from_ = lead_block;
  for (std::size_t r = 0; r < all.size(); ++r)
    if (block[r] == lead_block) walk_from_ = std::min(walk_from_, static_cast<int>(next[r]));
}

void Loop::RebuildSampler() {
  sampler_.reset();
  engine_.reset();
  if (st_.rounds == 0) return;
  engine_ = std::make_unique<EnergyModel>(MakeEnergyParts(c_, robot_, encoding_, Energy()));
  sampler_ = std::make_unique<manipulation::LearnedSampler>(*engine_, c_.sampler);
}

void Loop::Solve(int s) {
  const TrainingProblem& p = problems_[static_cast<std::size_t>(s) % problems_.size()];
  const auto started = std::chrono::steady_clock::now();
  const manipulation::Fabric fabric(robot_, p.problem.world, c_.fabric);
  manipulation::GfcsParams params = c_.gfcs;
  params.batches = c_.loop.batches;
  params.batch_size = c_.loop.batch_size;
  params.seed = c_.seed + s;
  manipulation::GfcsQuery query;
  query.start = p.problem.start;
  query.goal = p.problem.goal;
  manipulation::UniformSampler uniform(robot_.limits().lower, robot_.limits().upper);
  manipulation::CommandSampler* sampler = &uniform;
  if (sampler_) {
    sampler_->SetWorld(p.problem.world);
    sampler = sampler_.get();
  }
  manipulation::GfcsSolution sol;
  try {
    sol = SolveGfcop(fabric, query, sampler, params);
  } catch (const std::exception& e) {
    // The learned sampler failed (e.g. too many non-finite SGLD particles): this solve falls back
    // to the uniform sampler, deterministically, so a resumed run does not fail here again.
    if (sampler == &uniform) throw;
    log::Info("solve ", s + 1, ": the learned sampler failed (", e.what(), "); uniform instead");
    ++st_.pending.sampler_failures;
    sampler = &uniform;
    sol = SolveGfcop(fabric, query, sampler, params);
  }
  FS_THROW_UNLESS(sol.status != manipulation::GfcsStatus::kError, "gfcs loop: solve ", s, " (",
                  Where(s), "): ", sol.message);
  if (sampler == sampler_.get()) st_.pending.dropped += sampler_->last_dropped();
  ++st_.pending.solves;
  st_.pending.solved += sol.solved();
  const std::size_t before = st_.pending.positives.size();
  const auto record = [&](const manipulation::GfcsCandidate& cand, std::vector<Positive>* list) {
    Positive entry;
    entry.problem = static_cast<int>(static_cast<std::size_t>(s) % problems_.size());
    entry.solve = s;
    entry.cost = static_cast<float>(cand.cost);
    entry.u = Normalise(cand.commands, robot_.limits());
    list->push_back(std::move(entry));
  };
  for (const manipulation::GfcsCandidate& cand : sol.top)
    if (cand.reached || !c_.loop.reached_only) record(cand, &st_.pending.positives);
  // The sampler's own proposals that failed (fully evaluated: a pruned one's outcome is unknown).
  int kept = 0;
  for (const manipulation::GfcsCandidate& cand : sol.first_batch) {
    if (kept >= c_.loop.failure_negatives) break;
    if (cand.reached || cand.pruned) continue;
    record(cand, &st_.pending.failures);
    ++kept;
  }
  const double secs = Seconds(started);
  stats_.solve_seconds += secs;
  const int total = c_.loop.passes * static_cast<int>(problems_.size());
  const int done = st_.solves + st_.pending.solves;  // this rank's view
  const int ok = st_.solved + st_.pending.solved;
  log::Info("solve ", s + 1, "/", total, " (pass ", s / problems_.size() + 1, ", ", Where(s), ", ",
            sampler->name(), "): ", sol.solved() ? "solved" : "not solved", ", +",
            st_.pending.positives.size() - before, " positives; success so far ", ok, "/", done,
            ", buffer ", st_.buffer.size(), ", last loss ", st_.last_loss, ", ", secs, " s");
}

void Loop::FinishBlock(int block_end) {
  // Every rank's results, merged in solve order: the buffer does not depend on the rank count.
  const std::vector<std::string> parts = group_->AllGatherBytes(Pack(st_.pending));
  std::vector<Positive> fresh, failed;
  for (const std::string& part : parts) {
    BlockResult r = Unpack(part);
    st_.solves += r.solves;
    st_.solved += r.solved;
    st_.dropped += r.dropped;
    st_.sampler_failures += r.sampler_failures;
    for (Positive& p : r.positives) fresh.push_back(std::move(p));
    for (Positive& p : r.failures) failed.push_back(std::move(p));
  }
  const auto by_solve = [](const Positive& a, const Positive& b) { return a.solve < b.solve; };
  std::stable_sort(fresh.begin(), fresh.end(), by_solve);
  std::stable_sort(failed.begin(), failed.end(), by_solve);
  for (Positive& p : failed) st_.failures.push_back(std::move(p));
  st_.memory.insert(st_.memory.end(), fresh.begin(), fresh.end());
  for (Positive& p : fresh) st_.buffer.push_back(std::move(p));
  if (st_.buffer.size() > static_cast<std::size_t>(c_.loop.buffer))
    st_.buffer.erase(st_.buffer.begin(),
                     st_.buffer.end() - static_cast<std::ptrdiff_t>(c_.loop.buffer));
  st_.pending = BlockResult{};
  if ((block_end % c_.loop.train_every == 0 || block_end == Total()) && !st_.buffer.empty()) {
    TrainRound();
    ++st_.rounds;
    RebuildSampler();
  }
  st_.block_start = block_end;
  st_.rank_next = block_end;
}

void Loop::TrainRound() {
  const int b_total = static_cast<int>(st_.buffer.size());
  const int n_neg = c_.loop.negatives;
  const int dim = CommandSize(c_);
  const int round = st_.rounds;

  // Negatives: SGLD on the current model from uniform particles (thesis Algorithm, inner loop),
  // buffer entries dealt over the ranks and, within a rank, over threads.
  auto neg_started = std::chrono::steady_clock::now();
  const EnergyModel engine(MakeEnergyParts(c_, robot_, encoding_, Energy()));
  manipulation::SgldParams sgld = c_.loop.negative_sgld;
  sgld.particles = n_neg;
  std::vector<Eigen::MatrixXf> negatives(static_cast<std::size_t>(b_total));
  std::vector<int> mine;
  for (int j = group_->rank(); j < b_total; j += group_->size()) mine.push_back(j);
  const int threads = std::max(1, std::min<int>(c_.loop.threads, static_cast<int>(mine.size())));
  std::vector<int> dropped(static_cast<std::size_t>(threads), 0);
  std::vector<std::string> errors(static_cast<std::size_t>(threads));
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t)
    pool.emplace_back([&, t] {
      try {
        EnergyModel::Workspace ws = engine.MakeWorkspace(n_neg);
        for (std::size_t i = static_cast<std::size_t>(t); i < mine.size();
             i += static_cast<std::size_t>(threads)) {
          const int j = mine[i];
          const Positive& pos = st_.buffer[static_cast<std::size_t>(j)];
          std::mt19937_64 rng(StreamSeed(c_.seed, kNegativeStream, round, pos.solve * 64 + j));
          manipulation::SgldResult r;
          try {
            r = manipulation::RunSgld(
                engine, problems_[static_cast<std::size_t>(pos.problem)].context, sgld, &rng, &ws);
          } catch (const std::exception&) {  // too many non-finite particles: all count as dropped
            r = manipulation::SgldResult{};
            r.dropped = n_neg;
          }
          dropped[static_cast<std::size_t>(t)] += r.dropped;
          // Dropped particles are replaced by survivors, or by uniform ones when none survived.
          Eigen::MatrixXf u(dim, n_neg);
          std::uniform_real_distribution<float> uniform(-1.f, 1.f);
          for (int k = 0; k < n_neg; ++k) {
            if (r.u.cols() > 0) {
              u.col(k) = r.u.col(k % r.u.cols());
            } else {
              for (int d = 0; d < dim; ++d) u(d, k) = uniform(rng);
            }
          }
          negatives[static_cast<std::size_t>(j)] = std::move(u);
        }
      } catch (const std::exception& e) {
        errors[static_cast<std::size_t>(t)] = e.what();
      }
    });
  for (std::thread& th : pool) th.join();
  for (const std::string& e : errors)
    FS_THROW_UNLESS(e.empty(), "gfcs loop: training round ", round + 1, ": negatives: ", e);
  int round_dropped = 0;
  for (int d : dropped) round_dropped += d;
  if (group_->size() > 1) {
    std::string msg;
    PutInt(&msg, round_dropped);
    for (int j : mine)
      msg.append(reinterpret_cast<const char*>(negatives[static_cast<std::size_t>(j)].data()),
                 sizeof(float) * static_cast<std::size_t>(dim * n_neg));
    const std::vector<std::string> all = group_->AllGatherBytes(msg);
    round_dropped = 0;
    for (int r = 0; r < group_->size(); ++r) {
      std::size_t at = 0;
      round_dropped += static_cast<int>(GetInt(all[static_cast<std::size_t>(r)], &at));
      for (int j = r; j < b_total; j += group_->size()) {
        Eigen::MatrixXf u(dim, n_neg);
        FS_THROW_UNLESS(at + sizeof(float) * u.size() <= all[static_cast<std::size_t>(r)].size(),
                        "gfcs loop: truncated negatives from rank ", r);
        std::memcpy(u.data(), all[static_cast<std::size_t>(r)].data() + at,
                    sizeof(float) * static_cast<std::size_t>(u.size()));
        at += sizeof(float) * static_cast<std::size_t>(u.size());
        negatives[static_cast<std::size_t>(j)] = std::move(u);
      }
    }
  }
  st_.dropped += round_dropped;
  stats_.negative_seconds += Seconds(neg_started);

  // InfoNCE over the buffer, each positive against its own negatives: its SGLD ones, then
  // (loop.failure_negatives) up to that many of its problem's kept failures, drawn without
  // replacement; a problem with fewer leaves the rest of its slots masked out.
  const auto train_started = std::chrono::steady_clock::now();
  const int context_size = static_cast<int>(problems_.front().context.size());
  const int n_fail = c_.loop.failure_negatives;
  torch::Tensor ctx = torch::empty({b_total, context_size}, torch::kFloat32);
  torch::Tensor u_all = torch::zeros({b_total, 1 + n_neg + n_fail, dim}, torch::kFloat32);
  torch::Tensor valid;  // undefined without failure negatives: every negative counts
  std::map<int, std::vector<int>> failures_of;  // problem -> indices into st_.failures
  for (std::size_t i = 0; i < st_.failures.size(); ++i)
    failures_of[st_.failures[i].problem].push_back(static_cast<int>(i));
  if (n_fail > 0) valid = torch::ones({b_total, n_neg + n_fail}, torch::kBool);
  int failure_slots = 0;
  for (int j = 0; j < b_total; ++j) {
    const Positive& pos = st_.buffer[static_cast<std::size_t>(j)];
    ctx[j] = ToTensor(problems_[static_cast<std::size_t>(pos.problem)].context);
    u_all[j][0] = ToTensor(pos.u);
    const Eigen::MatrixXf& neg = negatives[static_cast<std::size_t>(j)];
    u_all[j].slice(0, 1, 1 + n_neg) =
        torch::from_blob(const_cast<float*>(neg.data()), {n_neg, dim}, torch::kFloat32).clone();
    if (n_fail == 0) continue;
    auto found = failures_of.find(pos.problem);
    std::vector<int> own_failures = found == failures_of.end() ? std::vector<int>{} : found->second;
    std::mt19937_64 pick_rng(StreamSeed(c_.seed, kFailureStream, round, j));
    const int take = std::min<int>(n_fail, static_cast<int>(own_failures.size()));
    ShuffleHead(&own_failures, take, &pick_rng);
    for (int k = 0; k < take; ++k)
      u_all[j][1 + n_neg + k] = ToTensor(
          st_.failures[static_cast<std::size_t>(own_failures[static_cast<std::size_t>(k)])].u);
    if (take < n_fail) valid[j].slice(0, n_neg + take, n_neg + n_fail).fill_(false);
    failure_slots += take;
  }
  std::mt19937_64 rng(StreamSeed(c_.seed, kBatchStream, round));
  const int batch = std::min(c_.loop.batch_positives, b_total);
  const int shards = c_.loop.gradient_shards, size = group_->size(), rank = group_->rank();
  std::vector<std::int64_t> order(static_cast<std::size_t>(b_total));
  net_->train();
  double loss_sum = 0;
  for (int step = 0; step < c_.loop.adam_steps; ++step) {
    // A batch without replacement (a fresh permutation's head), identical on every rank.
    std::iota(order.begin(), order.end(), 0);
    ShuffleHead(&order, batch, &rng);
    adam_.zero_grad();
    // The batch's mean loss as a weighted sum over fixed shards (shard s: positives [batch s / K,
    // batch (s + 1) / K) of this step's draw), each with its own backward; over several ranks,
    // rank r takes shards r, r + R, ... and the gradients (and the loss, both float32) are summed
    // over the ranks. With K <= 2 that is the same float additions on one rank as on two, so the
    // model does not depend on the rank count. With K = 1 every rank computes the one shard.
    const bool exchange = shards > 1 && size > 1;
    float local_loss = 0;
    for (int shard = exchange ? rank : 0; shard < shards; shard += exchange ? size : 1) {
      const int from = batch * shard / shards, to = batch * (shard + 1) / shards;
      if (to == from) continue;
      const torch::Tensor idx = torch::tensor(
          std::vector<std::int64_t>(order.begin() + from, order.begin() + to), torch::kInt64);
      const torch::Tensor e = net_->forward(ctx.index_select(0, idx), u_all.index_select(0, idx));
      const double weight = static_cast<double>(to - from) / batch;
      const torch::Tensor part =
          InfoNceLoss(e.select(1, 0), e.slice(1, 1),
                      valid.defined() ? valid.index_select(0, idx) : torch::Tensor()) *
          weight;
      part.backward();
      local_loss += part.item<float>();
    }
    std::vector<double> loss{local_loss};
    if (exchange) group_->AllReduceGradients(*net_, 1.0, &loss);
    FS_THROW_UNLESS(std::isfinite(loss[0]), "gfcs loop: training round ", round + 1, ", step ",
                    step + 1, ": the InfoNCE loss is not finite");
    loss_sum += loss[0];
    adam_.step();
  }
  net_->eval();
  st_.last_loss = c_.loop.adam_steps > 0 ? loss_sum / c_.loop.adam_steps : st_.last_loss;
  stats_.train_seconds += Seconds(train_started);
  log::Info("training round ", round + 1, ": ", b_total, " positives x ", n_neg, " negatives",
            n_fail > 0 ? " (+ " + std::to_string(failure_slots) + " of " +
                             std::to_string(b_total * n_fail) + " failure slots filled)"
                       : std::string(),
            ", ", c_.loop.adam_steps, " Adam steps, mean InfoNCE ", st_.last_loss);
}

LoopStats Loop::Run(bool resume, const std::atomic<bool>* interrupt) {
  torch::set_num_threads(c_.loop.threads);
  group_->LowerLocalFlag(kStopFlag);  // a stop of an earlier run in this process is not this one's
  Resume(resume);
  if (resume && st_.block_start + st_.rounds > 0)
    log::Info("resuming the loop at solve ", walk_from_ + 1, " (", st_.rounds,
              " training rounds done, buffer ", st_.buffer.size(), ")");
  RebuildSampler();
  const int total = Total(), size = group_->size(), rank = group_->rank();
  int since_save = 0;
  int s = walk_from_;        // start of the next chunk: `size` solves, one per rank
  int done = st_.rank_next;  // this rank's solves before `done` are in its pending results
  const auto loop_started = std::chrono::steady_clock::now();
  while (st_.block_start < total) {
    const int block_end =
        std::min(total, (st_.block_start / c_.loop.train_every + 1) * c_.loop.train_every);
    // The ranks meet once per block (the gather before training), not after every solve: a rank
    // whose solves were quick goes on with its next ones instead of waiting for the slowest rank.
    // A stop reaches the others through a flag in the rendezvous store, read between solves.
    bool stopping = false;
    for (; s < block_end; s += size) {
      if (interrupt && interrupt->load() && !stopping) group_->RaiseFlag(kStopFlag);
      if (group_->FlagRaised(kStopFlag)) {
        stopping = true;
        break;
      }
      const int mine = s + rank;
      if (mine < block_end && mine >= done) {
        Solve(mine);
        done = mine + 1;
      }
      st_.rank_next = std::min(block_end, s + size);
      if (++since_save >= c_.loop.checkpoint_every) {
        Save();
        since_save = 0;
      }
    }
    // Every rank stops at this block or none does: the flag is agreed on (one small all-reduce).
    if (interrupt && interrupt->load()) stopping = true;
    std::vector<torch::Tensor> stop{torch::full({1}, stopping ? 1.0 : 0.0, torch::kFloat64)};
    group_->AllReduceSum(stop);
    if (stop[0].item<double>() > 0) {
      Save();
      stats_.interrupted = true;
      log::Info("interrupted before solve ", std::min(s, block_end) + 1,
                "; continue with train --resume");
      break;
    }
    FinishBlock(block_end);
    Save();
    since_save = 0;
    s = done = st_.block_start;
  }
  stats_.loop_seconds = Seconds(loop_started);
  stats_.solves = st_.solves;
  stats_.solved = st_.solved;
  stats_.rounds = st_.rounds;
  stats_.last_loss = st_.last_loss;
  stats_.dropped_particles = st_.dropped;
  stats_.sampler_failures = st_.sampler_failures;
  stats_.failures_kept = static_cast<int>(st_.failures.size());
  return stats_;
}

}  // namespace

std::string LoopStats::ToJson() const {
  std::ostringstream os;
  os << "{\"solves\": " << solves << ", \"solved\": " << solved
     << ", \"success_rate\": " << (solves ? static_cast<double>(solved) / solves : 0.0)
     << ", \"training_rounds\": " << rounds << ", \"last_loss\": " << last_loss
     << ", \"dropped_particles\": " << dropped_particles
     << ", \"sampler_failures\": " << sampler_failures << ", \"failures_kept\": " << failures_kept
     << ", \"solve_seconds\": " << solve_seconds << ", \"negative_seconds\": " << negative_seconds
     << ", \"train_seconds\": " << train_seconds << ", \"loop_seconds\": " << loop_seconds
     << ", \"interrupted\": " << (interrupted ? "true" : "false") << "}";
  return os.str();
}

std::string LoopCheckpointPath(const std::string& run_dir, int rank) {
  return run_dir + "/checkpoints/loop" + (rank ? ".rank" + std::to_string(rank) : "") + ".pt";
}

manipulation::EnergyModelParts MakeEnergyParts(const ExperimentConfig& c,
                                               const manipulation::RobotModel& robot,
                                               const Encoding& encoding, const Mlp& energy) {
  manipulation::EnergyModelParts p;
  p.lattice = c.lattice;
  p.bps_mean = encoding.bps_mean;
  p.bps_std = encoding.bps_std;
  p.encoder = encoding.encoder;
  p.energy = energy;
  p.lower = robot.limits().lower;
  p.upper = robot.limits().upper;
  p.velocity_scale = 1.0;
  p.intermediate_commands = c.gfcs.commands - 1;
  return p;
}

LoopStats RunSelfSupervisedLoop(const ExperimentConfig& c, const std::string& config_yaml,
                                const manipulation::RobotModel& robot, const Encoding& encoding,
                                const std::vector<TrainingProblem>& problems,
                                const std::string& run_dir, bool resume,
                                const std::atomic<bool>* interrupt, Mlp* energy,
                                manipulation::SolutionMemory* memory) {
  FS_THROW_UNLESS(!problems.empty(), run_dir, ": no valid training problems");
  fs::create_directories(run_dir + "/checkpoints");
  torch::manual_seed(static_cast<std::uint64_t>(c.seed));
  Loop loop(c, config_yaml, robot, encoding, problems, run_dir);
  const LoopStats stats = loop.Run(resume, interrupt);
  *energy = loop.Energy();
  *memory = loop.Memory();
  return stats;
}

void LoadLoopResult(const ExperimentConfig& c, const std::string& config_yaml,
                    const std::string& run_dir, Encoding* encoding, Mlp* energy,
                    manipulation::SolutionMemory* memory) {
  const std::string path = LoopCheckpointPath(run_dir, 0);
  FS_THROW_UNLESS(fs::exists(path), run_dir,
                  ": no loop checkpoint (the run has not started its loop; continue it with train "
                  "--resume)");
  torch::serialize::InputArchive a;
  a.load_from(path);
  const std::string diff = FirstDifference(config_yaml, TensorText(Read(&a, "config_yaml")));
  FS_THROW_UNLESS(diff.empty(), path, ": the checkpoint is from another config (", diff, ")");
  const torch::Tensor counters = Read(&a, "counters");
  FS_THROW_UNLESS(counters.size(0) == 8, path, ": not a loop checkpoint of this version");
  const std::int64_t at = counters[0].item<std::int64_t>(),
                     total = counters[6].item<std::int64_t>();
  FS_THROW_UNLESS(at >= total, path, ": the loop is unfinished (", at, " of ", total,
                  " solves trained on); continue it with train --resume");
  encoding->bps_mean = ToVector(Read(&a, "encoding.bps_mean"));
  encoding->bps_std = ToVector(Read(&a, "encoding.bps_std"));
  encoding->encoder = ReadMlp(&a, "encoding.encoder");
  EnergyNet net = MakeNet(c, manipulation::kDof * 3 + encoding->encoder.output_size());
  torch::serialize::InputArchive n;
  a.read("net", n);
  net->load(n);
  *energy = net->net()->ToMlp();
  Eigen::MatrixXf contexts;
  const std::vector<Positive> positives = ReadMemory(&a, path, &contexts);
  *memory = MakeMemory(positives, contexts);
}

}  // namespace foresight::gfcs
