#pragma once
/// Data-parallel training through LibTorch's own c10d process groups (Gloo over TCP), launched
/// like torchrun (RANK, WORLD_SIZE, MASTER_ADDR, MASTER_PORT) or by OpenMPI's mpirun
/// (OMPI_COMM_WORLD_RANK, OMPI_COMM_WORLD_SIZE). docs/distributed.md describes the launch, what is
/// exchanged each step and what happens when a rank fails.
///
/// Every collective of a Group throws foresight::Error when it fails (a peer exited, a timeout):
/// the message names this rank, the collective and the cause. Nothing here aborts or hangs past
/// the group's timeout.

#include <torch/torch.h>

#include <chrono>
#include <memory>
#include <string>
#include <vector>

namespace foresight::dist {

/// Where this process sits in a job and how the ranks meet.
struct LaunchInfo {
  int rank = 0, world_size = 1;
  std::string master_addr;  ///< MASTER_ADDR: host of rank 0's TCPStore
  int master_port = 0;      ///< MASTER_PORT
  std::string store_file;   ///< FORESIGHT_STORE_FILE: FileStore rendezvous instead of TCP
  bool distributed() const { return world_size > 1; }
};

/// From RANK/WORLD_SIZE/MASTER_ADDR/MASTER_PORT (torchrun style) or OMPI_COMM_WORLD_RANK/SIZE
/// (mpirun; MASTER_ADDR/MASTER_PORT or FORESIGHT_STORE_FILE still name the rendezvous). WORLD_SIZE
/// wins over OMPI_COMM_WORLD_SIZE; neither set means one process. With more than one rank,
/// FORESIGHT_STORE_FILE or both MASTER_ADDR and MASTER_PORT are needed. Bad or missing values are
/// a foresight::Error naming the variable.
LaunchInfo LaunchInfoFromEnv();

/// Timeout of every collective and of the rendezvous: FORESIGHT_DIST_TIMEOUT_S (seconds, > 0),
/// else 60 s.
std::chrono::milliseconds TimeoutFromEnv();

/// One process group. World size 1 makes every collective a local no-op.
class Group {
 public:
  /// Joins the group of `info` (waits up to `timeout` for every rank). A size-1 `info` is Local().
  static std::shared_ptr<Group> Create(const LaunchInfo& info,
                                       std::chrono::milliseconds timeout = TimeoutFromEnv());
  static std::shared_ptr<Group> Local();
  ~Group();
  Group(const Group&) = delete;
  Group& operator=(const Group&) = delete;

  int rank() const;
  int size() const;
  bool distributed() const { return size() > 1; }

  /// Sums every tensor over the ranks, in place (CPU tensors, one collective per call).
  void AllReduceSum(std::vector<torch::Tensor>& tensors);
  /// Every parameter's grad := mean over ranks, in one flattened all-reduce.
  void AllReduceGradients(torch::nn::Module& module);
  /// Every parameter's grad := sum over ranks of `weight` * grad (each rank passes its own
  /// weight), in one flattened all-reduce that also sums `extra` (a few float64 scalars that ride
  /// along, e.g. loss terms). A grad that is undefined on every rank stays undefined.
  void AllReduceGradients(torch::nn::Module& module, double weight, std::vector<double>* extra);
  /// Copies rank `root`'s parameters and buffers to every rank.
  void BroadcastParameters(torch::nn::Module& module, int root = 0);
  /// Copies rank `root`'s tensors into every rank's (same shapes and dtypes on every rank).
  void Broadcast(std::vector<torch::Tensor>& tensors, int root = 0);
  /// Rank `root`'s `mine` on every rank (the other ranks' `mine` is ignored).
  std::string BroadcastBytes(const std::string& mine, int root = 0);
  /// Every rank's `mine`, in rank order.
  std::vector<std::string> AllGatherBytes(const std::string& mine);
  void Barrier();

  /// Raises the job-wide flag `name` in the rendezvous store: every rank sees it at its next
  /// FlagRaised(), and no rank waits for another (unlike a collective). A Local() group keeps it
  /// in the process.
  void RaiseFlag(const std::string& name);
  /// Whether some rank raised `name`: one look-up in the store (a file read or a round trip to
  /// rank 0's TCPStore), so cheap enough between two solves, not inside a step.
  bool FlagRaised(const std::string& name);
  /// Starts a new job's use of `name` in a Local() group: the process-wide DefaultGroup() would
  /// otherwise keep a flag raised by an earlier run in the same process. A distributed group's
  /// flags live in the launch's store, which a new launch replaces: there it does nothing (a rank
  /// deleting a key another rank may already have raised would lose that stop).
  void LowerLocalFlag(const std::string& name);

 private:
  struct Impl;
  explicit Group(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

/// The process-wide group the trainer uses: created on first use from LaunchInfoFromEnv() and
/// TimeoutFromEnv() (Local() when WORLD_SIZE and OMPI_COMM_WORLD_SIZE are unset or 1).
std::shared_ptr<Group> DefaultGroup();

}  // namespace foresight::dist
