#pragma once

#include <cstddef>
#include <istream>
#include <optional>
#include <string>

#include <scanplan/kinematics/motion_model.h>

namespace scanplan::cli {

/// Measured axis positions, one CSV line at a time, from a log file or a live pipe (`watch`).
/// Columns: `t_s,table_deg,j1_deg,…,j6_deg`, in that order without a header, or named by a
/// header line (other columns are ignored, so plan's trajectory.csv reads as it is). Lines
/// starting with # and blank lines are skipped. Errors (InputError) name the source, the line,
/// the column and the value: a line longer than kMaxLineBytes, a missing column, one of the
/// eight named twice (with both positions), a non-number, a value beyond
/// kinematics::kMaxTrajectoryAngleDeg, a time not after the previous one.
class AxisStreamReader {
 public:
  static constexpr std::size_t kMaxLineBytes = 64 * 1024;

  AxisStreamReader(std::istream& in, std::string source);

  /// The next sample; std::nullopt at the end of the stream. Blocks on a pipe until a line comes.
  std::optional<kinematics::AxisSample> next();

  std::size_t line() const { return line_; }

 private:
  bool readLine(std::string& out);
  void readHeader(const std::string& line);

  std::istream* in_;
  std::string source_;
  std::size_t line_ = 0;
  bool header_seen_ = false;
  std::size_t columns_needed_ = 8;
  int column_of_[8] = {0, 1, 2, 3, 4, 5, 6, 7};  ///< t, table, j1…j6 → CSV column
  std::optional<double> last_t_;
};

}  // namespace scanplan::cli
