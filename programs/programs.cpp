#include <scanplan/programs/programs.h>

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include <scanplan/kinematics/error.h>
#include <scanplan/programs/detail/program_text.h>

namespace scanplan::programs {

using kinematics::Trajectory;
using kinematics::TrajectorySample;

namespace {

void checkTrajectory(const Trajectory& trajectory, const std::string& what) {
  const auto fail = [&](std::size_t k, const std::string& why) {
    throw InputError(what + ": sample " + std::to_string(k) + ": " + why);
  };
  if (trajectory.samples.empty()) {
    throw InputError(what + ": the trajectory has no samples: expected at least one");
  }
  for (std::size_t k = 0; k < trajectory.samples.size(); ++k) {
    const TrajectorySample& s = trajectory.samples[k];
    if (!std::isfinite(s.t) || !std::isfinite(s.theta) || !s.q.allFinite()) {
      fail(k, "t, table angle and joints must be finite");
    }
    if (k > 0 && !(s.t > trajectory.samples[k - 1].t)) {
      fail(k, "t = " + detail::fixed(s.t, detail::kDecimals) +
                  " s is not after the previous sample's " +
                  detail::fixed(trajectory.samples[k - 1].t, detail::kDecimals) +
                  " s: expected strictly increasing times");
    }
  }
}

void checkOptions(const ProgramOptions& o) {
  if (!(o.approach_speed_percent > 0.0 && o.approach_speed_percent <= 100.0)) {
    throw InputError(
        fmt::format("program: approach speed {} %: expected (0, 100]", o.approach_speed_percent));
  }
  if (o.vplus_table_start_signal < 0 || o.vplus_table_start_signal > 4096) {
    throw InputError(fmt::format("program: V+ table start signal {}: expected 0 (none) ... 4096",
                                 o.vplus_table_start_signal));
  }
  if (o.trigger.output < 0 || o.trigger.output > 4096) {
    throw InputError(
        fmt::format("program: trigger output {}: expected 0 (none) ... 4096", o.trigger.output));
  }
  if (!o.tool.matrix().allFinite() || !std::isfinite(o.payload_kg) || !o.payload_cog.allFinite()) {
    throw InputError("program: the tool and the payload must be finite");
  }
  if (!(o.servo_period >= 0.001 && o.servo_period <= 0.1)) {
    throw InputError(
        fmt::format("program: servo period {} s: expected 0.001 ... 0.1 s", o.servo_period));
  }
}

// The program's identifier in each language.
// The files of a program named `n` (as its language makes it) in `format`, the program first.
std::vector<std::string> filesOf(ProgramFormat format, const std::string& n) {
  switch (format) {
    case ProgramFormat::kCsv:
      return {n + ".csv"};
    case ProgramFormat::kVplus:
      return {n + ".v2", n + "_table.csv"};
    case ProgramFormat::kKrl:
      return {n + ".src"};
    case ProgramFormat::kRapid:
      return {n + ".mod"};
    case ProgramFormat::kUrscript:
      return {n + ".script"};
  }
  return {};
}

std::string programName(ProgramFormat format, const std::string& name) {
  switch (format) {
    case ProgramFormat::kVplus:
      return detail::lower(detail::identifier(name, true, 15));
    case ProgramFormat::kKrl:
      return detail::identifier(name, false, 24);
    case ProgramFormat::kRapid: {
      const std::string id = detail::identifier(name, false, 28);
      return detail::lower(id) == "main" ? id + "_scan" : id;  // main() calls it
    }
    case ProgramFormat::kCsv:
    case ProgramFormat::kUrscript:
      break;
  }
  return detail::identifier(name, false, 64);
}

}  // namespace

const std::vector<std::string>& programFormatNames() {
  static const std::vector<std::string> names = {"csv", "vplus", "krl", "rapid", "urscript"};
  return names;
}

std::string programFormatName(ProgramFormat format) {
  return programFormatNames()[static_cast<std::size_t>(format)];
}

std::optional<ProgramFormat> parseProgramFormat(const std::string& name) {
  const auto& names = programFormatNames();
  const auto it = std::find(names.begin(), names.end(), detail::lower(name));
  if (it == names.end()) return std::nullopt;
  return static_cast<ProgramFormat>(it - names.begin());
}

std::optional<ProgramFormat> programFormatOfFile(const std::string& file_name) {
  const std::string name = detail::lower(file_name);
  const auto ends = [&](const std::string& ext) { return name.ends_with(ext); };
  if (ends(".v2")) return ProgramFormat::kVplus;
  if (ends(".src")) return ProgramFormat::kKrl;
  if (ends(".mod")) return ProgramFormat::kRapid;
  if (ends(".script")) return ProgramFormat::kUrscript;
  if (ends(".csv")) return ProgramFormat::kCsv;
  return std::nullopt;
}

std::vector<std::string> programFileNames(const std::string& name) {
  std::vector<std::string> out;
  for (const ProgramFormat f : {ProgramFormat::kCsv, ProgramFormat::kVplus, ProgramFormat::kKrl,
                                ProgramFormat::kRapid, ProgramFormat::kUrscript}) {
    const std::vector<std::string> files = filesOf(f, programName(f, name));
    out.insert(out.end(), files.begin(), files.end());
  }
  return out;
}

ProgramFiles writeProgram(const Trajectory& trajectory,
                          const kinematics::RobotModel& robot,
                          ProgramFormat format,
                          const ProgramOptions& options) {
  checkTrajectory(trajectory, programFormatName(format) + " program");
  checkOptions(options);
  detail::ProgramContext c{trajectory,
                           robot,
                           options,
                           detail::steps(trajectory, robot, options),
                           0,
                           detail::triggerSwitches(trajectory, options.trigger),
                           detail::writtenTable(trajectory, options.table_endless),
                           programName(format, options.name)};
  ProgramFiles result;
  for (const detail::Step& s : c.step) {
    result.max_speed_percent = std::max(result.max_speed_percent, s.percent);
    if (s.over_speed) ++result.over_speed_segments;
  }
  c.over_speed = result.over_speed_segments;
  const std::vector<std::string> files = filesOf(format, c.name);
  switch (format) {
    case ProgramFormat::kCsv:
      result.files.emplace_back(files[0], kinematics::trajectoryToCsv(trajectory));
      break;
    case ProgramFormat::kVplus: {
      result.files.emplace_back(files[0], detail::vplusProgram(c, files[1]));
      result.files.emplace_back(files[1], detail::vplusTable(c));
      break;
    }
    case ProgramFormat::kKrl:
      result.files.emplace_back(files[0], detail::krlProgram(c));
      break;
    case ProgramFormat::kRapid:
      result.files.emplace_back(files[0], detail::rapidProgram(c));
      break;
    case ProgramFormat::kUrscript:
      result.files.emplace_back(files[0], detail::urscriptProgram(c));
      break;
  }
  for (auto& file : result.files) file.second = detail::asciiText(file.second);
  return result;
}

ProgramReading readProgram(const std::string& text,
                           ProgramFormat format,
                           const std::string& source,
                           const kinematics::RobotModel* robot) {
  switch (format) {
    case ProgramFormat::kVplus:
      return detail::readVplus(text, source, robot);
    case ProgramFormat::kKrl:
      return detail::readKrl(text, source);
    case ProgramFormat::kRapid:
      return detail::readRapid(text, source);
    case ProgramFormat::kUrscript:
      return detail::readUrscript(text, source);
    case ProgramFormat::kCsv:
      break;
  }
  ProgramReading reading;
  reading.trajectory = kinematics::parseTrajectoryCsv(text, source);
  return reading;
}

Trajectory atStepTimes(const ProgramReading& reading) {
  const auto& read = reading.trajectory.samples;
  if (!reading.servo_steps || read.size() < 2 || reading.step_times.empty()) {
    return reading.trajectory;
  }
  Trajectory out;
  std::size_t i = 0;
  for (const double t : reading.step_times) {
    while (i + 2 < read.size() && read[i + 1].t < t) ++i;
    const TrajectorySample &a = read[i], &b = read[i + 1];
    const double w = std::clamp((t - a.t) / (b.t - a.t), 0.0, 1.0);
    TrajectorySample s = w < 1.0 ? a : b;
    s.t = t;
    s.q = a.q + w * (b.q - a.q);
    s.theta = a.theta + w * (b.theta - a.theta);
    if (!out.samples.empty() && !(t > out.samples.back().t)) continue;
    out.samples.push_back(s);
  }
  return out;
}

Trajectory readVplusProgram(const std::string& text,
                            const std::string& source,
                            const kinematics::RobotModel* robot) {
  return detail::readVplus(text, source, robot).trajectory;
}

}  // namespace scanplan::programs
