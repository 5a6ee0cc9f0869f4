// scanplan watch: the predictive collision watch (seed §7.3) over a stream of measured axis
// positions. Parses, calls pipeline::CollisionWatch and prints; the prediction is the library's.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include <fmt/format.h>

#include <scanplan/collision/scene.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/pipeline/collision_watch.h>
#include "cli/commands/commands.h"
#include "cli/io/axis_stream.h"

namespace scanplan::cli {
namespace {

const char* motionWords(kinematics::MotionKind kind) {
  switch (kind) {
    case kinematics::MotionKind::kJoint:
      return "joint move";
    case kinematics::MotionKind::kCartesian:
      return "Cartesian move";
    case kinematics::MotionKind::kStill:
      break;
  }
  return "standing still";
}

pipeline::WatchOptions watchOptions(const WatchCommandOptions& o) {
  const auto positive = [](double v, const char* option, const char* unit) {
    if (!(v > 0.0) || !std::isfinite(v) || v > 1e6) {
      throw InputError(fmt::format("{}: {} {}: expected a positive number", option, v, unit));
    }
  };
  positive(o.horizon_s, "--horizon-s", "s");
  positive(o.step_s, "--step-s", "s");
  positive(o.warn_distance_mm, "--warn-distance-mm", "mm");
  positive(o.stop_time_s, "--stop-time-s", "s");
  if (!(o.repeat_s >= 0.0) || !std::isfinite(o.repeat_s)) {
    throw InputError(fmt::format("--repeat-s: {} s: expected 0 or more", o.repeat_s));
  }
  if (o.window < 3 || o.window > 10000) {
    throw InputError(fmt::format("--window: {} samples: expected 3 … 10000", o.window));
  }
  if (o.horizon_s / o.step_s > 10000) {
    throw InputError(
        fmt::format("--horizon-s {} / --step-s {}: {} predicted poses a sample: "
                    "expected at most 10000",
                    o.horizon_s, o.step_s, o.horizon_s / o.step_s));
  }
  pipeline::WatchOptions w;
  w.window = o.window;
  w.horizon = o.horizon_s;
  w.step = o.step_s;
  w.warn_distance = o.warn_distance_mm * kMmToM;
  if (o.stop_distance_mm) {
    if (!(*o.stop_distance_mm >= 0.0) || *o.stop_distance_mm > 1e6) {
      throw InputError(
          fmt::format("--stop-distance-mm: {} mm: expected 0 or more", *o.stop_distance_mm));
    }
    w.stop_distance = *o.stop_distance_mm * kMmToM;
  }
  w.stop_time = o.stop_time_s;
  return w;
}

std::string pairName(const collision::Scene& scene, int pair) {
  const collision::PairInfo& p = scene.pairs()[static_cast<std::size_t>(pair)];
  return scene.bodies()[static_cast<std::size_t>(p.a)].name + " – " +
         scene.bodies()[static_cast<std::size_t>(p.b)].name;
}

std::string warningLine(const collision::Scene& scene,
                        const pipeline::WatchStep& step,
                        const pipeline::WatchWarning& w) {
  const std::string now = w.far_now ? fmt::format("beyond {:.1f} mm now", toMm(w.distance_now))
                                    : fmt::format("{:.1f} mm now", toMm(w.distance_now));
  const std::string ahead =
      w.time_to_contact
          ? fmt::format("contact in {:.3f} s", *w.time_to_contact)
          : fmt::format("closest {:.1f} mm in {:.3f} s", toMm(w.closest), w.time_to_closest);
  return fmt::format("t={:.3f} s  {}  {}: {}, {} ({})\n", step.t, w.stop ? "STOP" : "WARN",
                     pairName(scene, w.pair), now, ahead, motionWords(step.fit.kind));
}

// The time per sample as a histogram of 10 µs bins up to 100 ms (the rest in the last): a live
// stream runs for days, so nothing is kept per sample.
class LatencyHistogram {
 public:
  void add(double seconds) {
    const auto bin = static_cast<std::size_t>(std::max(0.0, seconds) / kBin);
    ++bins_[std::min(bin, bins_.size() - 1)];
    ++count_;
    sum_ += seconds;
    max_ = std::max(max_, seconds);
  }
  double mean() const { return count_ ? sum_ / static_cast<double>(count_) : 0.0; }
  double max() const { return max_; }
  /// The upper edge of the bin holding the q-quantile, s (at most the max).
  double quantile(double q) const {
    const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(count_)));
    std::size_t seen = 0;
    for (std::size_t b = 0; b < bins_.size(); ++b) {
      seen += bins_[b];
      if (seen >= std::max<std::size_t>(rank, 1))
        return std::min(max_, static_cast<double>(b + 1) * kBin);
    }
    return max_;
  }

 private:
  static constexpr double kBin = 1e-5;
  std::vector<std::size_t> bins_ = std::vector<std::size_t>(10000, 0);
  std::size_t count_ = 0;
  double sum_ = 0.0;
  double max_ = 0.0;
};

struct Tally {
  std::size_t samples = 0;
  std::size_t kinds[3] = {0, 0, 0};
  std::size_t warned_samples = 0;
  std::map<int, std::size_t> warnings_by_pair;
  LatencyHistogram latency;
  double first_t = 0.0, last_t = 0.0;
};

void printSummary(const collision::Scene& scene, Tally& tally) {
  if (tally.samples == 0) {
    std::fputs("watch: no samples\n", stdout);
    return;
  }
  const auto share = [&](kinematics::MotionKind k) {
    return 100.0 * static_cast<double>(tally.kinds[static_cast<int>(k)]) /
           static_cast<double>(tally.samples);
  };
  std::string pairs;
  for (const auto& [pair, n] : tally.warnings_by_pair) {
    pairs += fmt::format("{}{} ({} samples)", pairs.empty() ? "" : ", ", pairName(scene, pair), n);
  }
  std::fputs(fmt::format(
                 "watch: {} samples over {:.3f} s: joint moves {:.0f} %, Cartesian {:.0f} %, "
                 "still {:.0f} %\n",
                 tally.samples, tally.last_t - tally.first_t, share(kinematics::MotionKind::kJoint),
                 share(kinematics::MotionKind::kCartesian), share(kinematics::MotionKind::kStill))
                 .c_str(),
             stdout);
  std::fputs(fmt::format("watch: warnings in {} samples{}\n", tally.warned_samples,
                         pairs.empty() ? "" : ": " + pairs)
                 .c_str(),
             stdout);
  std::fputs(fmt::format("watch: time per sample mean {:.3f} ms, p99 {:.3f} ms, max {:.3f} ms "
                         "(a 250 Hz stream leaves 4 ms)\n",
                         1e3 * tally.latency.mean(), 1e3 * tally.latency.quantile(0.99),
                         1e3 * tally.latency.max())
                 .c_str(),
             stdout);
}

}  // namespace

ExitCode runWatch(const WatchCommandOptions& options) {
  const config::JobSpec job = config::loadJob(options.job_file, options.overrides);
  const pipeline::WatchOptions watch_options = watchOptions(options);
  const kinematics::CellModel cell = config::buildCell(job);
  const collision::Scene scene(cell, config::clearanceConfig(job));
  pipeline::CollisionWatch watch(scene, cell.scanner.X_FS, watch_options);

  std::ifstream file;
  if (!options.log_file.empty()) {
    file.open(options.log_file, std::ios::binary);
    if (!file) throw InputError(options.log_file.string() + ": cannot be read");
  }
  const std::string source = options.log_file.empty() ? "<stdin>" : options.log_file.string();
  AxisStreamReader reader(options.log_file.empty() ? std::cin : file, source);
  std::fputs(
      fmt::format("watch: {} pairs of {}, horizon {:g} s, warn within {:g} mm{}; reading {}\n",
                  scene.pairs().size(), options.job_file.string(), options.horizon_s,
                  options.warn_distance_mm,
                  options.stop_distance_mm
                      ? fmt::format(", stop within {:g} mm in {:g} s", *options.stop_distance_mm,
                                    options.stop_time_s)
                      : std::string(),
                  source)
          .c_str(),
      stderr);

  Tally tally;
  std::map<int, double> printed;  // pair → time of its last printed warning
  while (const auto sample = reader.next()) {
    const auto start = std::chrono::steady_clock::now();
    const pipeline::WatchStep step = watch.push(*sample);
    tally.latency.add(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    if (tally.samples++ == 0) tally.first_t = step.t;
    tally.last_t = step.t;
    ++tally.kinds[static_cast<int>(step.fit.kind)];
    if (!step.warnings.empty()) ++tally.warned_samples;
    std::map<int, double> still_warning;
    for (const pipeline::WatchWarning& w : step.warnings) {
      ++tally.warnings_by_pair[w.pair];
      const auto it = printed.find(w.pair);
      const bool repeat = it == printed.end() || step.t - it->second >= options.repeat_s || w.stop;
      still_warning[w.pair] = repeat ? step.t : it->second;
      if (repeat) std::fputs(warningLine(scene, step, w).c_str(), stdout);
    }
    for (const auto& [pair, t] : printed) {
      if (!still_warning.count(pair)) {
        std::fputs(fmt::format("t={:.3f} s  clear {}\n", step.t, pairName(scene, pair)).c_str(),
                   stdout);
      }
    }
    printed = std::move(still_warning);
    std::fflush(stdout);
    if (step.stop) {
      std::fputs(fmt::format("watch: stop needed at t={:.3f} s (line {} of {})\n", step.t,
                             reader.line(), source)
                     .c_str(),
                 stdout);
      printSummary(scene, tally);
      return ExitCode::kStop;
    }
  }
  printSummary(scene, tally);
  return ExitCode::kOk;
}

}  // namespace scanplan::cli
