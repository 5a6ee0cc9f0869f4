// Cutting chosen passes to what the cover needs of them (scanner::cutToCover, trimmedPass): on
// synthetic passes whose every stretch's coverage is known, every counting sample the chosen
// passes covered is still seen by a kept stretch that truly sees it, and the time only drops.
#include <algorithm>
#include <cstdint>
#include <map>
#include <random>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include <scanplan/scanner/pass_selection.h>
#include <scanplan/scanner/scan_passes.h>

namespace {

using scanplan::scanner::CutPasses;
using scanplan::scanner::cutToCover;
using scanplan::scanner::ScanPass;

// A pass of `seen.size()` stretches whose stretch k sees the samples seen[k] and takes dt[k] s.
// Key k sits at x = k, y = `id`, so a piece tells which pass and stretches it kept.
struct Synthetic {
  std::vector<std::set<std::uint32_t>> seen;
  std::vector<double> dt;
};

ScanPass makePass(const Synthetic& s, int id) {
  ScanPass p;
  const std::size_t n = s.seen.size();
  p.t.push_back(0.0);
  for (std::size_t k = 0; k <= n; ++k) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Eigen::Vector3d(static_cast<double>(k), id, 0.0);
    p.X_RS.push_back(X);
    if (k < n) p.t.push_back(p.t.back() + s.dt[k]);
  }
  std::map<std::uint32_t, std::pair<std::uint32_t, std::uint32_t>> range;
  for (std::uint32_t k = 0; k < n; ++k)
    for (const std::uint32_t i : s.seen[k]) {
      auto [it, fresh] = range.insert({i, {k, k}});
      if (!fresh) it->second.second = k;
    }
  for (const auto& [i, fl] : range) {
    p.covers.push_back(i);
    p.cover_first.push_back(fl.first);
    p.cover_last.push_back(fl.second);
  }
  return p;
}

// The samples a piece truly sees: its kept stretches of the pass it came from.
std::set<std::uint32_t> trulySeen(const ScanPass& piece, const std::vector<Synthetic>& all) {
  const auto id = static_cast<std::size_t>(piece.X_RS.front().translation().y());
  const auto a = static_cast<std::size_t>(piece.X_RS.front().translation().x());
  std::set<std::uint32_t> out;
  for (std::size_t k = a; k + 1 < a + piece.X_RS.size(); ++k)
    out.insert(all[id].seen[k].begin(), all[id].seen[k].end());
  return out;
}

// Two passes over samples 0…9: A sees sample k on its stretch k (1 s each), B sees 0…4 in 2 s.
// A, the longer, is cut first to the stretches of 5…9 that only it sees; B then stays whole.
TEST(CutToCover, TheLongerPassGivesUpWhatTheShorterAlsoSees) {
  Synthetic a, b;
  for (std::uint32_t k = 0; k < 10; ++k) {
    a.seen.push_back({k});
    a.dt.push_back(1.0);
  }
  b.seen = {{0, 1, 2}, {3, 4}};
  b.dt = {1.0, 1.0};
  const std::vector<ScanPass> passes{makePass(a, 0), makePass(b, 1)};
  const std::vector<std::uint8_t> counts(10, 1), covered(10, 0);
  const CutPasses cut = cutToCover(passes, {0, 1}, counts, covered, 100.0, 0);
  ASSERT_EQ(cut.passes.size(), 2u);
  EXPECT_EQ(cut.from, (std::vector<std::size_t>{0, 1}));
  EXPECT_DOUBLE_EQ(cut.passes[0].duration(), 5.0);
  EXPECT_DOUBLE_EQ(cut.passes[0].X_RS.front().translation().x(), 5.0);
  EXPECT_DOUBLE_EQ(cut.passes[1].duration(), 2.0);
  EXPECT_DOUBLE_EQ(cut.cut_time, 5.0);
  EXPECT_EQ(cut.dropped, 0u);
  EXPECT_EQ(cut.split, 0u);
  // Padded by 0.25 s either side where the pass runs on: a key a quarter of the way back into
  // stretch 4, none after its end.
  const CutPasses padded = cutToCover(passes, {0, 1}, counts, covered, 100.0, 0.25);
  EXPECT_DOUBLE_EQ(padded.passes[0].X_RS.front().translation().x(), 4.75);
  EXPECT_DOUBLE_EQ(padded.passes[0].X_RS[1].translation().x(), 5.0);
  EXPECT_DOUBLE_EQ(padded.passes[0].duration(), 5.25);
  EXPECT_DOUBLE_EQ(padded.passes[0].t.front(), 0.0);
}

// A pass needed only at both ends of a long stretch that adds nothing is split in two when the
// stretch takes longer than the gap, and kept whole (cut to its ends) when it does not; a pass
// that adds nothing at all is left out; samples that do not count or are covered already are not
// needed.
TEST(CutToCover, SplitsAtAGapWorthAMoveAndLeavesOutAPassThatAddsNothing) {
  Synthetic a, b;
  a.seen = {{9}, {0, 2}, {}, {}, {}, {}, {1}, {8}};
  a.dt.assign(8, 1.0);
  b.seen = {{2}, {}};  // shorter than A: A is cut first, keeps 2, and B adds nothing
  b.dt = {0.5, 0.5};
  const std::vector<ScanPass> passes{makePass(a, 0), makePass(b, 1)};
  std::vector<std::uint8_t> counts(10, 1), covered(10, 0);
  counts[9] = 0;   // stretch 0 of A: does not count
  covered[8] = 1;  // stretch 7 of A: covered already
  const CutPasses whole = cutToCover(passes, {0, 1}, counts, covered, 10.0, 0);
  ASSERT_EQ(whole.passes.size(), 1u);
  EXPECT_EQ(whole.from[0], 0u);
  EXPECT_DOUBLE_EQ(whole.passes[0].X_RS.front().translation().x(), 1.0);
  EXPECT_DOUBLE_EQ(whole.passes[0].duration(), 6.0);
  EXPECT_EQ(whole.dropped, 1u);
  const CutPasses split = cutToCover(passes, {0, 1}, counts, covered, 3.0, 0);
  ASSERT_EQ(split.passes.size(), 2u);
  EXPECT_EQ(split.split, 1u);
  EXPECT_DOUBLE_EQ(split.passes[0].duration() + split.passes[1].duration(), 2.0);
  EXPECT_DOUBLE_EQ(split.cut_time, 7.0);
}

// A sample seen at both ends of a pass and nowhere between (a spin's seam, a helix's
// neighbouring turns) keeps one of those ends, never only the stretches between.
TEST(CutToCover, ASampleSeenAtBothEndsKeepsAnEndThatSeesIt) {
  Synthetic a;
  a.seen = {{0}, {1}, {1}, {1}, {0}};
  a.dt.assign(5, 1.0);
  const std::vector<ScanPass> passes{makePass(a, 0)};
  const CutPasses cut = cutToCover(passes, {0}, {1, 1}, {0, 0}, 100.0, 0);
  ASSERT_EQ(cut.passes.size(), 1u);
  const std::set<std::uint32_t> seen = trulySeen(cut.passes[0], {a});
  EXPECT_TRUE(seen.count(0) && seen.count(1));
  EXPECT_DOUBLE_EQ(cut.passes[0].duration(), 2.0);
}

// Random passes: whatever is cut and split, every counting sample the chosen passes saw is seen
// by a kept stretch, no piece is longer than its pass, and the time left out adds up.
TEST(CutToCover, RandomPassesKeepEveryCountingSampleTheyCovered) {
  std::mt19937 rng(7);
  const auto draw = [&](std::uint32_t n) { return static_cast<std::uint32_t>(rng() % n); };
  for (int trial = 0; trial < 200; ++trial) {
    const std::uint32_t samples = 60;
    std::vector<Synthetic> all(2 + rng() % 8);
    std::vector<ScanPass> passes;
    for (std::size_t id = 0; id < all.size(); ++id) {
      const std::size_t n = 1 + rng() % 30;
      for (std::size_t k = 0; k < n; ++k) {
        std::set<std::uint32_t> s;
        for (std::uint32_t j = draw(4); j > 0; --j) s.insert(draw(samples));
        all[id].seen.push_back(s);
        all[id].dt.push_back(0.1 + draw(100) / 50.0);
      }
      passes.push_back(makePass(all[id], static_cast<int>(id)));
    }
    std::vector<std::uint8_t> counts(samples), covered(samples);
    for (std::uint32_t i = 0; i < samples; ++i) {
      counts[i] = rng() % 5 != 0;
      covered[i] = rng() % 7 == 0;
    }
    std::vector<std::size_t> chosen(all.size());
    for (std::size_t k = 0; k < chosen.size(); ++k) chosen[k] = k;
    const CutPasses cut = cutToCover(passes, chosen, counts, covered, 1.0 + trial % 5, 0.0);
    std::set<std::uint32_t> before, after;
    for (const ScanPass& p : passes) before.insert(p.covers.begin(), p.covers.end());
    double total = 0.0, kept = 0.0;
    for (const ScanPass& p : passes) total += p.duration();
    for (std::size_t k = 0; k < cut.passes.size(); ++k) {
      const std::set<std::uint32_t> seen = trulySeen(cut.passes[k], all);
      after.insert(seen.begin(), seen.end());
      EXPECT_LE(cut.passes[k].duration(), passes[cut.from[k]].duration() + 1e-12);
      kept += cut.passes[k].duration();
      for (const std::uint32_t i : cut.passes[k].covers) EXPECT_TRUE(seen.count(i)) << trial;
    }
    for (const std::uint32_t i : before) {
      if (counts[i] && !covered[i]) {
        EXPECT_TRUE(after.count(i)) << "trial " << trial << ", sample " << i;
      }
    }
    EXPECT_NEAR(total - kept, cut.cut_time, 1e-9);
  }
}

}  // namespace
