#include "cli/io/axis_stream.h"

#include <cmath>
#include <cstdlib>
#include <vector>

#include <fmt/format.h>

#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/trajectory.h>
#include <scanplan/kinematics/units.h>

namespace scanplan::cli {
namespace {

constexpr const char* kNames[8] = {"t_s",    "table_deg", "j1_deg", "j2_deg",
                                   "j3_deg", "j4_deg",    "j5_deg", "j6_deg"};

std::vector<std::string> splitCells(const std::string& line) {
  std::vector<std::string> cells(1);
  for (const char ch : line) {
    if (ch == ',') {
      cells.emplace_back();
    } else if (ch != ' ' && ch != '\t') {
      cells.back() += ch;
    }
  }
  return cells;
}

}  // namespace

AxisStreamReader::AxisStreamReader(std::istream& in, std::string source)
    : in_(&in), source_(std::move(source)) {}

// One line, bounded: a stream without newlines cannot grow memory without end.
bool AxisStreamReader::readLine(std::string& out) {
  out.clear();
  std::streambuf* buffer = in_->rdbuf();
  for (;;) {
    const int ch = buffer->sbumpc();
    if (ch == std::char_traits<char>::eof()) {
      ++line_;
      return !out.empty();
    }
    if (ch == '\n') break;
    if (out.size() >= kMaxLineBytes) {
      throw InputError(
          fmt::format("{}:{}: a line longer than {} bytes: expected CSV lines of "
                      "t_s,table_deg,j1_deg,…,j6_deg",
                      source_, line_ + 1, kMaxLineBytes));
    }
    out += static_cast<char>(ch);
  }
  ++line_;
  if (!out.empty() && out.back() == '\r') out.pop_back();
  return true;
}

void AxisStreamReader::readHeader(const std::string& line) {
  const std::vector<std::string> cells = splitCells(line);
  columns_needed_ = 0;
  for (int k = 0; k < 8; ++k) {
    column_of_[k] = -1;
    for (std::size_t c = 0; c < cells.size(); ++c) {
      if (cells[c] != kNames[k]) continue;
      if (column_of_[k] >= 0) {  // which one is meant? Neither is taken.
        throw InputError(
            fmt::format("{}:{}: the header has column {} twice, as columns {} and {}: expected "
                        "each of t_s,table_deg,j1_deg,…,j6_deg once",
                        source_, line_, kNames[k], column_of_[k] + 1, c + 1));
      }
      column_of_[k] = static_cast<int>(c);
    }
    if (column_of_[k] < 0) {
      throw InputError(
          fmt::format("{}:{}: the header has no column {}: expected the columns "
                      "t_s,table_deg,j1_deg,…,j6_deg (in any order; others ignored)",
                      source_, line_, kNames[k]));
    }
    columns_needed_ = std::max(columns_needed_, static_cast<std::size_t>(column_of_[k]) + 1);
  }
}

std::optional<kinematics::AxisSample> AxisStreamReader::next() {
  std::string line;
  while (readLine(line)) {
    const std::size_t start = line.find_first_not_of(" \t");
    if (start == std::string::npos || line[start] == '#') continue;
    if (!header_seen_ && !last_t_ && line.compare(start, 3, "t_s") == 0) {
      header_seen_ = true;
      readHeader(line);
      continue;
    }
    const std::vector<std::string> cells = splitCells(line);
    if (cells.size() < columns_needed_) {
      throw InputError(
          fmt::format("{}:{}: {} columns: expected at least {} "
                      "(t_s,table_deg,j1_deg,…,j6_deg)",
                      source_, line_, cells.size(), columns_needed_));
    }
    double v[8];
    for (int k = 0; k < 8; ++k) {
      const std::string& cell = cells[static_cast<std::size_t>(column_of_[k])];
      char* end = nullptr;
      v[k] = std::strtod(cell.c_str(), &end);
      const bool number = !cell.empty() && end == cell.c_str() + cell.size() && std::isfinite(v[k]);
      const double limit = k == 0 ? 1e9 : kinematics::kMaxTrajectoryAngleDeg;
      if (!number || std::abs(v[k]) > limit) {
        throw InputError(
            fmt::format("{}:{}: column {}: '{}': expected a finite number within ±{:g}", source_,
                        line_, kNames[k], clipForMessage(cell), limit));
      }
    }
    if (last_t_ && !(v[0] > *last_t_)) {
      throw InputError(
          fmt::format("{}:{}: column t_s: {} s is not after the previous line's {} s: "
                      "expected strictly increasing times",
                      source_, line_, cells[static_cast<std::size_t>(column_of_[0])], *last_t_));
    }
    last_t_ = v[0];
    kinematics::AxisSample s;
    s.t = v[0];
    s.theta = v[1] * kDegToRad;
    for (int j = 0; j < 6; ++j) s.q(j) = v[2 + j] * kDegToRad;
    return s;
  }
  return std::nullopt;
}

}  // namespace scanplan::cli
