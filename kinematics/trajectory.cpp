#include <scanplan/kinematics/trajectory.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <sstream>

#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/units.h>

namespace scanplan::kinematics {

namespace {

constexpr const char* kColumns[] = {"t_s",    "table_deg", "j1_deg", "j2_deg",   "j3_deg", "j4_deg",
                                    "j5_deg", "j6_deg",    "f",      "scanning", "px_mm",  "py_mm",
                                    "pz_mm",  "qw",        "qx",     "qy",       "qz",     "limit"};
constexpr std::size_t kNumeric = 17;  // every column but `limit`

// Appends v as printf's "%.12g" writes it (std::to_chars is specified to give those characters,
// without printf's parsing of a format and its locale), "nan" for NaN, no "-0".
void appendNumber(std::string& out, double v) {
  if (std::isnan(v)) {
    out += "nan";
    return;
  }
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, v == 0.0 ? 0.0 : v,
                                 std::chars_format::general, 12)
                       .ptr;
  out.append(buffer, end);
}

std::string number(double v) {
  std::string out;
  appendNumber(out, v);
  return out;
}

std::vector<std::string> splitCells(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::stringstream row(line);
  while (std::getline(row, cell, ',')) {
    const auto b = cell.find_first_not_of(" \t");
    const auto e = cell.find_last_not_of(" \t");
    cells.push_back(b == std::string::npos ? std::string() : cell.substr(b, e - b + 1));
  }
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

// Angles (table, joints) within ±kMaxTrajectoryAngleDeg, positions within
// ±kMaxTrajectoryLengthMm; `fail` reports the column and the value.
template <class Fail>
void checkMagnitude(std::size_t column, double value, const Fail& fail) {
  const bool angle = column >= 1 && column <= 7;
  const bool length = column >= 10 && column <= 12;
  const double cap = angle ? kMaxTrajectoryAngleDeg : kMaxTrajectoryLengthMm;
  if ((angle || length) && std::abs(value) > cap) {
    fail("column " + std::string(kColumns[column]) + ": " + number(value) + ": expected " +
         (angle ? "an angle" : "a position") + " within ±" + number(cap) +
         (angle ? " deg" : " mm"));
  }
}

std::string header(std::size_t columns) {
  std::string h;
  for (std::size_t i = 0; i < columns; ++i) h += (i ? "," : "") + std::string(kColumns[i]);
  return h;
}

// The number of columns a header line names: all of kColumns, or all but `limit`, in order.
// A name given twice is reported with both its positions (which of the two is meant?).
template <class Fail>
std::size_t headerColumns(const std::string& line,
                          const std::vector<std::string>& cells,
                          const Fail& fail) {
  for (const std::size_t n : {std::size(kColumns), kNumeric}) {
    if (line == header(n)) return n;
  }
  std::map<std::string, std::size_t> first;  // name → its first column, from 1
  for (std::size_t c = 0; c < cells.size(); ++c) {
    const auto [at, fresh] = first.emplace(cells[c], c + 1);
    if (!fresh && !cells[c].empty()) {
      fail("header: column '" + clipForMessage(cells[c]) + "' twice, as columns " +
           std::to_string(at->second) + " and " + std::to_string(c + 1) +
           ": expected each column once, as in '" + header(std::size(kColumns)) + "'");
    }
  }
  fail("header '" + clipForMessage(line) + "': expected '" + header(std::size(kColumns)) +
       "' (the limit column may be left out)");
  return 0;
}

}  // namespace

std::string trajectoryToCsv(const Trajectory& trajectory) {
  std::string out = header(std::size(kColumns)) + "\n";
  out.reserve(out.size() + 240 * trajectory.samples.size());
  const auto field = [&out](double v) {
    out += ',';
    appendNumber(out, v);
  };
  for (const TrajectorySample& s : trajectory.samples) {
    Eigen::Quaterniond q(s.X_PS.linear());
    q.normalize();
    if (q.w() < 0.0) q.coeffs() *= -1.0;
    const Eigen::Vector3d p = s.X_PS.translation() * kMToMm;
    appendNumber(out, s.t);
    field(s.theta * kRadToDeg);
    for (int j = 0; j < kNumJoints; ++j) field(s.q(j) * kRadToDeg);
    field(s.f);
    out += s.scanning ? ",1" : ",0";
    for (const double v : {p.x(), p.y(), p.z(), q.w(), q.x(), q.y(), q.z()}) field(v);
    out += ',';
    for (const char c : s.limit) out += c == ',' ? ';' : c;  // keep the row's column count
    out += '\n';
  }
  return out;
}

Trajectory parseTrajectoryCsv(const std::string& text, const std::string& source) {
  Trajectory trajectory;
  std::istringstream in(text);
  std::string line;
  int number_of_line = 0;
  std::size_t columns = 0;  // from the header: 17 or 18
  const auto fail = [&](const std::string& what) {
    throw InputError(source + ":" + std::to_string(number_of_line) + ": " + what);
  };
  while (std::getline(in, line)) {
    ++number_of_line;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos || line[0] == '#') continue;
    const std::vector<std::string> cells = splitCells(line);
    if (columns == 0) {
      columns = headerColumns(line, cells, fail);
      continue;
    }
    if (cells.size() != columns) {
      fail(std::to_string(cells.size()) + " columns: expected " + std::to_string(columns) + " (" +
           header(columns) + ")");
    }
    double v[kNumeric];
    for (std::size_t c = 0; c < kNumeric; ++c) {
      const std::string& cell = cells[c];
      const bool unknown_f = c == 8 && (cell.empty() || cell == "nan" || cell == "NaN");
      if (unknown_f) {
        v[c] = std::numeric_limits<double>::quiet_NaN();
        continue;
      }
      char* end = nullptr;
      v[c] = std::strtod(cell.c_str(), &end);
      if (cell.empty() || end != cell.c_str() + cell.size() || !std::isfinite(v[c])) {
        fail("column " + std::string(kColumns[c]) + ": '" + clipForMessage(cell) +
             "' is not a finite number" + (c == 8 ? " (or empty / nan for unknown)" : ""));
      }
      checkMagnitude(c, v[c], fail);
    }
    TrajectorySample s;
    s.t = v[0];
    if (!trajectory.samples.empty() && !(s.t > trajectory.samples.back().t)) {
      fail("column t_s: " + cells[0] + " s is not after the previous sample's " +
           number(trajectory.samples.back().t) + " s: expected strictly increasing times");
    }
    s.theta = v[1] * kDegToRad;
    for (int j = 0; j < kNumJoints; ++j) s.q(j) = v[2 + j] * kDegToRad;
    s.f = v[8];
    if (v[9] != 0.0 && v[9] != 1.0) fail("column scanning: '" + cells[9] + "': expected 0 or 1");
    s.scanning = v[9] == 1.0;
    const Eigen::Quaterniond q(v[13], v[14], v[15], v[16]);
    if (std::abs(q.norm() - 1.0) > 1e-6) {
      fail("columns qw,qx,qy,qz: quaternion norm " + number(q.norm()) +
           ": expected a unit quaternion (within 1e-6)");
    }
    s.X_PS.linear() = q.normalized().toRotationMatrix();
    s.X_PS.translation() = Eigen::Vector3d(v[10], v[11], v[12]) * kMmToM;
    if (columns == std::size(kColumns)) s.limit = cells[kNumeric];
    trajectory.samples.push_back(std::move(s));
  }
  if (columns == 0) fail("empty file: expected the header '" + header(std::size(kColumns)) + "'");
  if (trajectory.samples.empty()) fail("no samples after the header");
  return trajectory;
}

}  // namespace scanplan::kinematics
