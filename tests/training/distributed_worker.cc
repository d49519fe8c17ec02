/// One rank of the distributed tests (tests/training/distributed_test.cc starts several). The rank,
/// world size and rendezvous come from the environment (RANK, WORLD_SIZE, FORESIGHT_STORE_FILE or
/// MASTER_ADDR/MASTER_PORT, FORESIGHT_DIST_TIMEOUT_S).
///
///   distributed_worker train OUT_DIR RUN_DIR N BATCH EPOCHS RESUME [EXIT_AT_BATCH]
///     trains TinyRegressionTask (initial weights seeded by the rank, so rank 0's broadcast
///     matters); writes OUT_DIR/rank<r>.pt (final parameters) and OUT_DIR/rank<r>.txt (summary).
///     With EXIT_AT_BATCH, the process exits (status 3) inside that BatchLoss call (1-based).
///   distributed_worker collectives OUT_DIR
///     checks AllGatherBytes, BroadcastBytes, AllReduceSum, Barrier, RaiseFlag/FlagRaised; writes
///     OUT_DIR/rank<r>.txt.
/// A foresight::Error goes to OUT_DIR/error<r>.txt and the status is 2.

#include <unistd.h>

#include <fstream>
#include <iostream>
#include <string>

#include "core/error.h"
#include "tests/training/distributed_task.h"
#include "training/distributed.h"

namespace {

using foresight::testing::TinyRegressionTask;

class ExitingTask : public TinyRegressionTask {
 public:
  ExitingTask(std::int64_t n, std::uint64_t init_seed, int exit_at)
      : TinyRegressionTask(n, init_seed), exit_at_(exit_at) {}
  torch::Tensor BatchLoss(const torch::Tensor& indices) override {
    if (++calls_ == exit_at_) ::_exit(3);  // a crash: no destructors, sockets closed by the kernel
    return TinyRegressionTask::BatchLoss(indices);
  }

 private:
  int exit_at_;
  int calls_ = 0;
};

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

int Train(const std::string& out, char** argv, int argc) {
  const std::string run_dir = argv[3];
  const std::int64_t n = std::stoll(argv[4]);
  const int batch = std::stoi(argv[5]);
  const int epochs = std::stoi(argv[6]);
  const bool resume = std::string(argv[7]) == "1";
  const int exit_at = argc > 8 ? std::stoi(argv[8]) : 0;
  auto group = foresight::dist::DefaultGroup();
  const int rank = group->rank();
  ExitingTask task(n, 1000 + static_cast<std::uint64_t>(rank), exit_at);
  const auto summary = foresight::Train(&task, foresight::testing::TinyTrainConfig(batch, epochs),
                                        foresight::RunPaths{run_dir}, 7, resume);
  std::vector<torch::Tensor> params;
  for (const auto& p : task.module().parameters()) params.push_back(p.detach().clone());
  torch::save(params, out + "/rank" + std::to_string(rank) + ".pt");
  WriteText(out + "/rank" + std::to_string(rank) + ".txt",
            std::string(foresight::ToString(summary.reason)) + " " +
                std::to_string(summary.epochs_completed) + " " +
                std::to_string(summary.best_epoch) + "\n");
  return 0;
}

int Collectives(const std::string& out) {
  auto group = foresight::dist::DefaultGroup();
  const int rank = group->rank();
  std::string report;
  const auto all = group->AllGatherBytes("rank" + std::string(static_cast<std::size_t>(rank), 'x'));
  for (const auto& s : all) report += s + ";";
  report += "\n" + group->BroadcastBytes(rank == 0 ? std::string("from\0zero", 9) : "ignored");
  std::vector<torch::Tensor> t{torch::full({3}, rank + 1.0),
                               torch::full({2}, rank + 1, torch::kInt64)};
  group->AllReduceSum(t);
  report += "\n" + std::to_string(t[0].sum().item<double>()) + " " +
            std::to_string(t[1].sum().item<std::int64_t>());
  group->Barrier();
  // A flag raised by rank 1 is seen by rank 0 after a barrier, without a collective of its own.
  report += std::string("\n") + (group->FlagRaised("f") ? "raised" : "lowered");
  group->Barrier();  // both have read before rank 1 raises it
  if (rank == 1) group->RaiseFlag("f");
  group->Barrier();
  report += std::string(" ") + (group->FlagRaised("f") ? "raised" : "lowered") +
            (group->FlagRaised("g") ? " g" : "");
  WriteText(out + "/rank" + std::to_string(rank) + ".txt", report);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: distributed_worker train|collectives OUT_DIR ...\n";
    return 1;
  }
  const std::string mode = argv[1], out = argv[2];
  try {
    if (mode == "train" && argc >= 8) return Train(out, argv, argc);
    if (mode == "collectives") return Collectives(out);
    std::cerr << "distributed_worker: bad arguments\n";
    return 1;
  } catch (const foresight::Error& e) {
    const char* rank = std::getenv("RANK");
    WriteText(out + "/error" + std::string(rank ? rank : "0") + ".txt", e.what());
    std::cerr << "distributed_worker: " << e.what() << "\n";
    return 2;
  }
}
