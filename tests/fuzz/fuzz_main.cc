// The driver of a fuzz target when it is not linked with libFuzzer (GCC builds, the regression
// ctests): runs LLVMFuzzerTestOneInput once on every file named on the command line (directories:
// every file inside, sorted), and with `--mutate N [--seed S]` also on N random mutations of
// those inputs (byte flips, inserts, deletions, truncations, splices): a small fuzzer for targets
// that libFuzzer does not build (the LibTorch checkpoint reader), see scripts/fuzz.sh.

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

std::vector<std::uint8_t> ReadBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void Mutate(std::vector<std::uint8_t>* bytes, const std::vector<std::vector<std::uint8_t>>& pool,
            std::mt19937_64* rng) {
  auto& b = *bytes;
  const int edits = 1 + static_cast<int>((*rng)() % 8);
  for (int e = 0; e < edits; ++e) {
    const std::size_t n = b.size();
    switch ((*rng)() % 6) {
      case 0:  // flip a bit
        if (n) b[(*rng)() % n] ^= static_cast<std::uint8_t>(1u << ((*rng)() % 8));
        break;
      case 1:  // overwrite a byte with an interesting one
        if (n) {
          static constexpr std::uint8_t kBytes[] = {0,   0xff, 0x7f, 0x80, '-', '9',
                                                    '.', 'e',  ',',  '\n', ':', ' '};
          b[(*rng)() % n] = kBytes[(*rng)() % sizeof(kBytes)];
        }
        break;
      case 2:  // insert a random byte
        b.insert(b.begin() + static_cast<std::ptrdiff_t>(n ? (*rng)() % (n + 1) : 0),
                 static_cast<std::uint8_t>((*rng)()));
        break;
      case 3:  // delete a range
        if (n) {
          const std::size_t at = (*rng)() % n,
                            len = 1 + (*rng)() % std::min<std::size_t>(n - at, 64);
          b.erase(b.begin() + static_cast<std::ptrdiff_t>(at),
                  b.begin() + static_cast<std::ptrdiff_t>(at + len));
        }
        break;
      case 4:  // truncate
        if (n) b.resize((*rng)() % n);
        break;
      default:  // splice a piece of another input
        if (!pool.empty()) {
          const auto& other = pool[(*rng)() % pool.size()];
          if (!other.empty()) {
            const std::size_t from = (*rng)() % other.size(),
                              len = 1 + (*rng)() % std::min<std::size_t>(other.size() - from, 256);
            const std::size_t at = n ? (*rng)() % (n + 1) : 0;
            b.insert(b.begin() + static_cast<std::ptrdiff_t>(at),
                     other.begin() + static_cast<std::ptrdiff_t>(from),
                     other.begin() + static_cast<std::ptrdiff_t>(from + len));
          }
        }
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  long mutations = 0;
  std::uint64_t seed = 1;
  double max_seconds = 0;
  std::vector<std::filesystem::path> files;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--mutate" && i + 1 < argc) {
      mutations = std::stol(argv[++i]);
    } else if (arg == "--seed" && i + 1 < argc) {
      seed = std::stoull(argv[++i]);
    } else if (arg == "--max-seconds" && i + 1 < argc) {
      max_seconds = std::stod(argv[++i]);
    } else if (std::filesystem::is_directory(arg)) {
      std::vector<std::filesystem::path> inside;
      for (const auto& entry : std::filesystem::directory_iterator(arg))
        if (entry.is_regular_file()) inside.push_back(entry.path());
      std::sort(inside.begin(), inside.end());
      files.insert(files.end(), inside.begin(), inside.end());
    } else if (std::filesystem::is_regular_file(arg)) {
      files.emplace_back(arg);
    } else {
      std::fprintf(stderr, "%s: no such input file or directory: %s\n", argv[0], arg.c_str());
      return 2;
    }
  }
  std::vector<std::vector<std::uint8_t>> pool;
  for (const auto& f : files) {
    pool.push_back(ReadBytes(f));
    LLVMFuzzerTestOneInput(pool.back().data(), pool.back().size());
  }
  std::printf("%s: %zu inputs ran\n", argv[0], files.size());
  if (mutations > 0 && !pool.empty()) {
    std::mt19937_64 rng(seed);
    const auto start = std::chrono::steady_clock::now();
    long done = 0;
    for (; done < mutations; ++done) {
      if (max_seconds > 0 &&
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >
              max_seconds)
        break;
      std::vector<std::uint8_t> input = pool[rng() % pool.size()];
      Mutate(&input, pool, &rng);
      // Kept where a crash leaves it, so the input that broke the target can be found.
      {
        std::ofstream last("fuzz_last_input", std::ios::binary | std::ios::trunc);
        last.write(reinterpret_cast<const char*>(input.data()),
                   static_cast<std::streamsize>(input.size()));
      }
      LLVMFuzzerTestOneInput(input.data(), input.size());
    }
    std::printf("%s: %ld mutations ran (seed %llu)\n", argv[0], done,
                static_cast<unsigned long long>(seed));
  }
  return 0;
}
