#include <scanplan/scanner/pass_selection.h>

#include <algorithm>
#include <cmath>
#include <queue>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <scanplan/kinematics/pose.h>
#include <scanplan/kinematics/scan_path.h>

namespace scanplan::scanner {

namespace {

std::size_t newlyCovered(const ScanPass& pass,
                         const std::vector<std::uint8_t>& counts,
                         const std::vector<std::uint8_t>& covered) {
  std::size_t n = 0;
  for (std::uint32_t i : pass.covers)
    if (counts[i] && !covered[i]) ++n;
  return n;
}

// A counting sample only one chosen pass covers, by its first and last covering stretches.
struct Need {
  std::uint32_t first = 0, last = 0;
};

// The shortest run of stretches [a, b] of `pass` (by time, t[b + 1] − t[a]) that holds the first
// or the last stretch of every need: a sliding window over the stretches in order.
std::pair<std::size_t, std::size_t> shortestRun(const ScanPass& pass,
                                                const std::vector<Need>& needs) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> at;  // (stretch, need)
  for (std::uint32_t j = 0; j < needs.size(); ++j) {
    at.push_back({needs[j].first, j});
    if (needs[j].last != needs[j].first) at.push_back({needs[j].last, j});
  }
  std::sort(at.begin(), at.end());
  const auto time = [&](std::size_t a, std::size_t b) { return pass.t[b + 1] - pass.t[a]; };
  std::pair<std::size_t, std::size_t> best{at.front().first, at.back().first};
  std::vector<std::uint32_t> held(needs.size(), 0);
  std::size_t holding = 0;
  for (std::size_t lo = 0, hi = 0; hi < at.size(); ++hi) {
    if (held[at[hi].second]++ == 0) ++holding;
    for (; holding == needs.size(); ++lo) {
      if (time(at[lo].first, at[hi].first) < time(best.first, best.second))
        best = {at[lo].first, at[hi].first};
      if (--held[at[lo].second] == 0) --holding;
    }
  }
  return best;
}

// The needs split into groups wherever `gap` s or more of the pass lies between two needs'
// first stretches.
std::vector<std::vector<Need>> splitNeeds(const ScanPass& pass,
                                          std::vector<Need> needs,
                                          double gap) {
  std::sort(needs.begin(), needs.end(),
            [](const Need& a, const Need& b) { return a.first < b.first; });
  std::vector<std::vector<Need>> groups(1);
  for (std::size_t j = 0; j < needs.size(); ++j) {
    if (j > 0 && needs[j].first > needs[j - 1].first + 1 &&
        pass.t[needs[j].first] - pass.t[needs[j - 1].first + 1] >= gap)
      groups.emplace_back();
    groups.back().push_back(needs[j]);
  }
  return groups;
}

// The pieces of one pass: its needs (samples `mult` says only it covers) cut and split.
std::vector<ScanPass> cutPass(const ScanPass& pass,
                              const std::function<bool(std::uint32_t)>& counting,
                              const std::vector<std::uint32_t>& mult,
                              double split_gap,
                              double pad) {
  std::vector<Need> needs;
  for (std::size_t j = 0; j < pass.covers.size(); ++j)
    if (counting(pass.covers[j]) && mult[pass.covers[j]] == 1)
      needs.push_back({pass.cover_first[j], pass.cover_last[j]});
  std::vector<ScanPass> pieces;
  if (needs.empty()) return pieces;
  for (const std::vector<Need>& group : splitNeeds(pass, std::move(needs), split_gap)) {
    const auto [a, b] = shortestRun(pass, group);
    pieces.push_back(trimmedPass(pass, a, b, pad));
    if (a > 0 || b + 2 < pass.X_RS.size())
      pieces.back().label += fmt::format(" ({:.1f} s of it, from {:.1f} s)",
                                         pieces.back().duration(), pass.t[a] - pass.t.front());
  }
  return pieces;
}

}  // namespace

CutPasses cutToCover(const std::vector<ScanPass>& passes,
                     const std::vector<std::size_t>& chosen,
                     const std::vector<std::uint8_t>& counts,
                     const std::vector<std::uint8_t>& covered,
                     double split_gap,
                     double pad) {
  const auto counting = [&](std::uint32_t i) {
    return i < counts.size() && counts[i] && !(i < covered.size() && covered[i]);
  };
  std::vector<std::uint32_t> mult(counts.size(), 0);  // chosen passes (as cut) covering each
  for (const std::size_t p : chosen)
    for (const std::uint32_t i : passes[p].covers) mult[i] += counting(i) ? 1u : 0u;
  std::vector<std::size_t> order(chosen.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return passes[chosen[a]].duration() > passes[chosen[b]].duration();
  });
  CutPasses out;
  std::vector<std::vector<ScanPass>> pieces(chosen.size());
  std::vector<std::uint8_t> kept(counts.size(), 0);
  for (const std::size_t k : order) {
    const ScanPass& pass = passes[chosen[k]];
    if (pass.cover_first.size() != pass.covers.size() || pass.X_RS.size() < 2) {
      pieces[k] = {pass};
      continue;
    }
    pieces[k] = cutPass(pass, counting, mult, split_gap, pad);
    double left = 0.0;
    for (const ScanPass& piece : pieces[k]) {
      left += piece.duration();
      for (const std::uint32_t i : piece.covers) kept[i] = 1;
    }
    for (const std::uint32_t i : pass.covers) {
      if (counting(i) && !kept[i]) --mult[i];
      kept[i] = 0;
    }
    out.cut_time += pass.duration() - left;
    out.dropped += pieces[k].empty() ? 1u : 0u;
    out.split += pieces[k].size() > 1 ? pieces[k].size() - 1 : 0u;
  }
  for (std::size_t k = 0; k < chosen.size(); ++k)
    for (ScanPass& piece : pieces[k]) {
      out.passes.push_back(std::move(piece));
      out.from.push_back(chosen[k]);
    }
  return out;
}

std::vector<std::size_t> pruneToGoal(const std::vector<ScanPass>& passes,
                                     const std::vector<double>& cost,
                                     const std::vector<std::uint8_t>& counts,
                                     double goal) {
  std::vector<std::uint32_t> mult(counts.size(), 0);  // kept passes covering each sample
  for (const ScanPass& pass : passes)
    for (const std::uint32_t i : pass.covers) mult[i] += counts[i] ? 1u : 0u;
  std::size_t counted = 0, have = 0;
  for (std::size_t i = 0; i < counts.size(); ++i) {
    counted += counts[i] ? 1u : 0u;
    have += (counts[i] && mult[i] > 0) ? 1u : 0u;
  }
  const auto need = static_cast<std::size_t>(std::ceil(goal * static_cast<double>(counted) - 1e-9));
  std::vector<std::uint8_t> kept(passes.size(), 1);
  const auto own = [&](std::size_t p) {
    std::size_t n = 0;
    for (const std::uint32_t i : passes[p].covers) n += (counts[i] && mult[i] == 1) ? 1u : 0u;
    return n;
  };
  while (true) {
    // The pass whose own samples cost the least coverage per second it takes.
    std::size_t best = passes.size(), best_own = 0;
    for (std::size_t p = 0; p < passes.size(); ++p) {
      if (!kept[p] || !(cost[p] > 0.0)) continue;
      const std::size_t n = own(p);
      if (have < need + n) continue;
      if (best == passes.size() ||
          static_cast<double>(n) * cost[best] < static_cast<double>(best_own) * cost[p]) {
        best = p;
        best_own = n;
      }
    }
    if (best == passes.size()) break;
    kept[best] = 0;
    for (const std::uint32_t i : passes[best].covers)
      if (counts[i] && --mult[i] == 0) --have;
  }
  std::vector<std::size_t> out;
  for (std::size_t p = 0; p < passes.size(); ++p)
    if (kept[p]) out.push_back(p);
  return out;
}

CoverResult greedyCover(const std::vector<ScanPass>& passes,
                        const std::vector<std::uint8_t>& counts,
                        std::vector<std::uint8_t> covered,
                        const CoverSettings& settings,
                        const std::function<bool(std::size_t)>& accept,
                        const std::function<bool()>& keep_going) {
  CoverResult r;
  r.covered = std::move(covered);
  r.covered.resize(counts.size(), 0);
  for (std::size_t i = 0; i < counts.size(); ++i) {
    if (!counts[i]) continue;
    ++r.counted;
    if (r.covered[i]) ++r.covered_counted;
  }
  const auto rate = [&](std::size_t p, std::size_t gain) {
    return static_cast<double>(gain) / (passes[p].duration() + settings.pass_overhead);
  };
  // Lazy evaluation: a pass's gain only shrinks, so a stale rate is an upper bound.
  std::priority_queue<std::pair<double, std::size_t>> queue;
  for (std::size_t p = 0; p < passes.size(); ++p)
    queue.push({rate(p, newlyCovered(passes[p], counts, r.covered)), passes.size() - p});
  while (true) {
    if (static_cast<double>(r.covered_counted) >=
        settings.target * static_cast<double>(r.counted)) {
      r.stop = "target reached";
      break;
    }
    if (queue.empty()) {
      r.stop = "no gain";
      break;
    }
    if (r.chosen.size() >= settings.max_passes) {
      r.stop = "max_passes";
      break;
    }
    if (keep_going && !keep_going()) {
      r.stop = "stopped";
      break;
    }
    const auto [stale, key] = queue.top();
    queue.pop();
    const std::size_t p = passes.size() - key;  // ties go to the earlier pass
    const std::size_t gain = newlyCovered(passes[p], counts, r.covered);
    if (gain < settings.min_gain) continue;
    if (!queue.empty() && rate(p, gain) < queue.top().first) {
      queue.push({rate(p, gain), key});
      continue;
    }
    if (accept && !accept(p)) {
      r.rejected.push_back(p);
      continue;
    }
    r.chosen.push_back(p);
    for (std::uint32_t i : passes[p].covers) {
      if (!r.covered[i] && counts[i]) ++r.covered_counted;
      r.covered[i] = 1;
    }
  }
  return r;
}

// ---- transfers ----------------------------------------------------------------------------

namespace {

constexpr int kArcSegments = 16;
constexpr std::size_t kMaxTwoOptWork = 20'000'000;  // transfers judged by 2-opt at most

struct Spherical {
  double azimuth = 0.0, elevation = 0.0, radius = 0.0;
};

Spherical spherical(const Eigen::Vector3d& p, const Eigen::Vector3d& c) {
  const Eigen::Vector3d d = p - c;
  Spherical s;
  s.radius = d.norm();
  s.azimuth = std::atan2(d.y(), d.x());
  s.elevation = s.radius > 1e-9 ? std::asin(std::clamp(d.z() / s.radius, -1.0, 1.0)) : 1.5707963;
  return s;
}

Eigen::Vector3d point(const Spherical& s, const Eigen::Vector3d& c) {
  return c + s.radius * Eigen::Vector3d(std::cos(s.elevation) * std::cos(s.azimuth),
                                        std::cos(s.elevation) * std::sin(s.azimuth),
                                        std::sin(s.elevation));
}

// How far the head backs away from X along its laser (−z_S) to reach the sphere, m (0 when X is
// on or outside it).
double backOff(const Eigen::Isometry3d& X, const TransferSphere& sphere) {
  const Eigen::Vector3d d = X.translation() - sphere.centre;
  const Eigen::Vector3d z = X.linear().col(2);
  const double c = d.squaredNorm() - sphere.radius * sphere.radius;
  if (c >= 0.0) return 0.0;
  const double b = d.dot(z);
  return b + std::sqrt(b * b - c);  // the positive root of s² − 2bs + c = 0
}

// The head at X moved `s` m back along its laser.
Eigen::Isometry3d backedOff(const Eigen::Isometry3d& X, double s) {
  Eigen::Isometry3d out = X;
  out.translation() -= s * X.linear().col(2);
  return out;
}

// The arc between two poses on or outside the sphere: azimuth, elevation and radius about its
// centre interpolated; the head turns with the azimuth and, relative to that, evenly (slerp).
Eigen::Isometry3d arcPose(const Eigen::Isometry3d& a,
                          const Eigen::Isometry3d& b,
                          const TransferSphere& sphere,
                          double s) {
  const Spherical sa = spherical(a.translation(), sphere.centre);
  const Spherical sb = spherical(b.translation(), sphere.centre);
  const double turn = std::remainder(sb.azimuth - sa.azimuth, 2.0 * 3.141592653589793);
  const Eigen::Quaterniond qa(a.linear());
  const Eigen::Quaterniond qb(Eigen::AngleAxisd(-turn, Eigen::Vector3d::UnitZ()) * b.linear());
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::AngleAxisd(s * turn, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                 qa.slerp(s, qb).toRotationMatrix();
  out.translation() =
      point({sa.azimuth + s * turn, sa.elevation + s * (sb.elevation - sa.elevation),
             sa.radius + s * (sb.radius - sa.radius)},
            sphere.centre);
  return out;
}

// A bound on the arc's length from a to b, m: its speed |dp/ds| = sqrt(Δr² + r²(Δel² +
// cos²(el) Δaz²)) at its largest radius and cosine, so that crossing it in (bound / speed) s keeps
// every part of it within the speed. Close to the length: r and el change little along an arc.
double arcBound(const Spherical& a, const Spherical& b, double turn) {
  const double dr = b.radius - a.radius, del = b.elevation - a.elevation;
  const double r = std::max(a.radius, b.radius);
  const bool level = (a.elevation <= 0.0) != (b.elevation <= 0.0);  // crosses el = 0
  const double c = level ? 1.0 : std::max(std::cos(a.elevation), std::cos(b.elevation));
  return std::sqrt(dr * dr + r * r * (del * del + c * c * turn * turn));
}

// The three legs of a transfer: back off, arc, approach.
struct Legs {
  Eigen::Isometry3d out, in;                    // where the head leaves and rejoins the sphere
  double back = 0.0, arc = 0.0, forward = 0.0;  // lengths, m (the arc's a bound: arcBound)
  double rotation = 0.0;                        // rad the head turns on the arc
};

Legs legs(const Eigen::Isometry3d& from,
          const Eigen::Isometry3d& to,
          const TransferSphere& sphere) {
  Legs l;
  l.back = backOff(from, sphere);
  l.forward = backOff(to, sphere);
  l.out = backedOff(from, l.back);
  l.in = backedOff(to, l.forward);
  const Spherical sa = spherical(l.out.translation(), sphere.centre);
  const Spherical sb = spherical(l.in.translation(), sphere.centre);
  const double turn = std::remainder(sb.azimuth - sa.azimuth, 2.0 * 3.141592653589793);
  l.arc = arcBound(sa, sb, turn);
  // The head turns with the azimuth and by the rest about another axis: the sum bounds its
  // angle along the arc.
  const Eigen::Matrix3d unturned =
      Eigen::AngleAxisd(-turn, Eigen::Vector3d::UnitZ()).toRotationMatrix() * to.linear();
  l.rotation = std::abs(turn) + kinematics::rotationDistance(from.linear(), unturned);
  return l;
}

double arcTime(const Legs& l, const TransferSphere& sphere) {
  return std::max(l.arc / sphere.speed, l.rotation / sphere.turn_speed);
}

}  // namespace

double transferTime(const Eigen::Isometry3d& from,
                    const Eigen::Isometry3d& to,
                    const TransferSphere& sphere) {
  const Legs l = legs(from, to, sphere);
  return (l.back + l.forward) / sphere.speed + arcTime(l, sphere);
}

Move transferMove(const Eigen::Isometry3d& from,
                  const Eigen::Isometry3d& to,
                  const TransferSphere& sphere) {
  const Legs l = legs(from, to, sphere);
  Move move;
  const auto add = [&move](const Eigen::Isometry3d& X, double t) {
    if (!move.t.empty() && t <= move.t.back() + 1e-6) return;  // a zero-length step
    move.X_RS.push_back(X);
    move.t.push_back(t);
  };
  add(from, 0.0);
  const double t_out = l.back / sphere.speed, t_arc = arcTime(l, sphere);
  add(l.out, t_out);
  for (int k = 1; k < kArcSegments; ++k) {
    const double s = static_cast<double>(k) / kArcSegments;
    add(arcPose(l.out, l.in, sphere, s), t_out + s * t_arc);
  }
  add(l.in, t_out + t_arc);
  add(to, t_out + t_arc + l.forward / sphere.speed);
  if (move.t.size() < 2) {  // from == to: a pause long enough to be a move
    move.X_RS.push_back(to);
    move.t.push_back(1e-3);
  }
  move.X_RS.back() = to;
  return move;
}

std::vector<Eigen::Isometry3d> backOffLeg(const Eigen::Isometry3d& X,
                                          const TransferSphere& sphere,
                                          double step) {
  const double length = backOff(X, sphere);
  const int n = std::max(1, static_cast<int>(std::ceil(length / std::max(step, 1e-6))));
  std::vector<Eigen::Isometry3d> out;
  for (int k = 0; k <= n; ++k) out.push_back(backedOff(X, length * k / n));
  return out;
}

// ---- ordering -----------------------------------------------------------------------------

namespace {

double azimuthOf(const Eigen::Isometry3d& X) {
  return std::atan2(X.translation().y(), X.translation().x());
}

// Where a step enters and leaves, given where the head is.
struct Ends {
  Eigen::Isometry3d entry, exit;
  double turn = 0.0;
};

Ends ends(const ScanPass& pass, bool reversed, const std::optional<Eigen::Isometry3d>& at) {
  Ends e;
  if (pass.turnable()) {
    e.turn = at ? azimuthOf(*at) - azimuthOf(pass.X_RS.front()) : 0.0;
    e.entry = Eigen::AngleAxisd(e.turn, Eigen::Vector3d::UnitZ()) * pass.X_RS.front();
    e.exit = e.entry;  // a full turn
    return e;
  }
  e.entry = reversed ? pass.X_RS.back() : pass.X_RS.front();
  e.exit = reversed ? pass.X_RS.front() : pass.X_RS.back();
  return e;
}

double tourCost(const std::vector<ScanPass>& passes,
                const std::vector<TourStep>& tour,
                const std::optional<Eigen::Isometry3d>& start,
                const TransferSphere& sphere) {
  std::optional<Eigen::Isometry3d> at = start;
  double cost = 0.0;
  for (const TourStep& s : tour) {
    const Ends e = ends(passes[s.pass], s.reversed, at);
    if (at) cost += transferTime(*at, e.entry, sphere);
    at = e.exit;
  }
  return cost;
}

std::vector<TourStep> nearestNeighbour(const std::vector<ScanPass>& passes,
                                       std::vector<std::size_t> left,
                                       std::optional<Eigen::Isometry3d> at,
                                       const TransferSphere& sphere) {
  std::vector<TourStep> tour;
  while (!left.empty()) {
    double best = 1e300;
    std::size_t best_k = 0;
    bool best_rev = false;
    for (std::size_t k = 0; k < left.size(); ++k) {
      for (bool rev : {false, true}) {
        const Ends e = ends(passes[left[k]], rev, at);
        const double c = at ? transferTime(*at, e.entry, sphere) : 0.0;
        if (c < best - 1e-12) {
          best = c;
          best_k = k;
          best_rev = rev;
        }
      }
    }
    tour.push_back({left[best_k], best_rev, 0.0});
    at = ends(passes[left[best_k]], best_rev, at).exit;
    left.erase(left.begin() + static_cast<std::ptrdiff_t>(best_k));
  }
  return tour;
}

// The transfer time into each step and where the head is before it.
struct TourState {
  std::vector<double> into;  // transfer into step k (0 for a first step)
  std::vector<std::optional<Eigen::Isometry3d>> before;  // the head before step k
};

TourState tourState(const std::vector<ScanPass>& passes,
                    const std::vector<TourStep>& tour,
                    std::optional<Eigen::Isometry3d> at,
                    const TransferSphere& sphere) {
  TourState st;
  for (const TourStep& s : tour) {
    st.before.push_back(at);
    const Ends e = ends(passes[s.pass], s.reversed, at);
    st.into.push_back(at ? transferTime(*at, e.entry, sphere) : 0.0);
    at = e.exit;
  }
  return st;
}

// 2-opt: reverse a stretch [i, j] of the tour (each pass in it runs the other way) when that
// shortens the transfers. Only the transfers from i up to the first strip after j change (a
// spin's entry depends on where the head comes from; a strip's exit does not), so each move is
// judged on that window.
void twoOpt(const std::vector<ScanPass>& passes,
            std::vector<TourStep>& tour,
            const std::optional<Eigen::Isometry3d>& start,
            const TransferSphere& sphere) {
  const std::size_t n = tour.size();
  // Each round is O(n²) windows; the work is capped so a tour of many passes stays seconds.
  std::size_t work = 0;
  for (int round = 0; round < 50 && work < kMaxTwoOptWork; ++round) {
    bool improved = false;
    for (std::size_t i = 0; i < n && work < kMaxTwoOptWork; ++i) {
      TourState st = tourState(passes, tour, start, sphere);
      for (std::size_t j = i; j < n; ++j) {
        std::size_t m = j + 1;
        while (m < n && passes[tour[m].pass].turnable()) ++m;
        const std::size_t last = std::min(m, n - 1);
        double before = 0.0;
        for (std::size_t k = i; k <= last; ++k) before += st.into[k];
        std::optional<Eigen::Isometry3d> at = st.before[i];
        double after = 0.0;
        for (std::size_t k = i; k <= last && after < before; ++k, ++work) {
          const TourStep s =
              k <= j ? TourStep{tour[i + j - k].pass, !tour[i + j - k].reversed, 0.0} : tour[k];
          const Ends e = ends(passes[s.pass], s.reversed, at);
          if (at) after += transferTime(*at, e.entry, sphere);
          at = e.exit;
        }
        if (after < before - 1e-9) {
          std::reverse(tour.begin() + static_cast<std::ptrdiff_t>(i),
                       tour.begin() + static_cast<std::ptrdiff_t>(j) + 1);
          for (std::size_t k = i; k <= j; ++k) tour[k].reversed = !tour[k].reversed;
          st = tourState(passes, tour, start, sphere);
          improved = true;
        }
      }
    }
    if (!improved) break;
  }
}

// Fills in each spin's turn, now that the order is fixed.
void settleTurns(const std::vector<ScanPass>& passes,
                 std::vector<TourStep>& tour,
                 std::optional<Eigen::Isometry3d> at) {
  for (TourStep& s : tour) {
    const Ends e = ends(passes[s.pass], s.reversed, at);
    s.turn = e.turn;
    at = e.exit;
  }
}

}  // namespace

std::vector<TourStep> orderPasses(const std::vector<ScanPass>& passes,
                                  const std::vector<std::size_t>& chosen,
                                  const std::optional<Eigen::Isometry3d>& start,
                                  const TransferSphere& sphere) {
  std::vector<TourStep> best;
  if (start) {
    best = nearestNeighbour(passes, chosen, start, sphere);
  } else {
    // Nearest neighbour from up to 12 first passes spread over the chosen ones (each run is
    // O(n²) transfers; from every pass it would be O(n³)), in parallel; the cheapest tour wins,
    // the earliest start on a tie.
    const std::size_t step = std::max<std::size_t>(1, chosen.size() / 12);
    std::vector<std::size_t> firsts;
    for (std::size_t k = 0; k < chosen.size(); k += step) firsts.push_back(k);
    std::vector<std::vector<TourStep>> tours(firsts.size());
    std::vector<double> costs(firsts.size(), 1e300);
    tbb::parallel_for(std::size_t{0}, firsts.size(), [&](std::size_t i) {
      const std::size_t k = firsts[i];
      std::vector<std::size_t> left = chosen;
      left.erase(left.begin() + static_cast<std::ptrdiff_t>(k));
      std::vector<TourStep> tour{{chosen[k], false, 0.0}};
      const auto rest =
          nearestNeighbour(passes, left, ends(passes[chosen[k]], false, {}).exit, sphere);
      tour.insert(tour.end(), rest.begin(), rest.end());
      costs[i] = tourCost(passes, tour, start, sphere);
      tours[i] = std::move(tour);
    });
    double best_cost = 1e300;
    for (std::size_t i = 0; i < tours.size(); ++i) {
      if (costs[i] < best_cost - 1e-12) {
        best_cost = costs[i];
        best = std::move(tours[i]);
      }
    }
  }
  twoOpt(passes, best, start, sphere);
  settleTurns(passes, best, start);
  return best;
}

ScanPass stepPass(const std::vector<ScanPass>& passes, const TourStep& step) {
  ScanPass p = passes[step.pass];
  if (p.turnable() && step.turn != 0.0) p = rotatedPass(p, step.turn);
  if (step.reversed) {
    std::reverse(p.X_RS.begin(), p.X_RS.end());
    std::reverse(p.azimuth.begin(), p.azimuth.end());
    const double end = p.t.back();
    std::reverse(p.t.begin(), p.t.end());
    for (double& t : p.t) t = end - t;
    // Stretch k of the pass run backwards is stretch n − 2 − k of the pass as evaluated.
    const std::size_t top = p.X_RS.size() >= 2 ? p.X_RS.size() - 2 : 0;
    for (std::size_t j = 0; j < p.cover_first.size() && j < p.cover_last.size(); ++j) {
      const std::uint32_t f = p.cover_first[j];
      p.cover_first[j] = static_cast<std::uint32_t>(top - p.cover_last[j]);
      p.cover_last[j] = static_cast<std::uint32_t>(top - f);
    }
  }
  return p;
}

double tourTransferTime(const std::vector<ScanPass>& passes,
                        const std::vector<TourStep>& tour,
                        const std::optional<Eigen::Isometry3d>& start,
                        const TransferSphere& sphere) {
  std::vector<TourStep> unturned = tour;
  for (TourStep& s : unturned) s.turn = 0.0;
  return tourCost(passes, unturned, start, sphere);
}

}  // namespace scanplan::scanner
