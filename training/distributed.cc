#include "training/distributed.h"

// ProcessGroupGloo.hpp declares its class only with USE_C10D_GLOO (Debian's libtorch is built
// with Gloo; the declarations need libgloo-dev). Kept private to this file.
#ifndef USE_C10D_GLOO
#define USE_C10D_GLOO 1
#endif
#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <torch/csrc/distributed/c10d/FileStore.hpp>
#include <torch/csrc/distributed/c10d/ProcessGroupGloo.hpp>
#include <torch/csrc/distributed/c10d/TCPStore.hpp>

#include "core/error.h"
#include "core/parse.h"

namespace foresight::dist {
namespace {

/// The value of an environment variable, or nothing when unset or empty.
std::optional<std::string> Env(const char* name) {
  const char* v = std::getenv(name);
  if (v == nullptr || *v == '\0') return std::nullopt;
  return std::string(v);
}

int IntFromEnv(const char* name, long long lo, long long hi) {
  const std::string text = *Env(name);
  const auto v = ParseInteger(text);
  FS_THROW_UNLESS(v && *v >= lo && *v <= hi, "environment variable ", name, "='", text,
                  "' is not an integer in [", lo, ", ", hi, "]");
  return static_cast<int>(*v);
}

/// First line of an exception message (LibTorch appends a backtrace), shortened.
std::string Brief(const std::exception& e) {
  std::string s = e.what();
  s = s.substr(0, s.find('\n'));
  return s.size() > 240 ? s.substr(0, 240) + "..." : s;
}

std::string Seconds(std::chrono::milliseconds t) {
  std::ostringstream os;
  os << static_cast<double>(t.count()) / 1000.0 << " s";
  return os.str();
}

/// Store key of a flag; the prefix keeps it apart from Gloo's own keys in the same store.
std::string FlagKey(const std::string& name) { return "foresight/flag/" + name; }

}  // namespace

LaunchInfo LaunchInfoFromEnv() {
  LaunchInfo info;
  const char* rank_var = "RANK";
  const char* size_var = "WORLD_SIZE";
  if (!Env(size_var) && Env("OMPI_COMM_WORLD_SIZE")) {
    rank_var = "OMPI_COMM_WORLD_RANK";
    size_var = "OMPI_COMM_WORLD_SIZE";
  }
  if (!Env(size_var)) return info;  // one process
  info.world_size = IntFromEnv(size_var, 1, 1 << 20);
  FS_THROW_UNLESS(Env(rank_var), "environment variable ", rank_var, " is not set (", size_var, "=",
                  info.world_size, ")");
  info.rank = IntFromEnv(rank_var, 0, 1 << 20);
  FS_THROW_UNLESS(info.rank < info.world_size, "environment variable ", rank_var, "=", info.rank,
                  " is not below ", size_var, "=", info.world_size);
  if (!info.distributed()) return info;
  if (const auto file = Env("FORESIGHT_STORE_FILE")) {
    info.store_file = *file;
    return info;
  }
  FS_THROW_UNLESS(Env("MASTER_ADDR"), "environment variable MASTER_ADDR is not set (needed with ",
                  size_var, "=", info.world_size,
                  " unless FORESIGHT_STORE_FILE names a FileStore)");
  FS_THROW_UNLESS(Env("MASTER_PORT"), "environment variable MASTER_PORT is not set (needed with ",
                  size_var, "=", info.world_size,
                  " unless FORESIGHT_STORE_FILE names a FileStore)");
  info.master_addr = *Env("MASTER_ADDR");
  info.master_port = IntFromEnv("MASTER_PORT", 1, 65535);
  return info;
}

std::chrono::milliseconds TimeoutFromEnv() {
  const auto text = Env("FORESIGHT_DIST_TIMEOUT_S");
  if (!text) return std::chrono::milliseconds(60000);
  const auto v = ParseDouble(*text);
  FS_THROW_UNLESS(v && std::isfinite(*v) && *v > 0 && *v < 1e7,
                  "environment variable FORESIGHT_DIST_TIMEOUT_S='", *text,
                  "' is not a positive number of seconds");
  return std::chrono::milliseconds(std::max<long long>(1, std::llround(*v * 1000.0)));
}

struct Group::Impl {
  int rank = 0, size = 1;
  std::chrono::milliseconds timeout{60000};
  c10::intrusive_ptr<c10d::Store> store;
  c10::intrusive_ptr<c10d::ProcessGroupGloo> pg;
  std::string broken;  ///< the failure that broke the group (later collectives refuse)
  std::set<std::string> local_flags;  ///< RaiseFlag() of a Local() group
  torch::Tensor grad_flat;            ///< reused buffer of AllReduceGradients

  /// Runs one collective and waits for it; any failure becomes an Error naming the rank, the
  /// collective and the cause, and breaks the group (its peers are gone or out of step).
  template <class Start>
  void Run(const std::string& what, Start start) {
    FS_THROW_UNLESS(broken.empty(), "rank ", rank, " of ", size, ": ", what,
                    " refused: the process group failed earlier (", broken, ")");
    try {
      c10::intrusive_ptr<c10d::Work> work = start();
      // Gloo's own timeout ends a stuck transfer; the margin only guards against a lost wake-up.
      work->wait(timeout + std::chrono::milliseconds(10000));
    } catch (const std::exception& e) {
      const std::string peer = size == 2 ? "peer rank " + std::to_string(1 - rank) : "a peer rank";
      broken = what + ": " + Brief(e);
      Fail("rank ", rank, " of ", size, ": ", what, " failed (", peer,
           " exited, crashed or did not answer within ", Seconds(timeout), "): ", Brief(e));
    }
  }

  /// One contiguous tensor per dtype of `tensors`, in first-seen order of dtypes.
  template <class Op>
  void Flattened(std::vector<torch::Tensor>& tensors, Op op) {
    std::map<int, std::vector<std::size_t>> by_type;
    for (std::size_t i = 0; i < tensors.size(); ++i)
      by_type[static_cast<int>(tensors[i].scalar_type())].push_back(i);
    torch::NoGradGuard no_grad;
    for (const auto& [type, members] : by_type) {
      std::vector<torch::Tensor> parts;
      for (std::size_t i : members) parts.push_back(tensors[i].detach().reshape({-1}));
      torch::Tensor flat = torch::cat(parts).contiguous();
      op(flat);
      std::int64_t offset = 0;
      for (std::size_t i : members) {
        const std::int64_t n = tensors[i].numel();
        tensors[i].detach().copy_(flat.slice(0, offset, offset + n).view(tensors[i].sizes()));
        offset += n;
      }
    }
  }

  void BroadcastFlat(torch::Tensor& flat, int root, const std::string& what) {
    std::vector<torch::Tensor> one{flat};
    c10d::BroadcastOptions options;
    options.rootRank = root;
    Run(what, [&] { return pg->broadcast(one, options); });
  }
};

Group::Group(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Group::~Group() = default;

std::shared_ptr<Group> Group::Local() {
  return std::shared_ptr<Group>(new Group(std::make_unique<Impl>()));
}

std::shared_ptr<Group> Group::Create(const LaunchInfo& info, std::chrono::milliseconds timeout) {
  FS_THROW_UNLESS(info.world_size >= 1 && info.rank >= 0 && info.rank < info.world_size, "rank ",
                  info.rank, " is not in a world of ", info.world_size);
  if (!info.distributed()) return Local();
  // Gloo writes with writev(): a write to a peer that died would raise SIGPIPE and end this
  // process. Ignored (unless the program handles it), the write fails and becomes an Error.
  struct sigaction pipe_action {};
  if (::sigaction(SIGPIPE, nullptr, &pipe_action) == 0 && pipe_action.sa_handler == SIG_DFL)
    std::signal(SIGPIPE, SIG_IGN);
  auto impl = std::make_unique<Impl>();
  impl->rank = info.rank;
  impl->size = info.world_size;
  impl->timeout = timeout;
  const std::string where = info.store_file.empty() ? "TCPStore " + info.master_addr + ":" +
                                                          std::to_string(info.master_port)
                                                    : "FileStore " + info.store_file;
  try {
    if (!info.store_file.empty()) {
      impl->store = c10::make_intrusive<c10d::FileStore>(info.store_file, info.world_size);
    } else {
      c10d::TCPStoreOptions options;
      options.port = static_cast<std::uint16_t>(info.master_port);
      options.isServer = info.rank == 0;
      options.numWorkers = static_cast<std::size_t>(info.world_size);
      options.waitWorkers = true;
      options.timeout = timeout;
      impl->store = c10::make_intrusive<c10d::TCPStore>(info.master_addr, options);
    }
    impl->store->setTimeout(timeout);
    auto options = c10d::ProcessGroupGloo::Options::create(timeout);
    const auto ifname = Env("GLOO_SOCKET_IFNAME");
    options->devices.push_back(ifname ? c10d::ProcessGroupGloo::createDeviceForInterface(*ifname)
                                      : c10d::ProcessGroupGloo::createDefaultDevice());
    impl->pg = c10::make_intrusive<c10d::ProcessGroupGloo>(impl->store, info.rank, info.world_size,
                                                           options);
  } catch (const std::exception& e) {
    Fail("rank ", info.rank, " of ", info.world_size, ": cannot join the process group through ",
         where, " within ", Seconds(timeout), ": ", Brief(e));
  }
  return std::shared_ptr<Group>(new Group(std::move(impl)));
}

int Group::rank() const { return impl_->rank; }
int Group::size() const { return impl_->size; }

void Group::AllReduceSum(std::vector<torch::Tensor>& tensors) {
  if (!distributed() || tensors.empty()) return;
  impl_->Flattened(tensors, [&](torch::Tensor& flat) {
    std::vector<torch::Tensor> one{flat};
    impl_->Run("all-reduce (sum) of " + std::to_string(flat.numel()) + " values",
               [&] { return impl_->pg->allreduce(one); });
  });
}

void Group::AllReduceGradients(torch::nn::Module& module) {
  AllReduceGradients(module, 1.0 / size(), nullptr);
}

void Group::AllReduceGradients(torch::nn::Module& module, double weight,
                               std::vector<double>* extra) {
  torch::NoGradGuard no_grad;
  std::vector<torch::Tensor> params = module.parameters();
  if (!distributed()) {
    if (weight != 1.0)
      for (auto& p : params)
        if (p.grad().defined()) p.mutable_grad().mul_(weight);
    return;
  }
  // Layout: every grad (times weight), one "defined here" flag per parameter, then `extra`.
  const auto dtype = params.empty() ? torch::kFloat32 : params[0].scalar_type();
  std::int64_t total = 0;
  for (const auto& p : params) total += p.numel();
  const std::int64_t n_params = static_cast<std::int64_t>(params.size());
  const std::int64_t n_extra = extra ? static_cast<std::int64_t>(extra->size()) : 0;
  const std::int64_t length = total + n_params + n_extra;
  torch::Tensor& flat = impl_->grad_flat;
  if (!flat.defined() || flat.numel() != length || flat.scalar_type() != dtype)
    flat = torch::empty({length}, torch::TensorOptions().dtype(dtype));
  std::vector<double> tail(static_cast<std::size_t>(n_params + n_extra), 0.0);
  std::int64_t offset = 0;
  for (std::size_t i = 0; i < params.size(); ++i) {
    const auto& p = params[i];
    const std::int64_t n = p.numel();
    torch::Tensor part = flat.slice(0, offset, offset + n);
    if (p.grad().defined()) {
      torch::mul_out(part, p.grad().reshape({-1}).to(dtype), weight);
      tail[i] = 1.0;
    } else {
      part.zero_();
    }
    offset += n;
  }
  if (extra) std::copy(extra->begin(), extra->end(), tail.begin() + n_params);
  flat.slice(0, total, length).copy_(torch::tensor(tail, torch::kFloat64));
  std::vector<torch::Tensor> one{flat};
  impl_->Run("all-reduce of gradients (" + std::to_string(total) + " values)",
             [&] { return impl_->pg->allreduce(one); });
  const torch::Tensor summed_tail = flat.slice(0, total, length).to(torch::kFloat64).contiguous();
  const double* sums = summed_tail.data_ptr<double>();
  offset = 0;
  for (std::size_t i = 0; i < params.size(); ++i) {
    auto& p = params[i];
    const std::int64_t n = p.numel();
    if (sums[i] > 0) {  // defined on some rank
      if (!p.grad().defined()) p.mutable_grad() = torch::zeros_like(p);
      p.mutable_grad().copy_(flat.slice(0, offset, offset + n).view(p.sizes()));
    }
    offset += n;
  }
  if (extra) std::copy(sums + n_params, sums + n_params + n_extra, extra->begin());
}

void Group::BroadcastParameters(torch::nn::Module& module, int root) {
  if (!distributed()) return;
  std::vector<torch::Tensor> tensors = module.parameters();
  for (const auto& b : module.buffers()) tensors.push_back(b);
  if (tensors.empty()) return;
  impl_->Flattened(tensors, [&](torch::Tensor& flat) {
    impl_->BroadcastFlat(flat, root, "broadcast of parameters from rank " + std::to_string(root));
  });
}

void Group::Broadcast(std::vector<torch::Tensor>& tensors, int root) {
  if (!distributed() || tensors.empty()) return;
  impl_->Flattened(tensors, [&](torch::Tensor& flat) {
    impl_->BroadcastFlat(flat, root, "broadcast from rank " + std::to_string(root));
  });
}

std::string Group::BroadcastBytes(const std::string& mine, int root) {
  if (!distributed()) return mine;
  const std::string what = "broadcast of bytes from rank " + std::to_string(root);
  torch::Tensor length = torch::tensor({static_cast<std::int64_t>(mine.size())}, torch::kInt64);
  impl_->BroadcastFlat(length, root, what);
  const std::int64_t n = length.item<std::int64_t>();
  torch::Tensor bytes = torch::zeros({n}, torch::kUInt8);
  if (rank() == root && n > 0)
    std::memcpy(bytes.data_ptr<std::uint8_t>(), mine.data(), mine.size());
  if (n > 0) impl_->BroadcastFlat(bytes, root, what);
  return std::string(reinterpret_cast<const char*>(bytes.data_ptr<std::uint8_t>()),
                     static_cast<std::size_t>(n));
}

std::vector<std::string> Group::AllGatherBytes(const std::string& mine) {
  if (!distributed()) return {mine};
  const int n = size();
  auto gather = [&](const torch::Tensor& input) {
    std::vector<std::vector<torch::Tensor>> outputs(1);
    for (int r = 0; r < n; ++r) outputs[0].push_back(torch::empty_like(input));
    std::vector<torch::Tensor> inputs{input};
    impl_->Run("all-gather of bytes", [&] { return impl_->pg->allgather(outputs, inputs); });
    return outputs[0];
  };
  const auto lengths =
      gather(torch::tensor({static_cast<std::int64_t>(mine.size())}, torch::kInt64));
  std::int64_t longest = 0;
  for (const auto& l : lengths) longest = std::max(longest, l.item<std::int64_t>());
  torch::Tensor padded = torch::zeros({std::max<std::int64_t>(longest, 1)}, torch::kUInt8);
  if (!mine.empty()) std::memcpy(padded.data_ptr<std::uint8_t>(), mine.data(), mine.size());
  const auto all = gather(padded);
  std::vector<std::string> out;
  for (int r = 0; r < n; ++r)
    out.emplace_back(reinterpret_cast<const char*>(all[r].data_ptr<std::uint8_t>()),
                     static_cast<std::size_t>(lengths[r].item<std::int64_t>()));
  return out;
}

void Group::Barrier() {
  if (!distributed()) return;
  impl_->Run("barrier", [&] { return impl_->pg->barrier(); });
}

void Group::RaiseFlag(const std::string& name) {
  if (!distributed()) {
    impl_->local_flags.insert(name);
    return;
  }
  try {
    impl_->store->set(FlagKey(name), std::vector<std::uint8_t>{1});
  } catch (const std::exception& e) {
    Fail("rank ", rank(), " of ", size(), ": cannot raise the flag '", name,
         "' in the rendezvous store: ", Brief(e));
  }
}

void Group::LowerLocalFlag(const std::string& name) {
  if (!distributed()) impl_->local_flags.erase(name);
}

bool Group::FlagRaised(const std::string& name) {
  if (!distributed()) return impl_->local_flags.count(name) > 0;
  try {
    return impl_->store->check({FlagKey(name)});
  } catch (const std::exception& e) {
    Fail("rank ", rank(), " of ", size(), ": cannot read the flag '", name,
         "' from the rendezvous store (rank 0, which holds a TCPStore, may have exited): ",
         Brief(e));
  }
}

std::shared_ptr<Group> DefaultGroup() {
  static std::mutex mutex;
  static std::shared_ptr<Group> group;
  std::lock_guard<std::mutex> lock(mutex);
  if (!group) group = Group::Create(LaunchInfoFromEnv(), TimeoutFromEnv());
  return group;
}

}  // namespace foresight::dist
