#include "training/trainer.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numeric>
#include <random>
#include <sstream>

#include "core/error.h"
#include "core/file_io.h"
#include "core/log.h"
#include "core/parse.h"
#include "training/distributed.h"
#include "training/progress.h"

namespace foresight {
namespace fs = std::filesystem;

double LearningRateAt(const TrainConfig& c, int epoch) {
  switch (c.schedule) {
    case LrSchedule::kConstant:
      return c.learning_rate;
    case LrSchedule::kStep:
      return c.learning_rate * std::pow(c.step_factor, epoch / c.step_every);
    case LrSchedule::kCosine: {
      const double progress = c.epochs > 1 ? static_cast<double>(epoch) / (c.epochs - 1) : 0.0;
      const double lo = c.min_lr_ratio;
      return c.learning_rate * (lo + (1.0 - lo) * 0.5 * (1.0 + std::cos(M_PI * progress)));
    }
  }
  return c.learning_rate;
}

const char* ToString(TerminationReason r) {
  switch (r) {
    case TerminationReason::kMaxEpochs:
      return "max_epochs";
    case TerminationReason::kEarlyStopped:
      return "early_stopped";
    case TerminationReason::kNonFiniteLoss:
      return "non_finite_loss";
    case TerminationReason::kInterrupted:
      return "interrupted";
    case TerminationReason::kAlreadyComplete:
      return "already_complete";
  }
  return "";
}

std::string TrainingSummary::BriefReport() const {
  std::ostringstream os;
  os << "training " << ToString(reason) << " after " << epochs_completed
     << " epochs; best val loss " << best_val_loss << " at epoch " << best_epoch << "; " << seconds
     << " s, " << std::lround(samples_per_second) << " samples/s";
  return os.str();
}

namespace {
/// A JSON number, or null for NaN and inf (which JSON cannot hold).
std::string JsonNumber(double v) {
  std::ostringstream os;
  os << v;
  return std::isfinite(v) ? os.str() : "null";
}
}  // namespace

std::string TrainingSummary::ToJson() const {
  std::ostringstream os;
  os << "{\"reason\": \"" << ToString(reason) << "\", \"epochs_completed\": " << epochs_completed
     << ", \"best_epoch\": " << best_epoch << ", \"best_val_loss\": " << JsonNumber(best_val_loss)
     << ", \"last_train_loss\": " << JsonNumber(last_train_loss)
     << ", \"seconds\": " << JsonNumber(seconds)
     << ", \"samples_per_second\": " << JsonNumber(samples_per_second) << "}\n";
  return os.str();
}

void WriteTrainingSummary(const std::string& path, const TrainingSummary& s) {
  if (s.reason == TerminationReason::kAlreadyComplete) {
    // Keep the summary of the invocation that finished, if it got to write one (a run killed
    // after its last epoch but before its summary left an earlier, interrupted one).
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    for (const TerminationReason finished :
         {TerminationReason::kMaxEpochs, TerminationReason::kEarlyStopped})
      if (text.str().find(std::string("\"reason\": \"") + ToString(finished) + "\"") !=
          std::string::npos)
        return;
  }
  WriteFileAtomically(path, s.ToJson());
}

namespace {
std::atomic<bool> g_interrupted{false};
extern "C" void SetInterrupted(int sig) {
  if (g_interrupted.exchange(true)) {  // the second signal: stop waiting for the next batch
    std::signal(sig, SIG_DFL);
    std::raise(sig);
  }
}
}  // namespace

ScopedInterruptFlag::ScopedInterruptFlag() {
  g_interrupted = false;
  previous_int_ = std::signal(SIGINT, SetInterrupted);
  previous_term_ = std::signal(SIGTERM, SetInterrupted);
}

ScopedInterruptFlag::~ScopedInterruptFlag() {
  if (previous_int_ != SIG_ERR) std::signal(SIGINT, previous_int_);
  if (previous_term_ != SIG_ERR) std::signal(SIGTERM, previous_term_);
}

const std::atomic<bool>* ScopedInterruptFlag::flag() const { return &g_interrupted; }

namespace {

constexpr const char* kMetricsHeader =
    "epoch,train_loss,val_loss,learning_rate,seconds,samples_per_second";

/// Flushes the file or directory `path` to disk; `required` failures are an Error.
void Sync(const std::string& path, bool required) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  const bool ok = fd >= 0 && ::fsync(fd) == 0;
  if (fd >= 0) ::close(fd);
  FS_THROW_UNLESS(ok || !required, path, ": cannot flush to disk");
}

/// First line of a (LibTorch) exception message, shortened: our errors are one line.
std::string Brief(const std::exception& e) {
  std::string s = e.what();
  s = s.substr(0, s.find('\n'));
  return s.size() > 160 ? s.substr(0, 160) + "..." : s;
}

/// Trainer state saved with every checkpoint.
struct State {
  int epoch = 0;  ///< completed epochs
  int best_epoch = -1;
  double best_val = INFINITY;
  int bad_epochs = 0;
};

// A checkpoint is LibTorch's archive followed by a 16-byte trailer: "FSCKPT01" and the FNV-1a
// hash of the archive (little-endian). LibTorch's reader does not notice flipped bytes inside
// tensor data; the trailer does, before anything is loaded.
constexpr char kChecksumMagic[8] = {'F', 'S', 'C', 'K', 'P', 'T', '0', '1'};

std::uint64_t Fnv1a(const char* data, std::size_t size) {
  std::uint64_t h = 1469598103934665603ULL;
  for (std::size_t i = 0; i < size; ++i) {
    h ^= static_cast<unsigned char>(data[i]);
    h *= 1099511628211ULL;
  }
  return h;
}

std::string WithChecksum(std::string bytes) {
  const std::uint64_t h = Fnv1a(bytes.data(), bytes.size());
  bytes.append(kChecksumMagic, sizeof(kChecksumMagic));
  for (int i = 0; i < 8; ++i) bytes.push_back(static_cast<char>((h >> (8 * i)) & 0xFF));
  return bytes;
}

/// The archive of a checkpoint file's bytes; a wrong checksum is an Error naming the file.
std::string WithoutChecksum(const std::string& path, const std::string& bytes) {
  const std::size_t n = bytes.size();
  const bool has_trailer = n >= 16 && bytes.compare(n - 16, 8, kChecksumMagic, 8) == 0;
  // Required: without it a corrupted file would reach LibTorch's archive reader, which is not
  // hardened against damaged input (it can crash the process; docs/robustness.md).
  FS_THROW_UNLESS(
      has_trailer, path,
      ": checkpoint has no checksum trailer (truncated, corrupted, or written by a build "
      "older than the checksum); delete it to start again, or restore a copy");
  std::uint64_t stored = 0;
  for (int i = 0; i < 8; ++i)
    stored |= static_cast<std::uint64_t>(static_cast<unsigned char>(bytes[n - 8 + i])) << (8 * i);
  FS_THROW_UNLESS(Fnv1a(bytes.data(), n - 16) == stored, path,
                  ": checkpoint checksum does not match its contents (corrupted on disk); "
                  "delete it to start again, or restore a copy");
  return bytes.substr(0, n - 16);
}

void SaveCheckpoint(const std::string& path, torch::nn::Module& module,
                    torch::optim::Optimizer& opt, const State& s) {
  torch::serialize::OutputArchive archive;
  torch::serialize::OutputArchive model_archive, opt_archive;
  module.save(model_archive);
  opt.save(opt_archive);
  archive.write("model", model_archive);
  archive.write("optimizer", opt_archive);
  archive.write("state/epoch", torch::tensor(static_cast<int64_t>(s.epoch)));
  archive.write("state/best_epoch", torch::tensor(static_cast<int64_t>(s.best_epoch)));
  archive.write("state/best_val", torch::tensor(s.best_val, torch::kFloat64));
  archive.write("state/bad_epochs", torch::tensor(static_cast<int64_t>(s.bad_epochs)));
  // Serialised in memory, then written with checked calls: LibTorch's file writer aborts the
  // process when the disk fills (its destructor throws), and a full disk must only stop the run.
  std::ostringstream bytes;
  archive.save_to(bytes);
  try {
    WriteFileAtomically(path, WithChecksum(bytes.str()));
  } catch (const Error& e) {
    const std::string name = fs::path(path).filename().string();
    Fail(e.what(), fs::exists(path) ? "; the previous " + name + " is kept"
                                    : "; no " + name + " was saved before");
  }
}

/// The archive bytes of the checkpoint file `path` (checksum verified).
std::string ReadCheckpointBytes(const std::string& path) {
  FS_THROW_UNLESS(fs::exists(path), path, ": checkpoint not found");
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  FS_THROW_UNLESS(in.good() || in.eof(), path, ": cannot read the checkpoint");
  return WithoutChecksum(path, bytes);
}

/// The archive of checkpoint bytes read from `path`.
torch::serialize::InputArchive OpenCheckpointBytes(const std::string& path,
                                                   const std::string& bytes) {
  std::istringstream archive_bytes(bytes);
  torch::serialize::InputArchive archive;
  try {
    archive.load_from(archive_bytes);
  } catch (const std::exception& e) {
    Fail(path, ": corrupt or truncated checkpoint (", Brief(e), ")");
  }
  return archive;
}

torch::serialize::InputArchive OpenCheckpoint(const std::string& path) {
  return OpenCheckpointBytes(path, ReadCheckpointBytes(path));
}

void ReadModel(const std::string& path, torch::serialize::InputArchive& archive,
               torch::nn::Module* module) {
  try {
    torch::serialize::InputArchive model_archive;
    archive.read("model", model_archive);
    module->load(model_archive);
  } catch (const std::exception& e) {
    Fail(path, ": checkpoint does not match the model (", Brief(e), ")");
  }
}

/// One scalar of the trainer state, read into a fresh tensor: `InputArchive::read` into a defined
/// tensor calls `set_` and keeps that tensor's dtype, so reusing one tensor for an int64 and then a
/// float64 entry reinterprets the float's bits as an integer (the resume defect of issue 18).
torch::Tensor ReadStateScalar(const std::string& path, torch::serialize::InputArchive& archive,
                              const std::string& key, torch::Dtype dtype) {
  torch::Tensor t;
  archive.read(key, t);
  FS_THROW_UNLESS(t.defined() && t.numel() == 1 && t.scalar_type() == dtype, path, ": entry '", key,
                  "' is not a scalar of the expected type");
  return t;
}

/// Loads checkpoint bytes read from `path` into the module, the optimiser and the trainer state.
State LoadCheckpointBytes(const std::string& path, const std::string& bytes,
                          torch::nn::Module* module, torch::optim::Optimizer* opt) {
  auto archive = OpenCheckpointBytes(path, bytes);
  ReadModel(path, archive, module);
  State s;
  try {
    torch::serialize::InputArchive opt_archive;
    archive.read("optimizer", opt_archive);
    opt->load(opt_archive);
    s.epoch = static_cast<int>(
        ReadStateScalar(path, archive, "state/epoch", torch::kInt64).item<int64_t>());
    s.best_epoch = static_cast<int>(
        ReadStateScalar(path, archive, "state/best_epoch", torch::kInt64).item<int64_t>());
    s.best_val = ReadStateScalar(path, archive, "state/best_val", torch::kFloat64).item<double>();
    s.bad_epochs = static_cast<int>(
        ReadStateScalar(path, archive, "state/bad_epochs", torch::kInt64).item<int64_t>());
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    Fail(path, ": checkpoint is missing trainer state (", Brief(e), ")");
  }
  return s;
}

State LoadCheckpoint(const std::string& path, torch::nn::Module* module,
                     torch::optim::Optimizer* opt) {
  return LoadCheckpointBytes(path, ReadCheckpointBytes(path), module, opt);
}

/// Data parallel: rank 0 reads the checkpoint and sends its bytes to every rank (the other ranks
/// need no access to rank 0's disk); a failure on rank 0 is the same Error on every rank.
State LoadCheckpointEverywhere(dist::Group* group, const std::string& path,
                               torch::nn::Module* module, torch::optim::Optimizer* opt) {
  std::string message;
  if (group->rank() == 0) {
    try {
      message = "+" + ReadCheckpointBytes(path);
    } catch (const Error& e) {
      message = std::string("-") + e.what();
    }
  }
  message = group->BroadcastBytes(message, 0);
  FS_THROW_UNLESS(!message.empty() && message[0] == '+', "rank 0: ", message.substr(1));
  return LoadCheckpointBytes(path, message.substr(1), module, opt);
}

/// Data parallel: every rank must train the same thing; a difference is an Error naming the rank.
void CheckRanksAgree(dist::Group* group, TrainingTask* task, const TrainConfig& c,
                     std::uint64_t seed, bool resume) {
  std::int64_t numel = 0;
  for (const auto& p : task->module().parameters()) numel += p.numel();
  std::ostringstream mine;
  mine << "num_train=" << task->num_train() << " parameters=" << numel
       << " batch_size=" << c.batch_size << " epochs=" << c.epochs << " seed=" << seed
       << " resume=" << resume;
  const auto all = group->AllGatherBytes(mine.str());
  for (std::size_t r = 1; r < all.size(); ++r)
    FS_THROW_UNLESS(all[r] == all[0], "data-parallel ranks disagree: rank 0 has ", all[0],
                    ", rank ", r, " has ", all[r]);
}

/// Rank 0's `value` on every rank.
double FromRankZero(dist::Group* group, double value) {
  if (!group->distributed()) return value;
  std::vector<torch::Tensor> t{torch::tensor({value}, torch::kFloat64)};
  group->Broadcast(t, 0);
  return t[0].item<double>();
}

/// Keeps the metrics rows of epochs 1..epoch (a resumed run rewrites later ones). A missing file
/// stays missing (AppendMetrics starts it with the header).
void TruncateMetrics(const std::string& path, int epoch) {
  std::ifstream in(path);
  if (!in.good()) return;
  std::vector<std::string> keep{kMetricsHeader};
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (number == 1 || line.empty()) continue;  // line 1 is the header (kept as kMetricsHeader)
    const auto row_epoch = ParseInteger(line.substr(0, line.find(',')));
    FS_THROW_UNLESS(row_epoch.has_value(), path, ":", number,
                    ": row does not start with an epoch number");
    if (*row_epoch <= epoch) keep.push_back(line);
  }
  in.close();
  std::string text;
  for (const auto& l : keep) text += l + "\n";
  WriteFileAtomically(path, text);
}

/// Appends one row (starting the file with the header when it is missing) and flushes it to disk.
void AppendMetrics(const std::string& path, const std::string& row) {
  const bool start = !fs::exists(path);
  std::ofstream out(path, std::ios::app);
  if (start) out << kMetricsHeader << "\n";
  out << row << "\n";
  out.close();
  FS_THROW_UNLESS(out.good(), path, ": cannot append to the metrics");
  Sync(path, true);
}

void SetLearningRate(torch::optim::Adam* opt, double lr) {
  for (auto& group : opt->param_groups())
    static_cast<torch::optim::AdamOptions&>(group.options()).lr(lr);
}

}  // namespace

void LoadCheckpointModel(const std::string& path, torch::nn::Module* module) {
  auto archive = OpenCheckpoint(path);
  ReadModel(path, archive, module);
}

TrainingSummary Train(TrainingTask* task, const TrainConfig& c, const RunPaths& run,
                      std::uint64_t seed, bool resume, const TrainHooks& hooks,
                      dist::Group* group) {
  std::shared_ptr<dist::Group> default_group;
  if (group == nullptr) {
    default_group = dist::DefaultGroup();
    group = default_group.get();
  }
  // Data parallel (docs/distributed.md): every rank runs this loop in lockstep on the same
  // shuffled global batches; rank 0 alone writes files and computes the validation loss.
  const bool distributed = group->distributed();
  const bool writer = group->rank() == 0;
  torch::set_num_threads(c.threads);
  if (writer) fs::create_directories(run.dir + "/checkpoints");
  torch::nn::Module& module = task->module();
  torch::optim::Adam opt(module.parameters(),
                         torch::optim::AdamOptions(c.learning_rate).weight_decay(c.weight_decay));
  if (distributed) CheckRanksAgree(group, task, c, seed, resume);
  State state;
  // A run killed (or stopped by a full disk) before its first complete last.pt has nothing to
  // continue: --resume then starts at epoch 1 (only rank 0's disk holds checkpoints).
  if (resume) {
    const bool has_checkpoint =
        FromRankZero(group, writer && fs::exists(run.Checkpoint()) ? 1.0 : 0.0) == 1.0;
    if (!has_checkpoint && writer)
      log::Warn(run.Checkpoint(),
                " does not exist (the run stopped before its first complete "
                "checkpoint); starting at epoch 1");
    resume = has_checkpoint;
  }
  if (resume) {
    state = distributed ? LoadCheckpointEverywhere(group, run.Checkpoint(), &module, &opt)
                        : LoadCheckpoint(run.Checkpoint(), &module, &opt);
    if (writer) {
      TruncateMetrics(run.Metrics(), state.epoch);
      log::Info("resuming ", run.Checkpoint(), " after epoch ", state.epoch);
    }
  } else if (writer) {
    fs::remove(run.Metrics());  // started with the first row: an epoch-less run leaves none
  }
  if (distributed) group->BroadcastParameters(module, 0);
  // After a stop that restores the last checkpoint (rank 0's disk), every rank holds its model.
  const auto restore_checkpoint = [&] {
    if (writer && fs::exists(run.Checkpoint())) LoadCheckpointModel(run.Checkpoint(), &module);
    if (distributed) group->BroadcastParameters(module, 0);
  };

  TrainingSummary summary;
  const auto t0 = std::chrono::steady_clock::now();
  const std::int64_t n = task->num_train();
  FS_THROW_UNLESS(n > 0, "training set is empty");
  Progress progress(writer ? c.progress : ProgressStyle::kNone, c.epochs, "samples");
  double items = 0;
  bool stop = false;
  if (state.epoch >= c.epochs || (c.patience > 0 && state.bad_epochs >= c.patience)) {
    summary.reason = TerminationReason::kAlreadyComplete;
    stop = true;
  }
  std::vector<std::int64_t> order(static_cast<std::size_t>(n));
  while (!stop) {
    const int epoch = state.epoch;  // 0-based index of the epoch being run
    const auto e0 = std::chrono::steady_clock::now();
    const double lr = LearningRateAt(c, epoch);
    SetLearningRate(&opt, lr);
    // The shuffle depends only on (seed, epoch): a resumed run sees the same batches.
    std::iota(order.begin(), order.end(), 0);
    std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ULL + static_cast<std::uint64_t>(epoch));
    std::shuffle(order.begin(), order.end(), rng);
    module.train();
    double loss_sum = 0;
    std::int64_t seen = 0;
    bool finite = true;
    bool interrupted = false;
    for (std::int64_t b = 0; b < n; b += c.batch_size) {
      const std::int64_t len = std::min<std::int64_t>(c.batch_size, n - b);
      double value = 0;
      if (!distributed) {
        if (hooks.interrupt && hooks.interrupt->load()) {
          interrupted = true;
          break;
        }
        const auto idx = torch::from_blob(order.data() + b, {len}, torch::kInt64).clone();
        opt.zero_grad();
        torch::Tensor loss = task->BatchLoss(idx);
        value = loss.item<double>();
        if (!std::isfinite(value)) {
          finite = false;
          break;
        }
        loss.backward();
      } else {
        // This rank's contiguous slice of the global batch; its gradient enters the sum with
        // weight slice/len, so the sum is the gradient of the global-batch mean loss. The batch
        // loss and the interrupt flags ride along in the same all-reduce.
        const std::int64_t lo = len * group->rank() / group->size();
        const std::int64_t hi = len * (group->rank() + 1) / group->size();
        const double weight = static_cast<double>(hi - lo) / static_cast<double>(len);
        const bool interrupt_here = hooks.interrupt && hooks.interrupt->load();
        opt.zero_grad();
        double local = 0;
        if (!interrupt_here && hi > lo) {
          const auto idx =
              torch::from_blob(order.data() + b + lo, {hi - lo}, torch::kInt64).clone();
          torch::Tensor loss = task->BatchLoss(idx);
          local = loss.item<double>();
          if (std::isfinite(local)) loss.backward();
        }
        std::vector<double> extra{local * weight, interrupt_here ? 1.0 : 0.0};
        group->AllReduceGradients(module, weight, &extra);
        if (extra[1] > 0) {
          interrupted = true;
          break;
        }
        value = extra[0];
        if (!std::isfinite(value)) {
          finite = false;
          break;
        }
      }
      if (c.grad_clip_norm > 0)
        torch::nn::utils::clip_grad_norm_(module.parameters(), c.grad_clip_norm);
      opt.step();
      loss_sum += value * static_cast<double>(len);
      seen += len;
      items += static_cast<double>(len);
      progress.Update(epoch, static_cast<double>(seen) / static_cast<double>(n), items,
                      loss_sum / static_cast<double>(seen));
    }
    if (interrupted) {
      summary.reason = TerminationReason::kInterrupted;
      if (writer && state.epoch == 0)
        log::Warn("interrupted in epoch 1 before the first checkpoint; nothing was saved");
      else if (writer)
        log::Warn("interrupted in epoch ", epoch + 1, "; the checkpoint of epoch ", state.epoch,
                  " is kept (continue with --resume)");
      restore_checkpoint();
      break;
    }
    double val = NAN;
    if (finite) {
      module.eval();
      torch::NoGradGuard no_grad;
      if (writer) val = task->ValidationLoss();
      val = FromRankZero(group, val);
      finite = std::isfinite(val);
    }
    if (!finite) {
      summary.reason = TerminationReason::kNonFiniteLoss;
      if (writer && state.epoch == 0)
        log::Warn("non-finite loss in epoch 1; stopping before the first checkpoint");
      else if (writer)
        log::Warn("non-finite loss in epoch ", epoch + 1,
                  "; stopping and keeping the checkpoint of epoch ", state.epoch);
      restore_checkpoint();
      break;
    }
    const double train_loss = loss_sum / static_cast<double>(seen);
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - e0).count();
    state.epoch = epoch + 1;
    // The row goes first: a run killed before its checkpoint resumes from the previous epoch and
    // drops the row (TruncateMetrics), so no row is lost or duplicated.
    std::ostringstream row;
    row << state.epoch << "," << train_loss << "," << val << "," << lr << "," << secs << ","
        << static_cast<double>(seen) / std::max(secs, 1e-9);
    if (writer) AppendMetrics(run.Metrics(), row.str());
    if (val < state.best_val - c.min_delta) {
      state.best_val = val;
      state.best_epoch = state.epoch;
      state.bad_epochs = 0;
      if (writer) SaveCheckpoint(run.BestCheckpoint(), module, opt, state);
    } else {
      ++state.bad_epochs;
    }
    if (writer) SaveCheckpoint(run.Checkpoint(), module, opt, state);
    std::ostringstream line;
    line << "train " << train_loss << " val " << val
         << (state.best_epoch == state.epoch ? " *" : "") << " lr " << lr;
    progress.EndStep(epoch, line.str());
    summary.last_train_loss = train_loss;
    if (state.epoch >= c.epochs) {
      summary.reason = TerminationReason::kMaxEpochs;
      stop = true;
    } else if (c.patience > 0 && state.bad_epochs >= c.patience) {
      summary.reason = TerminationReason::kEarlyStopped;
      stop = true;
    } else if (distributed) {
      // Every rank asks its hook; rank 0's answer holds for all.
      const bool go_on = !hooks.continue_after_epoch || hooks.continue_after_epoch(state.epoch);
      if (FromRankZero(group, go_on ? 1.0 : 0.0) == 0.0) {
        summary.reason = TerminationReason::kInterrupted;
        stop = true;
      }
    } else if (hooks.continue_after_epoch && !hooks.continue_after_epoch(state.epoch)) {
      summary.reason = TerminationReason::kInterrupted;
      stop = true;
    }
  }
  progress.Finish();
  summary.epochs_completed = state.epoch;
  summary.best_epoch = state.best_epoch;
  summary.best_val_loss = state.best_val;
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  summary.samples_per_second = items / std::max(summary.seconds, 1e-9);
  if (writer) log::Info(summary.BriefReport());
  return summary;
}

}  // namespace foresight
