#include "training/progress.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>

namespace foresight {

Progress::Progress(ProgressStyle style, int total, std::string unit)
    : total_(total), unit_(std::move(unit)), start_(std::chrono::steady_clock::now()) {
  const bool tty = isatty(fileno(stderr)) != 0;
  bar_ = style == ProgressStyle::kBar || (style == ProgressStyle::kAuto && tty);
  lines_ = style == ProgressStyle::kLines || (style == ProgressStyle::kAuto && !tty);
  last_draw_ = start_ - std::chrono::seconds(1);
}

namespace {
std::string Clock(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "--:--";
  const long s = std::lround(seconds);
  char buf[32];
  if (s >= 3600)
    std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", s / 3600, (s / 60) % 60, s % 60);
  else
    std::snprintf(buf, sizeof buf, "%02ld:%02ld", s / 60, s % 60);
  return buf;
}
}  // namespace

void Progress::Update(int step, double fraction, double items, double loss) {
  if (!bar_) return;
  if (first_step_ < 0) first_step_ = step;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ < std::chrono::milliseconds(100) && fraction < 1.0) return;
  last_draw_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double rate = items / std::max(elapsed, 1e-9);
  const double steps_done = (step - first_step_) + fraction;
  const double eta = steps_done > 0 ? elapsed / steps_done * (total_ - step - fraction) : NAN;
  const int width = 24;
  const int filled = static_cast<int>(std::round(width * (step + fraction) / std::max(total_, 1)));
  std::string bar(static_cast<std::size_t>(std::min(filled, width)), '=');
  bar.resize(static_cast<std::size_t>(width), ' ');
  std::fprintf(stderr, "\repoch %d/%d [%s] %.0f %s/s ETA %s loss %.4f   ", step + 1, total_,
               bar.c_str(), rate, unit_.c_str(), Clock(eta).c_str(), loss);
  std::fflush(stderr);
}

void Progress::EndStep(int step, const std::string& summary) {
  if (bar_) {
    std::fprintf(stderr, "\r\033[K");
  }
  if (bar_ || lines_) {
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    std::fprintf(stderr, "epoch %d/%d %s [%s]\n", step + 1, total_, summary.c_str(),
                 Clock(elapsed).c_str());
    std::fflush(stderr);
  }
}

void Progress::Finish() {
  if (bar_) std::fprintf(stderr, "\r\033[K");
}

}  // namespace foresight
