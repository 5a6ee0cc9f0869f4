#pragma once
// Choosing scan passes by an integer programme (docs/automatic-scan.md): the weighted partial set
// cover that greedyCover() (scanner/pass_selection.h) answers approximately, solved to optimality
// or to a proven gap within a budget by GLPK's branch and cut, started from a feasible answer such
// as greedy's. GLPK stays behind this header.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace scanplan::scanner {

/// A weighted partial set cover: choose sets (scan passes) of least total cost so that at least
/// `target` of the counting elements (area samples) are covered.
struct CoverProblem {
  std::vector<double> cost;                        ///< s per set: finite, ≥ 0 (time + overhead)
  std::vector<std::vector<std::uint32_t>> covers;  ///< per set: the elements it covers
  std::vector<std::uint8_t> counts;   ///< per element: 1 when it counts toward the target
  std::vector<std::uint8_t> covered;  ///< per element: covered before any set (free); empty: none
  std::vector<std::uint8_t> allowed;  ///< per set: 0 = may not be chosen; empty: all may
  double target = 0.98;               ///< fraction of the counting elements to cover, in [0, 1]
};

/// Limits on solveCover() besides its time budget.
struct CoverLimits {
  /// Branch-and-bound nodes solved at most, the root included (0: no limit). Unlike the time
  /// budget, a node limit stops the search at the same point on every machine, so the answer
  /// depends on the input only.
  std::size_t node_limit = 0;
  /// Constraint-matrix nonzeros of the reduced model at most: a larger model is not handed to
  /// GLPK, and the (pruned) start is returned with status "start only: …" and no bound.
  std::size_t max_nonzeros = 200'000;
  /// Called before the search and at every step of it (each node, each rounding of a node's
  /// LP); an exception it throws (a cancelled plan) ends the search and leaves solveCover().
  /// Empty: none.
  std::function<void()> poll;
};

struct CoverSolution {
  std::vector<std::size_t> chosen;  ///< set indices, ascending
  double cost = 0.0;                ///< s: Σ cost of chosen
  /// s: a proven lower bound on the optimal cost (GLPK's best bound or LP relaxation, within
  /// its tolerances); 0 when none was proven (model too large, no time, infeasible target).
  double lower_bound = 0.0;
  bool optimal = false;  ///< chosen is proven optimal (within GLPK's tolerances)
  bool reached = false;  ///< chosen covers the target
  /// Why it ended: "optimal", "time limit", "node limit", "infeasible target", "target met
  /// before any set", "start only: <why GLPK did not search>", or what else GLPK reported;
  /// ": no cover found" appended when chosen misses a target that can be reached.
  std::string status;
  std::size_t counted = 0;          ///< counting elements
  std::size_t required = 0;         ///< counting elements to cover: ⌈target · counted⌉
  std::size_t covered_counted = 0;  ///< counting elements chosen covers (pre-covered included)
  std::size_t model_sets = 0;       ///< columns x of the reduced model
  std::size_t model_classes = 0;    ///< merged element classes (rows) of the reduced model
  std::size_t nodes = 0;            ///< branch-and-bound nodes solved
  double seconds = 0.0;             ///< wall time of the call

  /// (cost − lower_bound) / cost: 0 when optimal or cost is 0, 1 when nothing is proven.
  double gap() const;
};

/// The cheapest choice of allowed sets covering at least ⌈target · counted⌉ counting elements
/// (the pre-covered ones included), by GLPK's branch and cut on a reduced model: elements
/// covered by exactly the same allowed sets are merged into one weighted class, sets covering no
/// open counting element are dropped (both exact). `start` (set indices, e.g. greedyCover()'s
/// chosen) is pruned of sets it does not need and, when it reaches the target, handed to GLPK
/// as its first incumbent; at every fractional node the node's LP solution is rounded into a
/// cover too (sets at ≥ 1/2, completed greedily, pruned). The answer never costs more than
/// `start` and never covers less of the target, and its coverage is recounted on the input.
///
/// The search stops at `time_budget_s` (s of wall time from the call, ≥ 0; infinity: none) or
/// at `limits.node_limit`, keeping the best cover found and the best bound proven (status "time
/// limit" or "node limit"). The budget is checked between the steps of the search: one LP
/// re-solve may run past it (about 2 s on a 100 000-nonzero model here, milliseconds on small
/// ones). GLPK is deterministic, so the answer depends on the input only, except when the time
/// budget cuts the search: how far it got then depends on the machine's speed and load. Where
/// the answer must be reproducible, use a node limit and an ample time budget.
///
/// When even every allowed set cannot reach the target, returns the pruned start with status
/// "infeasible target" (covered_counted says how far it gets). Throws std::invalid_argument on
/// inconsistent sizes, an element index out of range, a negative or non-finite cost, a target
/// outside [0, 1], a negative budget, or a start naming a set out of range or not allowed.
/// Thread safe (GLPK keeps its state per thread).
CoverSolution solveCover(const CoverProblem& problem,
                         const std::vector<std::size_t>& start,
                         double time_budget_s,
                         const CoverLimits& limits = {});

}  // namespace scanplan::scanner
