#include "training/distributed.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <thread>

#include "tests/test_util.h"
#include "tests/training/distributed_task.h"
#include "training/trainer.h"

extern char** environ;

namespace foresight {
namespace {
namespace fs = std::filesystem;
using testing::TinyRegressionTask;
using testing::TinyTrainConfig;

constexpr const char* kLaunchVariables[] = {"RANK",
                                            "WORLD_SIZE",
                                            "MASTER_ADDR",
                                            "MASTER_PORT",
                                            "LOCAL_RANK",
                                            "OMPI_COMM_WORLD_RANK",
                                            "OMPI_COMM_WORLD_SIZE",
                                            "FORESIGHT_STORE_FILE",
                                            "FORESIGHT_DIST_TIMEOUT_S"};

using EnvValues = std::map<std::string, std::optional<std::string>>;

/// Sets (or with nullopt unsets) environment variables while alive; restores them afterwards.
class ScopedEnv {
 public:
  explicit ScopedEnv(const EnvValues& values) {
    for (const char* name : kLaunchVariables) Save(name);
    for (const auto& [name, value] : values) {
      Save(name);
      if (value)
        ::setenv(name.c_str(), value->c_str(), 1);
      else
        ::unsetenv(name.c_str());
    }
    for (const char* name : kLaunchVariables)
      if (!values.count(name)) ::unsetenv(name);
  }
  ~ScopedEnv() {
    for (const auto& [name, value] : saved_) {
      if (value)
        ::setenv(name.c_str(), value->c_str(), 1);
      else
        ::unsetenv(name.c_str());
    }
  }

 private:
  void Save(const std::string& name) {
    if (saved_.count(name)) return;
    const char* v = std::getenv(name.c_str());
    saved_[name] = v ? std::optional<std::string>(v) : std::nullopt;
  }
  std::map<std::string, std::optional<std::string>> saved_;
};

TEST(DistributedLaunch, NoLaunchVariablesMeanOneProcess) {
  ScopedEnv env(EnvValues{});
  const dist::LaunchInfo info = dist::LaunchInfoFromEnv();
  EXPECT_EQ(info.rank, 0);
  EXPECT_EQ(info.world_size, 1);
  EXPECT_FALSE(info.distributed());
  EXPECT_EQ(dist::TimeoutFromEnv(), std::chrono::milliseconds(60000));
}

TEST(DistributedLaunch, TorchrunAndMpirunVariables) {
  {
    ScopedEnv env(EnvValues{{"RANK", "1"},
                            {"WORLD_SIZE", "2"},
                            {"MASTER_ADDR", "10.0.0.1"},
                            {"MASTER_PORT", "29500"},
                            {"FORESIGHT_DIST_TIMEOUT_S", "2.5"}});
    const dist::LaunchInfo info = dist::LaunchInfoFromEnv();
    EXPECT_EQ(info.rank, 1);
    EXPECT_EQ(info.world_size, 2);
    EXPECT_EQ(info.master_addr, "10.0.0.1");
    EXPECT_EQ(info.master_port, 29500);
    EXPECT_TRUE(info.store_file.empty());
    EXPECT_EQ(dist::TimeoutFromEnv(), std::chrono::milliseconds(2500));
  }
  {
    ScopedEnv env(EnvValues{{"OMPI_COMM_WORLD_RANK", "2"},
                            {"OMPI_COMM_WORLD_SIZE", "3"},
                            {"FORESIGHT_STORE_FILE", "/shared/store"}});
    const dist::LaunchInfo info = dist::LaunchInfoFromEnv();
    EXPECT_EQ(info.rank, 2);
    EXPECT_EQ(info.world_size, 3);
    EXPECT_EQ(info.store_file, "/shared/store");
  }
}

TEST(DistributedLaunch, BadVariablesAreErrorsNamingThem) {
  const auto expect_error = [](const EnvValues& values, const std::vector<std::string>& parts) {
    ScopedEnv env(values);
    testing::ExpectErrorContains([] { dist::LaunchInfoFromEnv(); }, parts);
  };
  expect_error({{"RANK", "one"}, {"WORLD_SIZE", "2"}, {"FORESIGHT_STORE_FILE", "/tmp/s"}},
               {"RANK", "'one'", "not an integer"});
  expect_error({{"WORLD_SIZE", "2"}, {"FORESIGHT_STORE_FILE", "/tmp/s"}}, {"RANK", "not set"});
  expect_error({{"RANK", "2"}, {"WORLD_SIZE", "2"}, {"FORESIGHT_STORE_FILE", "/tmp/s"}},
               {"RANK=2", "WORLD_SIZE=2"});
  expect_error({{"RANK", "0"}, {"WORLD_SIZE", "0"}}, {"WORLD_SIZE", "'0'"});
  expect_error({{"RANK", "0"}, {"WORLD_SIZE", "2"}, {"MASTER_ADDR", "localhost"}},
               {"MASTER_PORT", "not set", "FORESIGHT_STORE_FILE"});
  expect_error({{"RANK", "0"}, {"WORLD_SIZE", "2"}, {"MASTER_PORT", "29500"}},
               {"MASTER_ADDR", "not set"});
  expect_error(
      {{"RANK", "0"}, {"WORLD_SIZE", "2"}, {"MASTER_ADDR", "localhost"}, {"MASTER_PORT", "70000"}},
      {"MASTER_PORT", "'70000'"});
  expect_error({{"OMPI_COMM_WORLD_RANK", "5"}, {"OMPI_COMM_WORLD_SIZE", "4"}},
               {"OMPI_COMM_WORLD_RANK=5", "OMPI_COMM_WORLD_SIZE=4"});
  ScopedEnv env(EnvValues{{"FORESIGHT_DIST_TIMEOUT_S", "soon"}});
  testing::ExpectErrorContains([] { dist::TimeoutFromEnv(); },
                               {"FORESIGHT_DIST_TIMEOUT_S", "'soon'"});
}

TEST(DistributedGroup, LocalCollectivesAreNoOps) {
  const auto group = dist::Group::Local();
  EXPECT_EQ(group->rank(), 0);
  EXPECT_EQ(group->size(), 1);
  std::vector<torch::Tensor> t{torch::ones({3})};
  group->AllReduceSum(t);
  EXPECT_TRUE(torch::equal(t[0], torch::ones({3})));
  EXPECT_EQ(group->AllGatherBytes("abc"), std::vector<std::string>{"abc"});
  EXPECT_EQ(group->BroadcastBytes("abc"), "abc");
  TinyRegressionTask task(8, 1);
  task.BatchLoss(torch::arange(8)).backward();
  std::vector<torch::Tensor> grads;
  for (const auto& p : task.module().parameters()) grads.push_back(p.grad().clone());
  group->AllReduceGradients(task.module());
  group->BroadcastParameters(task.module());
  group->Barrier();
  EXPECT_FALSE(group->FlagRaised("stop"));
  group->RaiseFlag("stop");
  EXPECT_TRUE(group->FlagRaised("stop"));
  EXPECT_FALSE(group->FlagRaised("other"));
  group->LowerLocalFlag("stop");  // a later run in the same process starts without it
  EXPECT_FALSE(group->FlagRaised("stop"));
  const auto params = task.module().parameters();
  for (std::size_t i = 0; i < params.size(); ++i)
    EXPECT_TRUE(torch::equal(params[i].grad(), grads[i]));
}

// ---- several processes: the worker binary (distributed_worker.cc) once per rank -------------

/// Runs one worker per entry of `args` (rank = index) with the launch variables `env` (plus RANK
/// and WORLD_SIZE); returns the exit statuses (-1: killed after the deadline).
std::vector<int> RunRanks(const std::vector<std::vector<std::string>>& args,
                          const std::map<std::string, std::string>& env) {
  const int world = static_cast<int>(args.size());
  std::vector<pid_t> pids;
  for (int rank = 0; rank < world; ++rank) {
    std::vector<std::string> vars;
    for (char** e = environ; *e; ++e) {
      const std::string entry = *e;
      const std::string name = entry.substr(0, entry.find('='));
      bool launch = false;
      for (const char* v : kLaunchVariables) launch = launch || name == v;
      if (!launch) vars.push_back(entry);
    }
    for (const auto& [name, value] : env) vars.push_back(name + "=" + value);
    vars.push_back("RANK=" + std::to_string(rank));
    vars.push_back("WORLD_SIZE=" + std::to_string(world));
    std::vector<std::string> argv_s{FORESIGHT_DISTRIBUTED_WORKER};
    argv_s.insert(argv_s.end(), args[rank].begin(), args[rank].end());
    std::vector<char*> argv_p, env_p;
    for (auto& s : argv_s) argv_p.push_back(s.data());
    for (auto& s : vars) env_p.push_back(s.data());
    argv_p.push_back(nullptr);
    env_p.push_back(nullptr);
    pid_t pid = 0;
    EXPECT_EQ(::posix_spawn(&pid, argv_p[0], nullptr, nullptr, argv_p.data(), env_p.data()), 0);
    pids.push_back(pid);
  }
  std::vector<int> status(pids.size(), -1);
  std::vector<bool> done(pids.size(), false);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  for (std::size_t left = pids.size(); left > 0;) {
    for (std::size_t i = 0; i < pids.size(); ++i) {
      int s = 0;
      if (done[i] || ::waitpid(pids[i], &s, WNOHANG) != pids[i]) continue;
      done[i] = true;
      --left;
      status[i] = WIFEXITED(s) ? WEXITSTATUS(s) : 128 + WTERMSIG(s);
    }
    if (left > 0 && std::chrono::steady_clock::now() > deadline) {
      for (std::size_t i = 0; i < pids.size(); ++i)
        if (!done[i]) {
          ::kill(pids[i], SIGKILL);
          ::waitpid(pids[i], nullptr, 0);
          ADD_FAILURE() << "rank " << i << " did not finish within 60 s (killed)";
          done[i] = true;
          --left;
        }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return status;
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<torch::Tensor> LoadParams(const std::string& path) {
  std::vector<torch::Tensor> params;
  torch::load(params, path);
  return params;
}

/// The parameters of one process training TinyRegressionTask(n, rank 0's seed) on the same
/// global batches (the reference of every data-parallel run).
std::vector<torch::Tensor> OneProcess(std::int64_t n, int batch, int epochs) {
  testing::TempDir dir;
  TinyRegressionTask task(n, 1000);
  const auto group = dist::Group::Local();
  Train(&task, TinyTrainConfig(batch, epochs), RunPaths{dir.File("run")}, 7, false, {},
        group.get());
  std::vector<torch::Tensor> params;
  for (const auto& p : task.module().parameters()) params.push_back(p.detach().clone());
  return params;
}

double MaxAbsDiff(const std::vector<torch::Tensor>& a, const std::vector<torch::Tensor>& b) {
  EXPECT_EQ(a.size(), b.size());
  double worst = 0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i)
    worst = std::max(worst, (a[i] - b[i]).abs().max().item<double>());
  return worst;
}

/// Trains with `world` ranks and checks: every rank ends with identical parameters, equal (to
/// float rounding) to one process; only rank 0 writes its run directory.
void ExpectDataParallelMatchesOneProcess(int world, std::int64_t n, int batch, int epochs,
                                         std::map<std::string, std::string> env,
                                         const testing::TempDir& dir) {
  std::vector<std::vector<std::string>> args;
  for (int r = 0; r < world; ++r)
    args.push_back({"train", dir.path(), dir.File("run" + std::to_string(r)), std::to_string(n),
                    std::to_string(batch), std::to_string(epochs), "0"});
  env["FORESIGHT_DIST_TIMEOUT_S"] = "20";
  const auto status = RunRanks(args, env);
  for (int r = 0; r < world; ++r)
    ASSERT_EQ(status[r], 0) << "rank " << r << ": "
                            << ReadText(dir.File("error") + std::to_string(r) + ".txt");
  const auto reference = OneProcess(n, batch, epochs);
  const auto rank0 = LoadParams(dir.File("rank0.pt"));
  const double diff = MaxAbsDiff(rank0, reference);
  std::cout << world << " ranks: max |parameter - one process's| = " << diff << "\n";
  EXPECT_LT(diff, 1e-6);
  for (int r = 1; r < world; ++r) {
    EXPECT_EQ(MaxAbsDiff(LoadParams(dir.File("rank" + std::to_string(r) + ".pt")), rank0), 0.0)
        << "rank " << r << " differs from rank 0";
    EXPECT_FALSE(fs::exists(dir.File("run" + std::to_string(r)))) << "rank " << r << " wrote";
  }
  EXPECT_EQ(ReadText(dir.File("rank0.txt")).rfind("max_epochs " + std::to_string(epochs) + " ", 0),
            0u);
  for (int r = 1; r < world; ++r)
    EXPECT_EQ(ReadText(dir.File("rank" + std::to_string(r) + ".txt")),
              ReadText(dir.File("rank0.txt")));
  EXPECT_TRUE(fs::exists(dir.File("run0/checkpoints/last.pt")));
  EXPECT_TRUE(fs::exists(dir.File("run0/metrics.csv")));
}

TEST(DistributedGroup, CollectivesAcrossTwoProcesses) {
  testing::TempDir dir;
  const auto status =
      RunRanks({{"collectives", dir.path()}, {"collectives", dir.path()}},
               {{"FORESIGHT_STORE_FILE", dir.File("store")}, {"FORESIGHT_DIST_TIMEOUT_S", "20"}});
  ASSERT_EQ(status, (std::vector<int>{0, 0}))
      << ReadText(dir.File("error0.txt")) << ReadText(dir.File("error1.txt"));
  const std::string expected =
      "rank;rankx;\n" + std::string("from\0zero", 9) + "\n9.000000 6\nlowered raised";
  EXPECT_EQ(ReadText(dir.File("rank0.txt")), expected);
  EXPECT_EQ(ReadText(dir.File("rank1.txt")), expected);
}

TEST(DistributedTraining, TwoRanksMatchOneProcessOnTheGlobalBatch) {
  testing::TempDir dir;
  ExpectDataParallelMatchesOneProcess(2, 48, 16, 3, {{"FORESIGHT_STORE_FILE", dir.File("store")}},
                                      dir);
}

// 46 samples in batches of 15: slices of 7 and 8, and a last batch of one sample that leaves
// rank 0 without any (its gradient enters the sum with weight 0).
TEST(DistributedTraining, UnevenSplitAndAnEmptySliceMatchOneProcess) {
  testing::TempDir dir;
  ExpectDataParallelMatchesOneProcess(2, 46, 15, 3, {{"FORESIGHT_STORE_FILE", dir.File("store")}},
                                      dir);
}

int FreePort() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = 0;
  socklen_t len = sizeof(addr);
  EXPECT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)), 0);
  EXPECT_EQ(::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len), 0);
  ::close(fd);
  return ntohs(addr.sin_port);
}

TEST(DistributedTraining, ThreeRanksThroughATcpStoreMatchOneProcess) {
  testing::TempDir dir;
  ExpectDataParallelMatchesOneProcess(
      3, 46, 15, 2, {{"MASTER_ADDR", "127.0.0.1"}, {"MASTER_PORT", std::to_string(FreePort())}},
      dir);
}

TEST(DistributedTraining, APeerThatExitsIsAnErrorAndTheLastCheckpointResumes) {
  testing::TempDir dir;
  const auto train = [&](bool resume, const std::string& exit_at) {
    std::vector<std::string> rank0{"train", dir.path(), dir.File("run0"),  "48",
                                   "16",    "4",        resume ? "1" : "0"};
    std::vector<std::string> rank1 = rank0;
    rank1[2] = dir.File("run1");  // no shared run directory: rank 0 sends the checkpoint
    if (!exit_at.empty()) rank1.push_back(exit_at);
    const std::string store = dir.File(resume ? "store_resume" : "store");
    return RunRanks({rank0, rank1},
                    {{"FORESIGHT_STORE_FILE", store}, {"FORESIGHT_DIST_TIMEOUT_S", "3"}});
  };
  // 3 batches per epoch, one BatchLoss per batch on each rank: rank 1 dies in epoch 3.
  const auto crashed = train(false, "7");
  EXPECT_EQ(crashed[1], 3);
  EXPECT_EQ(crashed[0], 2);  // a foresight::Error, not a hang or an abort
  const std::string error = ReadText(dir.File("error0.txt"));
  EXPECT_NE(error.find("rank 0 of 2"), std::string::npos) << error;
  EXPECT_NE(error.find("all-reduce of gradients"), std::string::npos) << error;
  EXPECT_NE(error.find("peer rank 1"), std::string::npos) << error;
  ASSERT_TRUE(fs::exists(dir.File("run0/checkpoints/last.pt")));

  const auto resumed = train(true, "");
  ASSERT_EQ(resumed, (std::vector<int>{0, 0}))
      << ReadText(dir.File("error0.txt")) << ReadText(dir.File("error1.txt"));
  EXPECT_EQ(ReadText(dir.File("rank0.txt")).rfind("max_epochs 4 ", 0), 0u);
  const auto rank0 = LoadParams(dir.File("rank0.pt"));
  EXPECT_EQ(MaxAbsDiff(LoadParams(dir.File("rank1.pt")), rank0), 0.0);
  EXPECT_LT(MaxAbsDiff(rank0, OneProcess(48, 16, 4)), 1e-6);
  // metrics.csv: one row per epoch, none lost or duplicated by the crash.
  std::ifstream metrics(dir.File("run0/metrics.csv"));
  int rows = 0;
  for (std::string line; std::getline(metrics, line);) rows += !line.empty();
  EXPECT_EQ(rows, 5);
}

}  // namespace
}  // namespace foresight
