#include <scanplan/scanner/set_cover.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdint>
#include <exception>
#include <map>
#include <memory>
#include <queue>
#include <stdexcept>
#include <string>
#include <utility>

#include <glpk.h>

namespace scanplan::scanner {

namespace {

using Clock = std::chrono::steady_clock;
constexpr double kNoDeadline_s = 1e9;  // a budget this long is no budget (and fits Clock)

// The problem with only what matters for the target: per set, the open elements (counting, not
// covered before) it covers, sorted and unique; empty for sets that may not be chosen.
struct OpenProblem {
  std::vector<std::vector<std::uint32_t>> covers;
  std::size_t elements = 0;
  std::size_t counted = 0;
  std::size_t precovered = 0;  // counting elements covered before any set
  std::size_t required = 0;    // counting elements to cover, pre-covered included
  std::size_t need = 0;        // open elements to cover: required − precovered, or 0
};

OpenProblem openProblem(const CoverProblem& problem) {
  const std::size_t sets = problem.cost.size();
  const std::size_t elements = problem.counts.size();
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("solveCover: " + what);
  };
  if (problem.covers.size() != sets)
    fail(std::to_string(problem.covers.size()) + " cover lists for " + std::to_string(sets) +
         " costs");
  if (!problem.allowed.empty() && problem.allowed.size() != sets)
    fail("allowed has " + std::to_string(problem.allowed.size()) + " entries for " +
         std::to_string(sets) + " sets (expected one per set, or none)");
  if (!problem.covered.empty() && problem.covered.size() != elements)
    fail("covered has " + std::to_string(problem.covered.size()) + " entries for " +
         std::to_string(elements) + " elements (expected one per element, or none)");
  if (!(problem.target >= 0.0 && problem.target <= 1.0))
    fail("target " + std::to_string(problem.target) + " is not in [0, 1]");

  OpenProblem open;
  open.elements = elements;
  std::vector<std::uint8_t> is_open(elements, 0);
  for (std::size_t i = 0; i < elements; ++i) {
    if (!problem.counts[i]) continue;
    ++open.counted;
    if (!problem.covered.empty() && problem.covered[i])
      ++open.precovered;
    else
      is_open[i] = 1;
  }
  // The smallest count c with c ≥ target · counted, the test greedyCover() stops on.
  open.required =
      static_cast<std::size_t>(std::ceil(problem.target * static_cast<double>(open.counted)));
  open.need = open.required > open.precovered ? open.required - open.precovered : 0;

  open.covers.resize(sets);
  for (std::size_t p = 0; p < sets; ++p) {
    if (!std::isfinite(problem.cost[p]) || problem.cost[p] < 0.0)
      fail("cost of set " + std::to_string(p) + " is " + std::to_string(problem.cost[p]) +
           " (expected finite, ≥ 0)");
    for (std::uint32_t i : problem.covers[p])
      if (i >= elements)
        fail("set " + std::to_string(p) + " covers element " + std::to_string(i) + " of " +
             std::to_string(elements));
    if (!problem.allowed.empty() && !problem.allowed[p]) continue;
    auto& c = open.covers[p];
    for (std::uint32_t i : problem.covers[p])
      if (is_open[i]) c.push_back(i);
    std::sort(c.begin(), c.end());
    c.erase(std::unique(c.begin(), c.end()), c.end());
  }
  return open;
}

// Open elements the sets cover.
std::size_t coveredOpen(const OpenProblem& open, const std::vector<std::size_t>& sets) {
  std::vector<std::uint8_t> hit(open.elements, 0);
  std::size_t n = 0;
  for (std::size_t p : sets)
    for (std::uint32_t i : open.covers[p])
      if (!hit[i]) hit[i] = 1, ++n;
  return n;
}

double costOf(const CoverProblem& problem, const std::vector<std::size_t>& sets) {
  double c = 0.0;
  for (std::size_t p : sets) c += problem.cost[p];
  return c;
}

// Drops sets the choice does not need: the costliest first, each while the rest still covers
// min(need, what the whole choice covers). Keeps the order of the rest (ascending).
std::vector<std::size_t> prune(const CoverProblem& problem,
                               const OpenProblem& open,
                               std::vector<std::size_t> sets) {
  std::vector<std::uint32_t> hits(open.elements, 0);
  std::size_t covered = 0;
  for (std::size_t p : sets)
    for (std::uint32_t i : open.covers[p])
      if (hits[i]++ == 0) ++covered;
  const std::size_t goal = std::min(open.need, covered);
  std::vector<std::size_t> order = sets;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return problem.cost[a] > problem.cost[b]; });
  std::vector<std::uint8_t> dropped(problem.cost.size(), 0);
  for (std::size_t p : order) {
    std::size_t loss = 0;
    for (std::uint32_t i : open.covers[p])
      if (hits[i] == 1) ++loss;
    if (covered - loss < goal) continue;
    for (std::uint32_t i : open.covers[p]) --hits[i];
    covered -= loss;
    dropped[p] = 1;
  }
  std::erase_if(sets, [&](std::size_t p) { return dropped[p] != 0; });
  return sets;
}

// The reduced model: columns are the allowed sets that cover an open element; rows are classes
// of open elements covered by exactly the same columns, each with its number of elements.
struct Model {
  std::vector<std::size_t> set_of_column;
  std::vector<std::vector<std::uint32_t>> columns_of_class;  // ascending
  std::vector<std::size_t> weight;
  std::vector<std::uint32_t> class_of_element;  // kNoClass for elements in no column
  std::size_t nonzeros = 0;
};

constexpr std::uint32_t kNoClass = UINT32_MAX;

Model reducedModel(const OpenProblem& open) {
  Model m;
  std::vector<std::vector<std::uint32_t>> columns_of_element(open.elements);
  for (std::size_t p = 0; p < open.covers.size(); ++p) {
    if (open.covers[p].empty()) continue;
    const auto column = static_cast<std::uint32_t>(m.set_of_column.size());
    m.set_of_column.push_back(p);
    for (std::uint32_t i : open.covers[p]) columns_of_element[i].push_back(column);
  }
  // Merging is exact: elements with the same columns are covered by the same choices. Classes
  // are numbered in order of their first element, so the model does not depend on the map.
  std::map<std::vector<std::uint32_t>, std::uint32_t> class_of_columns;
  m.class_of_element.assign(open.elements, kNoClass);
  for (std::size_t i = 0; i < open.elements; ++i) {
    if (columns_of_element[i].empty()) continue;
    const auto next = static_cast<std::uint32_t>(m.columns_of_class.size());
    const auto [it, inserted] =
        class_of_columns.try_emplace(std::move(columns_of_element[i]), next);
    if (inserted) {
      m.columns_of_class.push_back(it->first);
      m.weight.push_back(0);
    }
    ++m.weight[it->second];
    m.class_of_element[i] = it->second;
  }
  // Per class: y_k and its columns in its coupling row, y_k in the count row.
  for (const auto& columns : m.columns_of_class) m.nonzeros += columns.size() + 2;
  return m;
}

// The model's point for a choice of sets (all in the model): 1-based, x then y.
std::vector<double> modelPoint(const OpenProblem& open,
                               const Model& m,
                               const std::vector<std::size_t>& column_of_set,
                               const std::vector<std::size_t>& sets) {
  const std::size_t P = m.set_of_column.size();
  std::vector<double> point(1 + P + m.columns_of_class.size(), 0.0);
  for (std::size_t p : sets) {
    point[1 + column_of_set[p]] = 1.0;
    for (std::uint32_t i : open.covers[p]) point[1 + P + m.class_of_element[i]] = 1.0;
  }
  return point;
}

// A cover from a node's fractional LP solution `x` (per column): the sets it takes at ≥ 1/2,
// completed by lazy greedy (most new open elements per second, as greedyCover()), pruned.
std::vector<std::size_t> roundLp(const CoverProblem& problem,
                                 const OpenProblem& open,
                                 const Model& m,
                                 const std::vector<double>& x) {
  std::vector<std::uint8_t> hit(open.elements, 0);
  std::size_t covered = 0;
  std::vector<std::size_t> sets;
  std::vector<std::uint8_t> taken(x.size(), 0);
  const auto take = [&](std::size_t j) {
    const std::size_t p = m.set_of_column[j];
    for (std::uint32_t i : open.covers[p])
      if (!hit[i]) hit[i] = 1, ++covered;
    sets.push_back(p);
    taken[j] = 1;
  };
  for (std::size_t j = 0; j < x.size(); ++j)
    if (x[j] >= 0.5) take(j);
  const auto rate = [&](std::size_t j) {
    const std::size_t p = m.set_of_column[j];
    std::size_t gain = 0;
    for (std::uint32_t i : open.covers[p]) gain += hit[i] == 0;
    if (gain == 0) return 0.0;
    return problem.cost[p] > 0.0 ? static_cast<double>(gain) / problem.cost[p] : INFINITY;
  };
  // A stale rate bounds the fresh one from above (gains only shrink); ties to the first column.
  std::priority_queue<std::pair<double, std::size_t>> queue;
  for (std::size_t j = 0; j < x.size(); ++j)
    if (!taken[j]) queue.push({rate(j), x.size() - j});
  while (covered < open.need && !queue.empty()) {
    const std::size_t j = x.size() - queue.top().second;
    queue.pop();
    const double fresh = rate(j);
    if (fresh <= 0.0) continue;
    if (!queue.empty() && fresh < queue.top().first) {
      queue.push({fresh, x.size() - j});
      continue;
    }
    take(j);
  }
  std::sort(sets.begin(), sets.end());
  return prune(problem, open, std::move(sets));
}

struct SearchContext {
  const CoverProblem* problem = nullptr;
  const OpenProblem* open = nullptr;
  const Model* model = nullptr;
  std::vector<std::size_t> column_of_set;
  std::vector<std::size_t> start;  // a cover reaching the target, handed over first; or empty
  bool start_given = false;
  const std::function<void()>* poll = nullptr;  // CoverLimits::poll, when set
  std::size_t node_limit = 0;
  bool node_limit_hit = false;
  Clock::time_point deadline = Clock::time_point::max();
  bool deadline_hit = false;
  std::size_t nodes = 0;     // selected to be solved
  double bound = -INFINITY;  // best global lower bound seen in the tree
  std::exception_ptr error;
};

void searchStep(glp_tree* tree, SearchContext& ctx) {
  if (ctx.poll != nullptr) (*ctx.poll)();
  switch (glp_ios_reason(tree)) {
    case GLP_IHEUR: {
      // Called at each node whose LP solution is fractional, the first time after the root
      // LP. GLPK takes a point that beats its incumbent without checking it: every point given
      // is a cover reaching the target (the start is, roundLp() completes its covers).
      if (!ctx.start_given && !ctx.start.empty()) {
        glp_ios_heur_sol(tree,
                         modelPoint(*ctx.open, *ctx.model, ctx.column_of_set, ctx.start).data());
        ctx.start_given = true;
      }
      glp_prob* mip = glp_ios_get_prob(tree);
      std::vector<double> x(ctx.model->set_of_column.size());
      for (std::size_t j = 0; j < x.size(); ++j)
        x[j] = glp_get_col_prim(mip, static_cast<int>(j) + 1);
      const std::vector<std::size_t> rounded = roundLp(*ctx.problem, *ctx.open, *ctx.model, x);
      if (coveredOpen(*ctx.open, rounded) >= ctx.open->need)
        glp_ios_heur_sol(tree,
                         modelPoint(*ctx.open, *ctx.model, ctx.column_of_set, rounded).data());
      break;
    }
    case GLP_ISELECT: {
      // Every solution not yet found lies in an active node, so min(incumbent, best active
      // node's bound) is a global lower bound; the nodes' bounds only rise as the search goes.
      const int best = glp_ios_best_node(tree);
      double bound = best != 0 ? glp_ios_node_bound(tree, best) : INFINITY;
      glp_prob* mip = glp_ios_get_prob(tree);
      if (glp_mip_status(mip) == GLP_FEAS) bound = std::min(bound, glp_mip_obj_val(mip));
      if (std::isfinite(bound)) ctx.bound = std::max(ctx.bound, bound);
      // Called before each node is solved, the root first.
      if (ctx.node_limit != 0 && ctx.nodes >= ctx.node_limit) {
        ctx.node_limit_hit = true;
        glp_ios_terminate(tree);
      } else {
        ++ctx.nodes;
      }
      break;
    }
    default:
      break;
  }
  // GLPK looks at tm_lim only between nodes; looking here too also stops it between the stages
  // of a node. A node's LP re-solve itself cannot be interrupted.
  if (Clock::now() >= ctx.deadline) {
    ctx.deadline_hit = true;
    glp_ios_terminate(tree);
  }
}

// No exception may cross GLPK's C frames: one is kept, the search stopped, and it is rethrown
// once glp_intopt() has returned.
void searchCallback(glp_tree* tree, void* info) {
  auto& ctx = *static_cast<SearchContext*>(info);
  if (ctx.error) return;  // stopping already
  try {
    searchStep(tree, ctx);
  } catch (...) {
    ctx.error = std::current_exception();
    glp_ios_terminate(tree);
  }
}

// GLPK's environment (per thread) for the call: one this call creates is freed when it ends, so
// that a thread that only calls solveCover() keeps nothing of GLPK's (5 KB a thread otherwise,
// which leak checkers report when the thread ends). One that existed before stays.
class GlpkEnvironment {
 public:
  GlpkEnvironment() : state_(glp_init_env()) {}
  ~GlpkEnvironment() {
    if (state_ == 0) glp_free_env();
  }
  GlpkEnvironment(const GlpkEnvironment&) = delete;
  GlpkEnvironment& operator=(const GlpkEnvironment&) = delete;
  bool ok() const { return state_ == 0 || state_ == 1; }

 private:
  int state_;  // glp_init_env(): 0 created, 1 there before, else failed
};

// GLPK's terminal output off for this thread while it lives, then as it was.
class TerminalOff {
 public:
  TerminalOff() : was_(glp_term_out(GLP_OFF)) {}
  ~TerminalOff() { glp_term_out(was_); }
  TerminalOff(const TerminalOff&) = delete;
  TerminalOff& operator=(const TerminalOff&) = delete;

 private:
  int was_;
};

int milliseconds(double seconds) {
  if (!(seconds < static_cast<double>(INT_MAX) / 1000.0)) return INT_MAX;
  return std::max(1, static_cast<int>(std::ceil(seconds * 1000.0)));
}

// A candidate answer: reaching the target beats not reaching it, then the lower cost.
struct Candidate {
  std::vector<std::size_t> sets;
  std::size_t covered_open = 0;
  double cost = 0.0;
};

bool better(const Candidate& a, const Candidate& b, std::size_t need) {
  const bool a_reaches = a.covered_open >= need, b_reaches = b.covered_open >= need;
  if (a_reaches != b_reaches) return a_reaches;
  if (!a_reaches) return a.covered_open > b.covered_open;
  return a.cost < b.cost;
}

}  // namespace

double CoverSolution::gap() const {
  if (optimal || cost <= 0.0) return 0.0;
  return std::clamp((cost - lower_bound) / cost, 0.0, 1.0);
}

namespace {

// The start's sets, sorted and each once; throws when one is out of range or not allowed.
std::vector<std::size_t> checkedStart(const CoverProblem& problem,
                                      const std::vector<std::size_t>& start) {
  std::vector<std::size_t> sets = start;
  std::sort(sets.begin(), sets.end());
  sets.erase(std::unique(sets.begin(), sets.end()), sets.end());
  for (std::size_t p : sets)
    if (p >= problem.cost.size() || (!problem.allowed.empty() && !problem.allowed[p]))
      throw std::invalid_argument("solveCover: the start names set " + std::to_string(p) +
                                  (p >= problem.cost.size() ? ", out of range" : ", not allowed"));
  return sets;
}

using GlpkProblem = std::unique_ptr<glp_prob, decltype(&glp_delete_prob)>;

// The reduced model as GLPK's integer programme.
// Columns 1..P: x_p ∈ {0, 1}, set p chosen, cost c_p. Columns P+1..P+K: y_k ∈ [0, 1], class k
// counted as covered. Rows 1..K: y_k − Σ_{p covers k} x_p ≤ 0. Row K+1: Σ w_k y_k ≥ need.
// y may be continuous: it is not in the objective, and for a binary x each y_k may take any
// value in [0, min(1, Σ x_p)], i.e. in [0, 1] when x covers class k and 0 when not, so the
// count row holds for some y exactly when it holds for y_k = [x covers k], i.e. exactly when
// x covers the target. The x feasible for the MIP are the same as with binary y (and the LP
// relaxations are the same), while GLPK branches on x only. The bound y_k ≤ 1 is what makes
// this exact: without it an element covered twice would count twice.
GlpkProblem glpkModel(const CoverProblem& problem, const OpenProblem& open, const Model& m) {
  const int P = static_cast<int>(m.set_of_column.size());
  const int K = static_cast<int>(m.columns_of_class.size());
  GlpkProblem lp(glp_create_prob(), &glp_delete_prob);
  glp_set_obj_dir(lp.get(), GLP_MIN);
  glp_add_cols(lp.get(), P + K);
  for (int j = 1; j <= P; ++j) {
    glp_set_col_kind(lp.get(), j, GLP_BV);
    glp_set_obj_coef(lp.get(), j, problem.cost[m.set_of_column[static_cast<std::size_t>(j - 1)]]);
  }
  for (int k = 1; k <= K; ++k) glp_set_col_bnds(lp.get(), P + k, GLP_DB, 0.0, 1.0);
  glp_add_rows(lp.get(), K + 1);
  std::vector<int> ia(1), ja(1);
  std::vector<double> ar(1);
  ia.reserve(m.nonzeros + 1), ja.reserve(m.nonzeros + 1), ar.reserve(m.nonzeros + 1);
  const auto add = [&](int row, int column, double value) {
    ia.push_back(row), ja.push_back(column), ar.push_back(value);
  };
  for (int k = 1; k <= K; ++k) {
    glp_set_row_bnds(lp.get(), k, GLP_UP, 0.0, 0.0);
    add(k, P + k, 1.0);
    for (std::uint32_t column : m.columns_of_class[static_cast<std::size_t>(k - 1)])
      add(k, static_cast<int>(column) + 1, -1.0);
    add(K + 1, P + k, static_cast<double>(m.weight[static_cast<std::size_t>(k - 1)]));
  }
  glp_set_row_bnds(lp.get(), K + 1, GLP_LO, static_cast<double>(open.need), 0.0);
  glp_load_matrix(lp.get(), static_cast<int>(ia.size() - 1), ia.data(), ja.data(), ar.data());
  return lp;
}

// The sets of GLPK's integer solution.
std::vector<std::size_t> chosenSets(glp_prob* lp, const Model& m) {
  std::vector<std::size_t> sets;
  for (std::size_t j = 0; j < m.set_of_column.size(); ++j)
    if (glp_mip_col_val(lp, static_cast<int>(j) + 1) > 0.5) sets.push_back(m.set_of_column[j]);
  return sets;
}

// How the search ended, in words ("optimal" when no cheaper cover exists).
std::string searchStatus(int mip_ret,
                         int mip_status,
                         bool found_reaches,
                         const SearchContext& ctx) {
  if (mip_ret == 0 && mip_status == GLP_OPT && found_reaches) return "optimal";
  if (mip_ret == 0 && mip_status == GLP_OPT)
    return "GLPK's optimum misses the target (numerical tolerance)";
  if (mip_ret == GLP_ETMLIM || (mip_ret == GLP_ESTOP && ctx.deadline_hit)) return "time limit";
  if (mip_ret == GLP_ESTOP && ctx.node_limit_hit) return "node limit";
  return "GLPK stopped (code " + std::to_string(mip_ret) + ")";
}

// The search's context: the problem, the reduced model's columns and the start handed to GLPK.
SearchContext searchContext(const CoverProblem& problem,
                            const OpenProblem& open,
                            const Model& m,
                            const CoverLimits& limits) {
  SearchContext ctx;
  ctx.problem = &problem;
  ctx.open = &open;
  ctx.model = &m;
  ctx.column_of_set.assign(problem.cost.size(), SIZE_MAX);
  for (std::size_t j = 0; j < m.set_of_column.size(); ++j)
    ctx.column_of_set[m.set_of_column[j]] = j;
  ctx.node_limit = limits.node_limit;
  if (limits.poll) ctx.poll = &limits.poll;
  return ctx;
}

// `sets` pruned of sets the target does not need, with what they cover and cost.
Candidate makeCandidate(const CoverProblem& problem,
                        const OpenProblem& open,
                        std::vector<std::size_t> sets) {
  Candidate c;
  c.sets = prune(problem, open, std::move(sets));
  c.covered_open = coveredOpen(open, c.sets);
  c.cost = costOf(problem, c.sets);
  return c;
}

// The time left of a budget started at t0, in seconds.
double secondsLeft(Clock::time_point t0, double budget_s) {
  return budget_s - std::chrono::duration<double>(Clock::now() - t0).count();
}

// GLPK's branch and bound on the reduced model, from `best` (the start, handed over when it
// reaches the target): `best` becomes the cheapest cover found, `s` gets the proven lower bound,
// the nodes and whether `best` is optimal. Returns how the search ended.
std::string searchWithGlpk(const CoverProblem& problem,
                           const OpenProblem& open,
                           const Model& m,
                           const CoverLimits& limits,
                           Clock::time_point t0,
                           double time_budget_s,
                           Candidate& best,
                           CoverSolution& s) {
  // Declared before GLPK's objects: it outlives them.
  const GlpkEnvironment environment;
  if (!environment.ok()) return "start only: GLPK's environment could not be set up";
  const GlpkProblem lp = glpkModel(problem, open, m);

  // GLPK's own presolver stays off: with it, the callback sees the presolved problem, whose
  // columns are not ours, so the start could not be handed over. The reduction above does what
  // matters here (merged rows, dropped columns), and the LP relaxation is solved first, as
  // glp_intopt() without presolver requires.
  const TerminalOff quiet;  // glp_scale_prob() reports whatever msg_lev says
  glp_scale_prob(lp.get(), GLP_SF_AUTO);
  glp_smcp smcp;
  glp_init_smcp(&smcp);
  smcp.msg_lev = GLP_MSG_OFF;
  if (limits.poll) limits.poll();
  if (secondsLeft(t0, time_budget_s) <= 0.0) return "time limit";
  smcp.tm_lim = milliseconds(secondsLeft(t0, time_budget_s));
  const int lp_ret = glp_simplex(lp.get(), &smcp);
  if (lp_ret == GLP_ETMLIM) return "time limit";
  if (lp_ret != 0 || glp_get_status(lp.get()) != GLP_OPT)
    return "start only: GLPK's LP relaxation failed (code " + std::to_string(lp_ret) + ")";
  // The LP relaxation's optimum bounds the MIP's from below (the bound if the search makes no
  // progress); the tree's best bound replaces it when higher.
  s.lower_bound = glp_get_obj_val(lp.get());

  SearchContext ctx = searchContext(problem, open, m, limits);
  if (best.covered_open >= open.need) ctx.start = best.sets;
  glp_iocp iocp;
  glp_init_iocp(&iocp);
  iocp.msg_lev = GLP_MSG_OFF;
  iocp.presolve = GLP_OFF;
  iocp.cb_func = searchCallback;
  iocp.cb_info = &ctx;
  if (secondsLeft(t0, time_budget_s) <= 0.0) return "time limit";
  iocp.tm_lim = milliseconds(secondsLeft(t0, time_budget_s));
  if (time_budget_s < kNoDeadline_s)
    ctx.deadline = t0 + std::chrono::duration_cast<Clock::duration>(
                            std::chrono::duration<double>(time_budget_s));
  const int mip_ret = glp_intopt(lp.get(), &iocp);
  if (ctx.error) std::rethrow_exception(ctx.error);
  s.nodes = ctx.nodes;
  s.lower_bound = std::max(s.lower_bound, ctx.bound);

  const int mip_status = glp_mip_status(lp.get());
  bool found_reaches = false;
  if (mip_status == GLP_OPT || mip_status == GLP_FEAS) {
    // Checked on the original elements: the answer never rests on GLPK's tolerances.
    Candidate found = makeCandidate(problem, open, chosenSets(lp.get(), m));
    found_reaches = found.covered_open >= open.need;
    if (better(found, best, open.need)) best = std::move(found);
  }
  std::string status = searchStatus(mip_ret, mip_status, found_reaches, ctx);
  if (status == "optimal") {
    // No cheaper cover exists, and best costs no more than GLPK's optimum.
    s.optimal = true;
    s.lower_bound = best.cost;
  }
  return status;
}

}  // namespace

CoverSolution solveCover(const CoverProblem& problem,
                         const std::vector<std::size_t>& start,
                         double time_budget_s,
                         const CoverLimits& limits) {
  const auto t0 = Clock::now();
  if (!(time_budget_s >= 0.0))
    throw std::invalid_argument("solveCover: time budget " + std::to_string(time_budget_s) +
                                " s (expected ≥ 0)");
  const OpenProblem open = openProblem(problem);
  std::vector<std::size_t> start_sets = checkedStart(problem, start);

  CoverSolution s;
  s.counted = open.counted;
  s.required = open.required;
  const auto finish = [&](Candidate&& c, std::string status) {
    s.chosen = std::move(c.sets);
    s.cost = c.cost;
    s.covered_counted = open.precovered + c.covered_open;
    s.reached = c.covered_open >= open.need;
    s.status = std::move(status);
    if (!s.reached && s.status != "infeasible target") s.status += ": no cover found";
    s.lower_bound = std::min(s.lower_bound, s.cost);
    s.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    return s;
  };

  if (open.need == 0) {
    s.optimal = true;
    return finish(Candidate{}, "target met before any set");
  }
  Candidate best = makeCandidate(problem, open, std::move(start_sets));

  std::vector<std::size_t> all;
  for (std::size_t p = 0; p < open.covers.size(); ++p)
    if (!open.covers[p].empty()) all.push_back(p);
  if (coveredOpen(open, all) < open.need) return finish(std::move(best), "infeasible target");

  const Model m = reducedModel(open);
  s.model_sets = m.set_of_column.size();
  s.model_classes = m.columns_of_class.size();
  if (m.nonzeros > std::min<std::size_t>(limits.max_nonzeros, INT_MAX - 1))
    return finish(std::move(best), "start only: the reduced model has " +
                                       std::to_string(m.nonzeros) + " nonzeros, more than " +
                                       std::to_string(limits.max_nonzeros));
  std::string status = searchWithGlpk(problem, open, m, limits, t0, time_budget_s, best, s);
  return finish(std::move(best), std::move(status));
}

}  // namespace scanplan::scanner
