// The optimal weighted partial set cover (scanner/set_cover.h): hand-derived instances where the
// greedy cover (scanner/pass_selection.h) is beaten, and random instances checked against an
// enumeration of every subset of sets, with the coverage recomputed here from the input.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include <scanplan/scanner/pass_selection.h>
#include <scanplan/scanner/set_cover.h>

namespace {

using scanplan::scanner::CoverLimits;
using scanplan::scanner::CoverProblem;
using scanplan::scanner::CoverSettings;
using scanplan::scanner::CoverSolution;
using scanplan::scanner::greedyCover;
using scanplan::scanner::ScanPass;
using scanplan::scanner::solveCover;

constexpr double kInf = std::numeric_limits<double>::infinity();
// Costs are sums of a few doubles in different orders (here, in GLPK, in the enumeration).
constexpr double kCostTol = 1e-9;
// GLPK proves its bounds within its feasibility and optimality tolerances (1e-7 relative).
constexpr double kBoundTol = 1e-6;
// Budget for instances GLPK solves in milliseconds: the answers must not depend on it.
constexpr double kBudget = 60.0;

// Counting elements to cover: the least c with c ≥ target · counted.
std::size_t required(const CoverProblem& p) {
  std::size_t counted = 0;
  for (std::uint8_t c : p.counts) counted += c != 0;
  std::size_t c = 0;
  while (static_cast<double>(c) < p.target * static_cast<double>(counted)) ++c;
  return c;
}

// Counting elements covered by `chosen` or before any set.
std::size_t coverage(const CoverProblem& p, const std::vector<std::size_t>& chosen) {
  std::vector<bool> hit(p.counts.size(), false);
  for (std::size_t i = 0; i < p.covered.size(); ++i) hit[i] = p.covered[i] != 0;
  for (std::size_t s : chosen)
    for (std::uint32_t i : p.covers[s]) hit[i] = true;
  std::size_t n = 0;
  for (std::size_t i = 0; i < p.counts.size(); ++i) n += p.counts[i] && hit[i];
  return n;
}

double costOf(const CoverProblem& p, const std::vector<std::size_t>& chosen) {
  double c = 0.0;
  for (std::size_t s : chosen) c += p.cost[s];
  return c;
}

bool allowed(const CoverProblem& p, std::size_t s) { return p.allowed.empty() || p.allowed[s]; }

// The optimum by enumerating every subset of the allowed sets (≤ 64 elements): kInf when no
// subset reaches the target.
double bruteForce(const CoverProblem& p) {
  const std::size_t n = p.cost.size();
  EXPECT_LE(p.counts.size(), 64u);
  std::uint64_t counting = 0, before = 0;
  for (std::size_t i = 0; i < p.counts.size(); ++i) {
    if (p.counts[i]) counting |= std::uint64_t{1} << i;
    if (!p.covered.empty() && p.covered[i]) before |= std::uint64_t{1} << i;
  }
  std::vector<std::uint64_t> bits(n, 0);
  for (std::size_t s = 0; s < n; ++s)
    for (std::uint32_t i : p.covers[s]) bits[s] |= std::uint64_t{1} << i;
  const std::size_t need = required(p);
  std::vector<std::uint64_t> union_of(std::size_t{1} << n, 0);
  std::vector<double> cost(std::size_t{1} << n, 0.0);
  union_of[0] = before;
  double best = kInf;
  for (std::size_t mask = 0; mask < union_of.size(); ++mask) {
    if (mask != 0) {
      const auto low = static_cast<std::size_t>(std::countr_zero(mask));
      if (!allowed(p, low)) {
        cost[mask] = kInf;
        continue;
      }
      union_of[mask] = union_of[mask & (mask - 1)] | bits[low];
      cost[mask] = cost[mask & (mask - 1)] + p.cost[low];
    }
    if (static_cast<std::size_t>(std::popcount(union_of[mask] & counting)) >= need)
      best = std::min(best, cost[mask]);
  }
  return best;
}

// greedyCover() on the problem as passes: duration = cost, no overhead; refused sets are the
// ones not allowed. The start a caller would hand to solveCover().
std::vector<std::size_t> greedyStart(const CoverProblem& p) {
  std::vector<ScanPass> passes(p.cost.size());
  for (std::size_t s = 0; s < passes.size(); ++s) {
    passes[s].t = {0.0, p.cost[s]};
    passes[s].covers = p.covers[s];
  }
  CoverSettings settings;
  settings.target = p.target;
  settings.pass_overhead = 0.0;
  std::vector<std::uint8_t> covered = p.covered;
  covered.resize(p.counts.size(), 0);
  auto chosen = greedyCover(passes, p.counts, covered, settings, [&](std::size_t s) {
                  return allowed(p, s);
                }).chosen;
  std::sort(chosen.begin(), chosen.end());
  return chosen;
}

// What every answer must satisfy, whatever the status: indices ascending and allowed, cost and
// coverage as recomputed here, the bound below the cost, never worse than the start.
::testing::AssertionResult consistent(const CoverProblem& p,
                                      const std::vector<std::size_t>& start,
                                      const CoverSolution& s) {
  if (!std::is_sorted(s.chosen.begin(), s.chosen.end()) ||
      std::adjacent_find(s.chosen.begin(), s.chosen.end()) != s.chosen.end())
    return ::testing::AssertionFailure() << "chosen not ascending and unique";
  for (std::size_t c : s.chosen)
    if (c >= p.cost.size() || !allowed(p, c))
      return ::testing::AssertionFailure() << "chose set " << c << ", not allowed";
  if (std::abs(s.cost - costOf(p, s.chosen)) > kCostTol)
    return ::testing::AssertionFailure()
           << "cost " << s.cost << ", sets cost " << costOf(p, s.chosen);
  const std::size_t covered = coverage(p, s.chosen);
  if (s.covered_counted != covered)
    return ::testing::AssertionFailure()
           << "covered_counted " << s.covered_counted << ", recomputed " << covered;
  if (s.reached != (covered >= required(p)))
    return ::testing::AssertionFailure() << "reached " << s.reached << " with " << covered << " of "
                                         << required(p) << " required";
  if (!(s.lower_bound >= 0.0 && s.lower_bound <= s.cost + kCostTol))
    return ::testing::AssertionFailure() << "lower bound " << s.lower_bound << ", cost " << s.cost;
  const bool start_reaches = coverage(p, start) >= required(p);
  if (start_reaches && !(s.reached && s.cost <= costOf(p, start) + kCostTol))
    return ::testing::AssertionFailure()
           << "worse than the start: " << s.cost << " vs " << costOf(p, start);
  if (coverage(p, s.chosen) < std::min(required(p), coverage(p, start)))
    return ::testing::AssertionFailure() << "covers less than the start";
  return ::testing::AssertionSuccess();
}

// The classic trap for greedy. Elements 0..7, all counting, target 1:
//   set 0 = {0..5}    cost 6    (6 per 6 s = 1.0 per s: greedy's first pick)
//   set 1 = {0,1,2,6} cost 4.1  (0.976 per s)
//   set 2 = {3,4,5,7} cost 4.1  (0.976 per s)
//   set 3 = {6}       cost 1.5, set 4 = {7} cost 1.5  (0.667 per s)
// After set 0, only 6 and 7 are open: sets 3 and 4 (1/1.5 per s) beat sets 1 and 2 (1/4.1), so
// greedy pays 6 + 1.5 + 1.5 = 9, and none of its sets is redundant. Covering 6 takes set 1 or
// 3, covering 7 set 2 or 4. Without set 1, 0..2 need set 0: ≥ 1.5 + 6 + 1.5 = 9; without set
// 2, 3..5 need set 0 likewise: ≥ 9; with both, 8.2 and nothing else is needed. The optimum is
// {1, 2} at 8.2.
CoverProblem classic() {
  CoverProblem p;
  p.cost = {6.0, 4.1, 4.1, 1.5, 1.5};
  p.covers = {{0, 1, 2, 3, 4, 5}, {0, 1, 2, 6}, {3, 4, 5, 7}, {6}, {7}};
  p.counts.assign(8, 1);
  p.target = 1.0;
  return p;
}

TEST(SetCover, BeatsGreedyOnTheClassicTrap) {
  const CoverProblem p = classic();
  const std::vector<std::size_t> start = greedyStart(p);
  ASSERT_EQ(start, (std::vector<std::size_t>{0, 3, 4}));
  const CoverSolution s = solveCover(p, start, kBudget);
  EXPECT_TRUE(consistent(p, start, s));
  EXPECT_EQ(s.chosen, (std::vector<std::size_t>{1, 2}));
  EXPECT_NEAR(s.cost, 8.2, kCostTol);
  EXPECT_NEAR(s.cost, bruteForce(p), kCostTol);
  EXPECT_TRUE(s.optimal);
  EXPECT_EQ(s.status, "optimal");
  EXPECT_EQ(s.gap(), 0.0);
  EXPECT_EQ(s.covered_counted, 8u);
}

// Without a start GLPK finds the optimum on its own; without time either, nothing is found and
// the status says so.
TEST(SetCover, NoStart) {
  const CoverProblem p = classic();
  const CoverSolution s = solveCover(p, {}, kBudget);
  EXPECT_TRUE(consistent(p, {}, s));
  EXPECT_EQ(s.chosen, (std::vector<std::size_t>{1, 2}));
  EXPECT_TRUE(s.optimal);

  const CoverSolution none = solveCover(p, {}, 0.0);
  EXPECT_TRUE(consistent(p, {}, none));
  EXPECT_TRUE(none.chosen.empty());
  EXPECT_FALSE(none.reached);
  EXPECT_EQ(none.status, "time limit: no cover found");
}

// Partial cover, elements 0..9, target 0.6 (6 of 10):
//   set 0 = {0..4} cost 4 (1.25 per s), set 1 = {5..9} cost 4 (1.25 per s),
//   set 2 = {0..5} cost 5.5 (1.09 per s).
// Greedy takes set 0 (5 covered), then set 1 (5 new per 4 s beats 1 new per 5.5 s): 8, and
// neither alone covers 6. Set 2 alone covers 6 for 5.5, and every other cover costs ≥ 8: the
// optimum is {2}.
TEST(SetCover, PartialCoverStopsAtTheTarget) {
  CoverProblem p;
  p.cost = {4.0, 4.0, 5.5};
  p.covers = {{0, 1, 2, 3, 4}, {5, 6, 7, 8, 9}, {0, 1, 2, 3, 4, 5}};
  p.counts.assign(10, 1);
  p.target = 0.6;
  const std::vector<std::size_t> start = greedyStart(p);
  ASSERT_EQ(start, (std::vector<std::size_t>{0, 1}));
  const CoverSolution s = solveCover(p, start, kBudget);
  EXPECT_TRUE(consistent(p, start, s));
  EXPECT_EQ(s.chosen, (std::vector<std::size_t>{2}));
  EXPECT_NEAR(s.cost, 5.5, kCostTol);
  EXPECT_EQ(s.required, 6u);
  EXPECT_EQ(s.covered_counted, 6u);
  EXPECT_TRUE(s.optimal);
}

// The classic with 6 and 7 covered before any set: set 0 alone (6) covers the rest, cheaper than
// {1, 2} (8.2); covered_counted counts the two free elements.
TEST(SetCover, PreCoveredElementsAreFree) {
  CoverProblem p = classic();
  p.covered = {0, 0, 0, 0, 0, 0, 1, 1};
  const CoverSolution s = solveCover(p, {1, 2}, kBudget);
  EXPECT_TRUE(consistent(p, {1, 2}, s));
  EXPECT_EQ(s.chosen, (std::vector<std::size_t>{0}));
  EXPECT_NEAR(s.cost, 6.0, kCostTol);
  EXPECT_EQ(s.covered_counted, 8u);
  EXPECT_TRUE(s.optimal);
}

// The classic with set 1 refused: 6 needs set 3 (set 1 is out), and then 0..2 need set 0, whose
// 3..5 leave only 7 open: set 4 (1.5) is cheaper than set 2 (4.1). The optimum is {0, 3, 4} at 9.
TEST(SetCover, RefusedSetsAreNeverChosen) {
  CoverProblem p = classic();
  p.allowed = {1, 0, 1, 1, 1};
  const std::vector<std::size_t> start = greedyStart(p);
  const CoverSolution s = solveCover(p, start, kBudget);
  EXPECT_TRUE(consistent(p, start, s));
  EXPECT_EQ(s.chosen, (std::vector<std::size_t>{0, 3, 4}));
  EXPECT_NEAR(s.cost, 9.0, kCostTol);
  EXPECT_THROW(solveCover(p, {1, 2}, kBudget), std::invalid_argument);
}

// Elements that do not count are never paid for: the classic where 6 and 7 do not count is the
// pre-covered case's optimum without the two elements in covered_counted.
TEST(SetCover, ElementsThatDoNotCountAreIgnored) {
  CoverProblem p = classic();
  p.counts = {1, 1, 1, 1, 1, 1, 0, 0};
  const CoverSolution s = solveCover(p, {}, kBudget);
  EXPECT_TRUE(consistent(p, {}, s));
  EXPECT_EQ(s.chosen, (std::vector<std::size_t>{0}));
  EXPECT_EQ(s.counted, 6u);
  EXPECT_EQ(s.covered_counted, 6u);
}

TEST(SetCover, NothingToDo) {
  CoverProblem empty;
  const CoverSolution a = solveCover(empty, {}, kBudget);
  EXPECT_TRUE(a.chosen.empty());
  EXPECT_TRUE(a.optimal);
  EXPECT_TRUE(a.reached);
  EXPECT_EQ(a.cost, 0.0);

  CoverProblem zero = classic();
  zero.target = 0.0;
  const CoverSolution b = solveCover(zero, {0, 3}, kBudget);
  EXPECT_TRUE(consistent(zero, {0, 3}, b));
  EXPECT_TRUE(b.chosen.empty());
  EXPECT_TRUE(b.optimal);
  EXPECT_EQ(b.cost, 0.0);
}

// Without sets 1 and 3 element 6 cannot be covered: 7 of 8 at most, short of the target 1. The
// start comes back (less what it does not need: set 2 adds nothing to {0, 4}).
TEST(SetCover, InfeasibleTargetReturnsTheStart) {
  CoverProblem p = classic();
  p.allowed = {1, 0, 1, 0, 1};
  const CoverSolution s = solveCover(p, {0, 2, 4}, kBudget);
  EXPECT_TRUE(consistent(p, {0, 2, 4}, s));
  EXPECT_EQ(s.status, "infeasible target");
  EXPECT_FALSE(s.reached);
  EXPECT_FALSE(s.optimal);
  EXPECT_EQ(s.chosen, (std::vector<std::size_t>{0, 4}));
  EXPECT_EQ(s.covered_counted, 7u);
  EXPECT_EQ(s.lower_bound, 0.0);
}

TEST(SetCover, BadInputThrows) {
  CoverProblem p = classic();
  EXPECT_THROW(solveCover(p, {5}, kBudget), std::invalid_argument);
  EXPECT_THROW(solveCover(p, {}, -1.0), std::invalid_argument);
  CoverProblem q = p;
  q.cost[2] = -1.0;
  EXPECT_THROW(solveCover(q, {}, kBudget), std::invalid_argument);
  q = p;
  q.covers[0].push_back(8);
  EXPECT_THROW(solveCover(q, {}, kBudget), std::invalid_argument);
  q = p;
  q.target = 1.5;
  EXPECT_THROW(solveCover(q, {}, kBudget), std::invalid_argument);
  q = p;
  q.allowed = {1, 1};
  EXPECT_THROW(solveCover(q, {}, kBudget), std::invalid_argument);
}

// A random instance: `sets` sets over `elements` elements, each covering an element with a
// probability drawn per set, costs in [1, 10]; most elements count, a few are covered before,
// a few sets are refused.
CoverProblem randomProblem(std::mt19937& rng,
                           std::size_t sets,
                           std::size_t elements,
                           double target) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  CoverProblem p;
  p.target = target;
  p.counts.resize(elements);
  p.covered.resize(elements);
  for (std::size_t i = 0; i < elements; ++i) {
    p.counts[i] = unit(rng) < 0.9;
    p.covered[i] = unit(rng) < 0.08;
  }
  p.cost.resize(sets);
  p.covers.resize(sets);
  p.allowed.resize(sets);
  for (std::size_t s = 0; s < sets; ++s) {
    p.cost[s] = 1.0 + 9.0 * unit(rng);
    p.allowed[s] = unit(rng) < 0.9;
    const double density = 0.08 + 0.3 * unit(rng);
    for (std::uint32_t i = 0; i < elements; ++i)
      if (unit(rng) < density) p.covers[s].push_back(i);
  }
  return p;
}

// solveCover() finds the enumeration's optimum on every instance it can reach, proves it, and
// never does worse than greedy; when nothing reaches the target it says so.
TEST(SetCover, MatchesEnumerationOnRandomInstances) {
  std::mt19937 rng(20240607);
  int solved = 0, infeasible = 0, beat_greedy = 0;
  for (int instance = 0; instance < 40; ++instance) {
    for (double target : {0.8, 0.95, 1.0}) {
      const std::size_t sets = 12 + static_cast<std::size_t>(instance % 5);
      const CoverProblem p = randomProblem(rng, sets, 60, target);
      const std::vector<std::size_t> start = greedyStart(p);
      const CoverSolution s = solveCover(p, start, kBudget);
      SCOPED_TRACE("instance " + std::to_string(instance) + ", target " + std::to_string(target));
      EXPECT_TRUE(consistent(p, start, s));
      const double optimum = bruteForce(p);
      if (optimum == kInf) {
        EXPECT_EQ(s.status, "infeasible target");
        EXPECT_FALSE(s.reached);
        ++infeasible;
        continue;
      }
      ++solved;
      EXPECT_TRUE(s.optimal) << s.status;
      EXPECT_TRUE(s.reached);
      EXPECT_GE(coverage(p, s.chosen), required(p));
      EXPECT_NEAR(s.cost, optimum, kCostTol);
      EXPECT_LE(s.lower_bound, optimum + kBoundTol);
      EXPECT_LE(optimum, s.cost + kCostTol);
      if (s.cost < costOf(p, start) - kCostTol) ++beat_greedy;
    }
  }
  // The instances exercise both outcomes, and greedy is not always optimal on them.
  EXPECT_GT(solved, 60);
  EXPECT_GT(infeasible, 0);
  EXPECT_GT(beat_greedy, 5);
}

// Same input, same answer: every field but the wall time.
TEST(SetCover, Deterministic) {
  std::mt19937 rng(7);
  for (int instance = 0; instance < 10; ++instance) {
    const CoverProblem p = randomProblem(rng, 16, 60, 0.95);
    const std::vector<std::size_t> start = greedyStart(p);
    const CoverSolution a = solveCover(p, start, kBudget);
    const CoverSolution b = solveCover(p, start, kBudget);
    EXPECT_EQ(a.chosen, b.chosen);
    EXPECT_EQ(a.cost, b.cost);
    EXPECT_EQ(a.lower_bound, b.lower_bound);
    EXPECT_EQ(a.status, b.status);
    EXPECT_EQ(a.nodes, b.nodes);
  }
}

// GLPK keeps its state per thread: solves on two threads at once give the sequential answers.
TEST(SetCover, ThreadsDoNotInterfere) {
  std::mt19937 rng(5);
  std::vector<CoverProblem> problems;
  for (int i = 0; i < 8; ++i) problems.push_back(randomProblem(rng, 16, 60, 0.95));
  std::vector<CoverSolution> alone, together(problems.size());
  for (const CoverProblem& p : problems) alone.push_back(solveCover(p, greedyStart(p), kBudget));
  const auto half = [&](std::size_t first) {
    for (std::size_t i = first; i < problems.size(); i += 2)
      together[i] = solveCover(problems[i], greedyStart(problems[i]), kBudget);
  };
  std::thread other(half, 1);
  half(0);
  other.join();
  for (std::size_t i = 0; i < problems.size(); ++i) {
    EXPECT_EQ(alone[i].chosen, together[i].chosen);
    EXPECT_EQ(alone[i].lower_bound, together[i].lower_bound);
  }
}

// Elements covered by the same sets become one weighted class: thousands of samples, few rows.
TEST(SetCover, MergesElementsCoveredByTheSameSets) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<std::uint32_t> pattern_of(0, 29);
  const std::size_t sets = 14, elements = 10'000;
  // 30 patterns of sets; each element takes one of them.
  std::vector<std::vector<std::size_t>> patterns(30);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (auto& pattern : patterns)
    for (std::size_t s = 0; s < sets; ++s)
      if (unit(rng) < 0.3) pattern.push_back(s);
  CoverProblem p;
  p.target = 0.9;
  p.cost.resize(sets);
  for (double& c : p.cost) c = 1.0 + 9.0 * unit(rng);
  p.covers.resize(sets);
  p.counts.assign(elements, 1);
  std::set<std::vector<std::size_t>> used;
  for (std::uint32_t i = 0; i < elements; ++i) {
    const auto& pattern = patterns[pattern_of(rng)];
    for (std::size_t s : pattern) p.covers[s].push_back(i);
    if (!pattern.empty()) used.insert(pattern);
  }
  const std::vector<std::size_t> start = greedyStart(p);
  const CoverSolution s = solveCover(p, start, kBudget);
  EXPECT_TRUE(consistent(p, start, s));
  EXPECT_EQ(s.model_classes, used.size());
  EXPECT_TRUE(s.optimal) << s.status;
  EXPECT_TRUE(s.reached);
}

// Cut short (no time, one node, a model over the size limit), the answer is still a valid cover
// no worse than the start, and the node-limited one is the same on every run.
TEST(SetCover, LimitsKeepTheStart) {
  std::mt19937 rng(3);
  const CoverProblem p = randomProblem(rng, 16, 60, 0.95);
  const std::vector<std::size_t> start = greedyStart(p);
  ASSERT_GE(coverage(p, start), required(p));

  const CoverSolution none = solveCover(p, start, 0.0);
  EXPECT_TRUE(consistent(p, start, none));
  EXPECT_EQ(none.status, "time limit");
  EXPECT_EQ(none.lower_bound, 0.0);

  CoverLimits tiny;
  tiny.max_nonzeros = 10;
  const CoverSolution big = solveCover(p, start, kBudget, tiny);
  EXPECT_TRUE(consistent(p, start, big));
  EXPECT_EQ(big.status.rfind("start only", 0), 0u) << big.status;
  EXPECT_EQ(big.lower_bound, 0.0);
  EXPECT_EQ(big.gap(), 1.0);

  CoverLimits one_node;
  one_node.node_limit = 1;
  const CoverSolution a = solveCover(p, start, kBudget, one_node);
  const CoverSolution b = solveCover(p, start, kBudget, one_node);
  EXPECT_TRUE(consistent(p, start, a));
  EXPECT_TRUE(a.status == "node limit" || a.status == "optimal") << a.status;
  EXPECT_LE(a.nodes, 1u);
  EXPECT_GT(a.lower_bound, 0.0);  // the LP relaxation's bound at least
  EXPECT_EQ(a.chosen, b.chosen);
  EXPECT_EQ(a.lower_bound, b.lower_bound);
}

// The poll runs before the search and at every step of it without changing the answer; what it
// throws ends the search and leaves solveCover(), and GLPK is fit for the next call.
TEST(SetCover, APollRunsAtEveryStepAndItsExceptionEndsTheSearch) {
  std::mt19937 rng(5);
  const CoverProblem p = randomProblem(rng, 24, 60, 0.95);
  const std::vector<std::size_t> start = greedyStart(p);
  const CoverSolution plain = solveCover(p, start, kBudget);
  std::size_t calls = 0;
  CoverLimits counting;
  counting.poll = [&] { ++calls; };
  const CoverSolution polled = solveCover(p, start, kBudget, counting);
  EXPECT_EQ(polled.chosen, plain.chosen);
  EXPECT_EQ(polled.lower_bound, plain.lower_bound);
  EXPECT_GE(calls, polled.nodes + 1);  // before the search, then at least once a node
  ASSERT_GE(calls, 3u);
  struct Stop {};
  for (const std::size_t at : {std::size_t{1}, std::size_t{2}, calls}) {
    std::size_t k = 0;
    CoverLimits stopping;
    stopping.poll = [&] {
      if (++k == at) throw Stop{};
    };
    EXPECT_THROW(solveCover(p, start, kBudget, stopping), Stop) << "thrown at call " << at;
    EXPECT_EQ(k, at);  // not called again once it threw
  }
  EXPECT_EQ(solveCover(p, start, kBudget).chosen, plain.chosen);
}

}  // namespace
