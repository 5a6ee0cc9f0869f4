// The program readers: each language's moves, timed by its own timing model, with the tool,
// payload and trigger switches it sets (programs.h, readProgram).
#include <algorithm>
#include <cmath>
#include <optional>
#include <regex>
#include <sstream>

#include <fmt/format.h>

#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/programs/detail/program_text.h>

namespace scanplan::programs::detail {

namespace {

using kinematics::kNumJoints;
using kinematics::RobotModel;

const std::string kNum = R"([-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?)";

// A step comment waiting for its move.
struct PendingStep {
  double t = 0.0, table_deg = 0.0;
  bool scanning = false;
  int line = 0;
};

// What every reader keeps: the reading, the pending step comment, the trigger switches.
class ReaderState {
 public:
  ReaderState(const std::string& text, const std::string& source) : in(text, source) {}

  LineReader in;
  ProgramReading reading;
  std::optional<PendingStep> pending;

  // A comment: a step comment becomes the pending step.
  void comment(const std::string& body) {
    PendingStep p;
    if (!readStepComment(in, body, p.t, p.table_deg, p.scanning)) return;
    if (pending) {
      in.fail("step comment after the one on line " + std::to_string(pending->line) +
              ", which has no move: expected one move per step comment");
    }
    p.line = in.lineNumber();
    pending = p;
    reading.step_times.push_back(p.t);
  }
  PendingStep takeStep(const std::string& move) {
    if (!pending) {
      in.fail(move +
              " without its step comment: expected 't=<s> s table=<deg> deg scan=<0|1>' "
              "before it");
    }
    const PendingStep p = *pending;
    pending.reset();
    return p;
  }
  double lastTime() const {
    const auto& s = reading.trajectory.samples;
    return s.empty() ? (pending ? pending->t : 0.0) : s.back().t;
  }
  // Appends the move timed at t; its step comment's time must agree (to the printed precision,
  // accumulated over the steps): an edited time or a comment moved to another step is refused.
  void append(double t, const std::vector<double>& q_deg, double table_deg, const PendingStep& p) {
    const double tol = 1e-6 * static_cast<double>(reading.trajectory.samples.size() + 1);
    if (std::abs(t - p.t) > tol) {
      in.fail(
          fmt::format("the program's timing puts this move at t = {} s, its step comment (line "
                      "{}) at {} s: expected the same time (re-export rather than edit)",
                      fixed(t, kDecimals), p.line, fixed(p.t, kDecimals)));
    }
    appendSample(in, reading.trajectory, t, q_deg, table_deg, p.scanning);
  }
  void addSwitch(double t, int output, bool on) { reading.triggers.push_back({t, output, on}); }
  ProgramReading finish() {
    if (reading.trajectory.samples.empty()) in.fail("no moves in the program");
    return std::move(reading);
  }
};

bool isTrue(const std::string& word) {
  const std::string w = upper(word);
  return w == "TRUE" || w == "1";
}

// A V+ SPEED setting: percent of the joints' top speeds, and its line (0: the default, 100).
struct VplusSpeed {
  double percent = 100.0;
  int line = 0;
  bool always = false;
};

// ---------------------------------------------------------------------------------------------
// V+: MOVE #PPOINT per step, DURATION its time; SIGNAL runs as the move before it starts.
class VplusReader {
 public:
  VplusReader(const std::string& text, const std::string& source, const RobotModel* robot)
      : r_(text, source), robot_(robot) {}

  ProgramReading read() {
    std::string line;
    while (!ended_ && r_.in.next(line)) {
      if (line.empty()) continue;
      if (line[0] == ';') {
        if (!in_program_ && trim(line.substr(1)).rfind("t=", 0) == 0) {
          r_.in.fail("step comment before .PROGRAM");
        }
        r_.comment(line.substr(1));
      } else {
        instruction(line);
      }
    }
    if (!in_program_) r_.in.fail("no '.PROGRAM name()' line: expected a V+ program");
    if (r_.pending) r_.in.failAt(r_.pending->line, "step comment without its MOVE #PPOINT(...)");
    if (!ended_) r_.in.fail("the program has no .END");
    while (r_.in.next(line)) {  // another program would run only if called: nothing may follow
      if (!trim(line).empty() && line[0] != ';')
        r_.in.fail("'" + clipForMessage(line) + "' after .END: expected nothing after the program");
    }
    return r_.finish();
  }

 private:
  void instruction(const std::string& line) {
    static const std::regex kProgram(R"(\.PROGRAM\s+[A-Za-z][A-Za-z0-9._]*\s*\([^)]*\)\s*(;.*)?)",
                                     std::regex::icase);
    const std::string statement = trim(line.substr(0, line.find(';')));
    const std::string keyword = upper(statement.substr(0, statement.find_first_of(" \t(")));
    const std::string args = trim(statement.substr(keyword.size()));
    if (!in_program_) {
      if (keyword != ".PROGRAM" || !std::regex_match(line, kProgram)) {
        r_.in.fail("'" + clipForMessage(line) + "': expected '.PROGRAM name()' first");
      }
      in_program_ = true;
    } else if (keyword == ".END") {
      if (!args.empty()) r_.in.fail("'" + clipForMessage(line) + "': expected '.END'");
      ended_ = true;
    } else if (keyword == "MOVE") {
      move(line, statement);
    } else if (keyword == "SPEED" || keyword == "DURATION") {
      speed(line, keyword, args);
    } else if (keyword == "SIGNAL") {
      signal(line, args);
    } else if (keyword == "TOOL") {
      tool(line, args);
    } else if (keyword == "BREAK") {
      if (!args.empty()) r_.in.fail("'" + clipForMessage(line) + "': expected 'BREAK' alone");
      break_after_move_ = true;
      // After a timed move: the arm stops there, which only the last sample may do.
      if (r_.reading.trajectory.samples.size() >= 2 && !stop_line_) stop_line_ = r_.in.lineNumber();
    } else if (keyword == "LEFTY" || keyword == "RIGHTY" || keyword == "ABOVE" ||
               keyword == "BELOW" || keyword == "FLIP" || keyword == "NOFLIP") {
      if (!args.empty())
        r_.in.fail("'" + clipForMessage(line) + "': expected '" + keyword + "' alone");
    } else {
      r_.in.fail("'" + clipForMessage(line) +
                 "': not an instruction this reader knows (MOVE #PPOINT(...), SPEED, DURATION, "
                 "BREAK, SIGNAL, TOOL TRANS(...), LEFTY/RIGHTY, ABOVE/BELOW, FLIP/NOFLIP, .END)");
    }
  }

  // MOVE #PPOINT(j1, ..., j6) in degrees: timed by the DURATION before it (the first, untimed
  // move, and a move without DURATION: its step comment's time).
  void move(const std::string& line, const std::string& statement) {
    static const std::regex kMove(R"(MOVE\s+#PPOINT\s*\(([^)]*)\))", std::regex::icase);
    std::smatch m;
    if (!std::regex_match(statement, m, kMove)) {
      r_.in.fail("'" + clipForMessage(line) +
                 "': expected 'MOVE #PPOINT(j1, j2, j3, j4, j5, j6)' (degrees)");
    }
    const std::vector<double> q = numberList(r_.in, m[1].str(), kNumJoints, "MOVE #PPOINT joints");
    const PendingStep p = r_.takeStep("MOVE");
    const auto& samples = r_.reading.trajectory.samples;
    if (!samples.empty() && !duration_) {
      r_.in.fail(
          "MOVE without DURATION: expected 'DURATION <s>' (the step's time) before each "
          "MOVE after the first");
    }
    if (stop_line_) {
      r_.in.failAt(*stop_line_,
                   "BREAK between timed moves: the arm would stop here, where the plan moves on "
                   "without stopping (expected BREAK only after the first MOVE and the last)");
    }
    if (!samples.empty()) checkSpeed(q, next_speed_.value_or(always_speed_));
    const double t = samples.empty() ? p.t : samples.back().t + *duration_;
    r_.append(t, q, p.table_deg, p);
    duration_.reset();
    next_speed_.reset();
    break_after_move_ = false;
  }

  // A joint move takes the longer of its DURATION and its time at SPEED (percent of each joint's
  // top speed; a joint without one is not limited, as the writer assumes): longer than the
  // DURATION, the arm falls behind the table the plan times.
  void checkSpeed(const std::vector<double>& q_deg, const VplusSpeed& speed) {
    if (!robot_) return;
    const kinematics::JointVector& from = r_.reading.trajectory.samples.back().q;
    double at_speed = 0.0;
    int limiting = 0;
    for (int j = 0; j < kNumJoints; ++j) {
      const double v_max = robot_->joint(j).max_speed;
      if (!(v_max > 0.0)) continue;
      const double travel = std::abs(q_deg[static_cast<std::size_t>(j)] * kDegToRad - from(j));
      const double t = travel / (v_max * speed.percent / 100.0);
      if (t > at_speed) {
        at_speed = t;
        limiting = j;
      }
    }
    if (at_speed <= *duration_ * (1.0 + 1e-3) + 1e-6) return;
    const double needed = speed.percent * at_speed / *duration_;
    r_.in.fail(fmt::format(
        "SPEED {}{} makes this MOVE take {:.4f} s where its DURATION is {:.4f} s: the arm would "
        "fall behind the table, which the plan times ({})",
        speed.percent >= 0.01 ? fixed(speed.percent, 2) : fmt::format("{:g}", speed.percent),
        speedOrigin(speed), at_speed, *duration_,
        needed <= 100.0
            ? fmt::format("expected SPEED ≥ {:.2f}", needed)
            : fmt::format("the step needs {:.2f} % of joint {}'s top speed: re-plan it slower",
                          needed, limiting + 1)));
  }

  static std::string speedOrigin(const VplusSpeed& speed) {
    if (speed.line == 0) return " (the default: no SPEED before this MOVE)";
    return fmt::format("{} (line {})", speed.always ? " ALWAYS" : "", speed.line);
  }

  // SPEED or DURATION <value> [ALWAYS] (SPEED also in MMPS): DURATION times the next MOVE.
  void speed(const std::string& line, const std::string& keyword, const std::string& args) {
    std::istringstream words(args);
    std::string value, rest;
    words >> value;
    std::getline(words, rest);
    double v = 0.0;
    const std::string tail = upper(trim(rest));
    const bool units_ok = tail.empty() || tail == "ALWAYS" ||
                          (keyword == "SPEED" && (tail == "MMPS" || tail == "MMPS ALWAYS"));
    if (!parseNumber(value, v) || (keyword == "DURATION" && v < 0.0) || !units_ok) {
      r_.in.fail("'" + clipForMessage(line) + "': expected '" + keyword + " <value> [ALWAYS]'");
    }
    if (keyword == "DURATION") {
      if (!tail.empty()) {
        r_.in.fail("'" + clipForMessage(line) +
                   "': DURATION ... ALWAYS is not read: expected 'DURATION <s>' before each MOVE");
      }
      duration_ = v;
      return;
    }
    if (tail.rfind("MMPS", 0) == 0) {
      r_.in.fail("'" + clipForMessage(line) +
                 "': SPEED in mm/s applies to straight-line moves, which this reader does not "
                 "model: expected 'SPEED <percent>' for the joint moves");
    }
    if (!(v > 0.0 && v <= 100.0)) {
      r_.in.fail("'" + clipForMessage(line) +
                 "': expected SPEED in (0, 100] percent of the joints' top speeds");
    }
    // The latest setting times the next motion; ALWAYS also the ones after it.
    const VplusSpeed set{v, r_.in.lineNumber(), tail == "ALWAYS"};
    next_speed_ = set;
    if (set.always) always_speed_ = set;
  }

  // SIGNAL n[, -m ...]: at the start of the last MOVE, or at its end after a BREAK.
  void signal(const std::string& line, const std::string& args) {
    static const std::regex kList(R"([-+]?[0-9]{1,6}(\s*,\s*[-+]?[0-9]{1,6})*)");
    if (!std::regex_match(args, kList)) {
      r_.in.fail("'" + clipForMessage(line) + "': expected 'SIGNAL n[, m ...]'");
    }
    const auto& samples = r_.reading.trajectory.samples;
    double t = r_.lastTime();
    if (!break_after_move_ && samples.size() >= 2) t = samples[samples.size() - 2].t;
    std::stringstream cells(args);
    for (std::string cell; std::getline(cells, cell, ',');) {
      const int n = std::stoi(trim(cell));
      r_.addSwitch(t, std::abs(n), n > 0);
    }
  }

  // TOOL TRANS(x, y, z, yaw, pitch, roll): mm and degrees.
  void tool(const std::string& line, const std::string& args) {
    static const std::regex kTrans(R"(TRANS\s*\(([^)]*)\))", std::regex::icase);
    std::smatch m;
    if (!std::regex_match(args, m, kTrans)) {
      r_.in.fail("'" + clipForMessage(line) + "': expected 'TOOL TRANS(x, y, z, y, p, r)'");
    }
    const std::vector<double> v = numberList(r_.in, m[1].str(), 6, "TOOL TRANS");
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Eigen::Vector3d(v[0], v[1], v[2]) / 1000.0;
    X.linear() = fromVplusAngles(v[3], v[4], v[5]);
    r_.reading.tool = X;
  }

  ReaderState r_;
  const RobotModel* robot_;  // its joint speeds time SPEED; none: SPEED is read, not timed
  bool in_program_ = false, ended_ = false, break_after_move_ = false;
  std::optional<int> stop_line_;  // a BREAK after a timed move
  std::optional<double> duration_;
  VplusSpeed always_speed_;               // SPEED ... ALWAYS (monitor SPEED 100 assumed)
  std::optional<VplusSpeed> next_speed_;  // SPEED for the next motion only
};

// A KRL spline segment waiting for its block's TIME_BLOCK END.
struct KrlSegment {
  std::vector<double> q;
  double e1 = 0.0;
  PendingStep step;
  double part = 0.0;
  std::vector<std::pair<int, bool>> triggers;
};
struct KrlBlock {
  bool started = false, ended = false;
  std::vector<KrlSegment> segments;
};

// ---------------------------------------------------------------------------------------------
// KRL: the approach PTP, then PTP_SPLINE blocks of SPTP segments timed by TIME_BLOCK.
class KrlReader {
 public:
  KrlReader(const std::string& text, const std::string& source) : r_(text, source) {}

  ProgramReading read() {
    std::string line;
    while (!ended_ && r_.in.next(line)) {
      if (line.empty()) continue;
      if (line[0] == ';') {
        r_.comment(line.substr(1));
        continue;
      }
      const std::string statement = trim(line.substr(0, line.find(';')));
      if (!in_program_) {
        if (upper(statement).rfind("DEF ", 0) != 0) {
          r_.in.fail("'" + clipForMessage(line) + "': expected 'DEF name( )' first");
        }
        in_program_ = true;
        continue;
      }
      instruction(statement);
    }
    if (!in_program_) r_.in.fail("no 'DEF name( )' line: expected a KRL program");
    if (!ended_) r_.in.fail("the program has no END");
    if (block_) r_.in.fail("PTP_SPLINE without ENDSPLINE");
    velocityRoutine();
    return r_.finish();
  }

 private:
  void instruction(const std::string& s) {
    const std::string u = upper(s);
    if (u == "END") {
      ended_ = true;
    } else if (u.rfind("PTP {", 0) == 0 || u.rfind("PTP{", 0) == 0) {
      approach(s);
    } else if (u == "PTP_SPLINE") {
      if (block_) r_.in.fail("PTP_SPLINE inside another: expected ENDSPLINE first");
      if (velocity_ != std::pair{100, 100}) {
        r_.in.fail(fmt::format(
            "a timed PTP_SPLINE block after {}: TIME_BLOCK holds its times only at full axis "
            "velocity, expected SCANPLAN_VEL(100, 100) before it",
            velocity_ ? fmt::format("SCANPLAN_VEL({}, {})", velocity_->first, velocity_->second)
                      : std::string("no SCANPLAN_VEL")));
      }
      block_ = KrlBlock{};
    } else if (u.rfind("SPTP ", 0) == 0 || u.rfind("SPTP{", 0) == 0) {
      segment(s);
    } else if (u.rfind("TIME_BLOCK", 0) == 0) {
      timeBlock(s);
    } else if (u == "ENDSPLINE") {
      if (!block_ || !block_->ended)
        r_.in.fail("ENDSPLINE without a PTP_SPLINE and its TIME_BLOCK END");
      block_.reset();
    } else if (u.rfind("TRIGGER WHEN", 0) == 0) {
      trigger(s);
    } else if (u.rfind("$OUT[", 0) == 0) {
      const auto [n, on] = output(s);
      r_.addSwitch(r_.lastTime(), n, on);
    } else if (u.rfind("$TOOL", 0) == 0) {
      tool(s);
    } else if (u.rfind("$LOAD", 0) == 0) {
      load(s);
    } else if (u.rfind("SCANPLAN_VEL(", 0) == 0) {
      velocity(s);
    } else if (u.rfind("BAS(", 0) == 0) {
      if (!std::regex_match(u, std::regex(R"(BAS\s*\(\s*#INITMOV\s*,\s*0\s*\))")) ||
          !r_.reading.trajectory.samples.empty()) {
        r_.in.fail("'" + clipForMessage(s) +
                   "': BAS sets velocities and accelerations this reader does not model: "
                   "expected BAS(#INITMOV,0) alone, before the first motion");
      }
    } else if (u.rfind("$APO", 0) == 0 || u == "WAIT SEC 0") {
      // Settings that do not change the planned motion.
    } else {
      r_.in.fail(
          "'" + clipForMessage(s) +
          "': not an instruction this reader knows (PTP, PTP_SPLINE, SPTP, TIME_BLOCK, "
          "ENDSPLINE, TRIGGER WHEN, $OUT, $TOOL, $LOAD, BAS, SCANPLAN_VEL, WAIT SEC 0, END)");
    }
  }

  // SCANPLAN_VEL(arm %, E1 %): the axes' velocity limits the routine after END sets.
  void velocity(const std::string& s) {
    if (block_) {
      r_.in.fail("'" + clipForMessage(s) +
                 "' inside a PTP_SPLINE block: expected SCANPLAN_VEL before PTP_SPLINE");
    }
    static const std::regex kVel(R"(SCANPLAN_VEL\s*\(\s*([0-9]{1,3})\s*,\s*([0-9]{1,3})\s*\))",
                                 std::regex::icase);
    std::smatch m;
    const auto percent = [&](std::size_t i) { return std::stoi(m[i].str()); };
    if (!std::regex_match(s, m, kVel) || percent(1) < 1 || percent(1) > 100 || percent(2) < 1 ||
        percent(2) > 100) {
      r_.in.fail("'" + clipForMessage(s) + "': expected SCANPLAN_VEL(arm %, E1 %), each 1 ... 100");
    }
    velocity_ = std::pair{percent(1), percent(2)};
  }

  // After the program's END: the SCANPLAN_VEL routine as written (comments and blank lines
  // aside), and nothing else.
  void velocityRoutine() {
    std::vector<std::string> want;
    std::istringstream routine(krlVelocityRoutine());
    for (std::string line; std::getline(routine, line);) {
      line = trim(line);
      if (!line.empty() && line[0] != ';') want.push_back(line);
    }
    std::size_t i = 0;
    for (std::string line; r_.in.next(line);) {
      line = trim(line);
      if (line.empty() || line[0] == ';') continue;
      if (i >= want.size() || line != want[i]) {
        r_.in.fail(
            fmt::format("'{}' after the program's END: expected '{}' (the SCANPLAN_VEL "
                        "routine as scanplan writes it, which sets the axes' velocity)",
                        clipForMessage(line), i < want.size() ? want[i] : "nothing"));
      }
      ++i;
    }
    if (i < want.size())
      r_.in.fail("the SCANPLAN_VEL routine is missing or cut short: expected '" + want[i] + "'");
  }

  // {A1 v, ..., A6 v, E1 v} → joints (degrees) and E1.
  std::pair<std::vector<double>, double> axes(const std::string& s) {
    static const std::regex kAxis("([AE][1-6])\\s+(" + kNum + ")", std::regex::icase);
    const auto open = s.find('{'), close = s.find('}');
    if (open == std::string::npos || close == std::string::npos || close < open) {
      r_.in.fail("'" + clipForMessage(s) + "': expected {A1 .., A6 .., E1 ..} (degrees)");
    }
    std::vector<double> q(kNumJoints, std::nan(""));
    double e1 = std::nan("");
    const std::string body = s.substr(open + 1, close - open - 1);
    for (std::sregex_iterator it(body.begin(), body.end(), kAxis), end; it != end; ++it) {
      const std::string name = upper((*it)[1].str());
      const double v = std::strtod((*it)[2].str().c_str(), nullptr);
      if (name[0] == 'A') q[static_cast<std::size_t>(name[1] - '1')] = v;
      if (name == "E1") e1 = v;
    }
    for (const double v : q) {
      if (!std::isfinite(v)) r_.in.fail("'" + clipForMessage(s) + "': expected A1 ... A6 and E1");
    }
    if (!std::isfinite(e1)) r_.in.fail("'" + clipForMessage(s) + "': expected E1 (the table)");
    return {q, e1};
  }

  void approach(const std::string& s) {
    if (block_) r_.in.fail("PTP inside a PTP_SPLINE block: expected SPTP");
    if (!r_.reading.trajectory.samples.empty()) {
      r_.in.fail(
          "a PTP after the start: only the first motion, to the start, may be a PTP (TIME_BLOCK "
          "times the PTP_SPLINE blocks alone): expected SPTP segments in a timed block");
    }
    const auto [q, e1] = axes(s);
    const PendingStep p = r_.takeStep("PTP");
    r_.append(p.t, q, e1, p);
    fire(r_.reading.trajectory.samples.back().t);
  }

  void segment(const std::string& s) {
    if (!block_ || !block_->started || block_->ended) {
      r_.in.fail("SPTP outside a timed PTP_SPLINE block (between TIME_BLOCK START and END)");
    }
    const auto [q, e1] = axes(s);
    const PendingStep p = r_.takeStep("SPTP");
    block_->segments.push_back({q, e1, p, std::nan(""), trigger_});
    trigger_.clear();
  }

  void timeBlock(const std::string& s) {
    static const std::regex kPart("TIME_BLOCK\\s+(PART|END)\\s*=\\s*(" + kNum + ")",
                                  std::regex::icase);
    if (!block_ || block_->ended)
      r_.in.fail("TIME_BLOCK outside a PTP_SPLINE block, or after its END");
    if (upper(s) == "TIME_BLOCK START") {
      block_->started = true;
      return;
    }
    std::smatch m;
    if (!std::regex_match(s, m, kPart) || !block_->started) {
      r_.in.fail("'" + clipForMessage(s) + "': expected TIME_BLOCK START, PART=<%> or END=<s>");
    }
    const double v = std::strtod(m[2].str().c_str(), nullptr);
    if (!(v > 0.0) || !std::isfinite(v))
      r_.in.fail("'" + clipForMessage(s) + "': expected a positive value");
    if (upper(m[1].str()) == "PART") {
      if (block_->segments.empty() || !std::isnan(block_->segments.back().part)) {
        r_.in.fail("TIME_BLOCK PART without its SPTP segment");
      }
      block_->segments.back().part = v;
    } else {
      endBlock(v);
    }
  }

  // TIME_BLOCK END: each segment gets END · PART / ΣPART of the block's time.
  void endBlock(double total) {
    double sum = 0.0;
    for (const KrlSegment& g : block_->segments) {
      if (std::isnan(g.part)) r_.in.fail("TIME_BLOCK END: a segment has no TIME_BLOCK PART");
      sum += g.part;
    }
    if (block_->segments.empty()) r_.in.fail("TIME_BLOCK END: the block has no segments");
    double t = r_.lastTime(), acc = 0.0;
    for (const KrlSegment& g : block_->segments) {
      acc += g.part;
      r_.append(t + total * acc / sum, g.q, g.e1, g.step);
      for (const auto& [n, on] : g.triggers)
        r_.addSwitch(r_.reading.trajectory.samples.back().t, n, on);
    }
    block_->ended = true;
  }

  // TRIGGER WHEN PATH=0 (next SPTP's end) or DISTANCE=1 (next PTP's end) DELAY=0 DO $OUT[n]=..
  void trigger(const std::string& s) {
    static const std::regex kTrigger(
        R"(TRIGGER\s+WHEN\s+(PATH\s*=\s*0|DISTANCE\s*=\s*1)\s+DELAY\s*=\s*0\s+DO\s+(.*))",
        std::regex::icase);
    std::smatch m;
    if (!std::regex_match(s, m, kTrigger)) {
      r_.in.fail("'" + clipForMessage(s) +
                 "': expected 'TRIGGER WHEN PATH=0 DELAY=0 DO $OUT[n]=TRUE|FALSE' (or DISTANCE=1)");
    }
    trigger_.push_back(output(m[2].str()));
  }

  std::pair<int, bool> output(const std::string& s) {
    static const std::regex kOut(R"(\$OUT\[\s*([0-9]{1,6})\s*\]\s*=\s*(TRUE|FALSE))",
                                 std::regex::icase);
    std::smatch m;
    if (!std::regex_match(s, m, kOut))
      r_.in.fail("'" + clipForMessage(s) + "': expected $OUT[n]=TRUE|FALSE");
    return {std::stoi(m[1].str()), isTrue(m[2].str())};
  }

  void fire(double t) {
    for (const auto& [n, on] : trigger_) r_.addSwitch(t, n, on);
    trigger_.clear();
  }

  std::vector<double> frame(const std::string& s, const std::string& what) {
    static const std::regex kField("([XYZABC])\\s+(" + kNum + ")", std::regex::icase);
    std::vector<double> v(6, 0.0);
    std::vector<bool> seen(6, false);
    const std::string fields = "XYZABC";
    for (std::sregex_iterator it(s.begin(), s.end(), kField), end; it != end; ++it) {
      const auto i = fields.find(static_cast<char>(std::toupper((*it)[1].str()[0])));
      v[i] = std::strtod((*it)[2].str().c_str(), nullptr);
      seen[i] = true;
    }
    for (std::size_t i = 0; i < 3; ++i) {
      if (!seen[i]) r_.in.fail("'" + clipForMessage(s) + "': expected " + what + " with X, Y, Z");
    }
    return v;
  }

  void tool(const std::string& s) {
    const std::vector<double> v = frame(s, "$TOOL={X .., Y .., Z .., A .., B .., C ..}");
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Eigen::Vector3d(v[0], v[1], v[2]) / 1000.0;
    X.linear() = fromKrlAngles(v[3], v[4], v[5]);
    r_.reading.tool = X;
  }

  void load(const std::string& s) {
    const std::string u = upper(s);
    if (u.rfind("$LOAD.M", 0) == 0) {
      double m = 0.0;
      if (!parseNumber(s.substr(s.find('=') + 1), m) || m < 0.0) {
        r_.in.fail("'" + clipForMessage(s) + "': expected $LOAD.M=<kg>");
      }
      r_.reading.payload_kg = m;
    } else if (u.rfind("$LOAD.CM", 0) == 0) {
      const std::vector<double> v = frame(s, "$LOAD.CM={X .., Y .., Z ..}");
      r_.reading.payload_cog = Eigen::Vector3d(v[0], v[1], v[2]) / 1000.0;
    } else if (u.rfind("$LOAD.J", 0) != 0) {
      r_.in.fail("'" + clipForMessage(s) + "': expected $LOAD.M, $LOAD.CM or $LOAD.J");
    }
  }

  ReaderState r_;
  bool in_program_ = false, ended_ = false;
  std::optional<std::pair<int, int>> velocity_;  // the last SCANPLAN_VEL (arm %, E1 %)
  std::optional<KrlBlock> block_;
  std::vector<std::pair<int, bool>> trigger_;  // for the next motion's end
};

// ---------------------------------------------------------------------------------------------
// RAPID: MoveAbsJ \T:= per step; SetDO after the move that reaches its sample.
class RapidReader {
 public:
  RapidReader(const std::string& text, const std::string& source) : r_(text, source) {}

  ProgramReading read() {
    std::string line;
    while (r_.in.next(line)) {
      if (line.empty()) continue;
      if (line[0] == '!') {
        r_.comment(line.substr(1));
        continue;
      }
      instruction(line);
    }
    if (!module_) r_.in.fail("no 'MODULE name' line: expected a RAPID module");
    if (!ended_) r_.in.fail("the module has no ENDMODULE");
    checkCalls();
    return r_.finish();
  }

 private:
  void instruction(const std::string& s) {
    static const std::regex kCall(R"([A-Za-z][A-Za-z0-9_]*\s*;)");
    const std::string u = upper(s);
    if (!module_) {
      if (u.rfind("MODULE ", 0) != 0)
        r_.in.fail("'" + clipForMessage(s) + "': expected 'MODULE name' first");
      module_ = true;
    } else if (ended_) {
      r_.in.fail("'" + clipForMessage(s) + "': after ENDMODULE");
    } else if (u == "ENDMODULE") {
      ended_ = true;
    } else if (u.rfind("PROC ", 0) == 0) {
      if (!proc_.empty()) r_.in.fail("PROC inside PROC " + proc_ + ": expected ENDPROC first");
      proc_ = upper(trim(s.substr(5, s.find('(') - 5)));
      procs_.push_back(proc_);
    } else if (u == "ENDPROC") {
      if (proc_.empty()) r_.in.fail("ENDPROC without its PROC");
      proc_.clear();
    } else if (std::regex_match(s, kCall)) {
      // main() calls the scan procedure, and nothing else calls anything.
      if (proc_ != "MAIN") r_.in.fail("'" + clipForMessage(s) + "': a call outside PROC main()");
      calls_.emplace_back(upper(trim(s.substr(0, s.find(';')))), r_.in.lineNumber());
    } else if (u.rfind("MOVEABSJ ", 0) == 0) {
      requireScanProcedure(s);
      move(s);
    } else if (u.rfind("SETDO ", 0) == 0) {
      requireScanProcedure(s);
      setDo(s);
    } else if (u.rfind("PERS TOOLDATA ", 0) == 0) {
      toolData(s);
    } else {
      r_.in.fail("'" + clipForMessage(s) +
                 "': not an instruction this reader knows (MODULE, PROC, MoveAbsJ, SetDO, PERS "
                 "tooldata, ENDPROC, ENDMODULE)");
    }
  }

  // One run of the scan: main() calls, once, the one other procedure, which holds the motion.
  void checkCalls() {
    if (std::find(procs_.begin(), procs_.end(), "MAIN") == procs_.end()) {
      r_.in.fail("no PROC main(): expected main() calling the scan procedure once");
    }
    if (procs_.size() != 2) {
      r_.in.fail(
          fmt::format("{} procedures: expected two, main() and the scan procedure it "
                      "calls (the reader models one run of one scan)",
                      procs_.size()));
    }
    const std::string scan = procs_[0] == "MAIN" ? procs_[1] : procs_[0];
    if (calls_.empty()) r_.in.fail("PROC main() calls nothing: expected one call, '" + scan + ";'");
    if (calls_.size() > 1) {
      r_.in.failAt(calls_[1].second,
                   fmt::format("a second call in main() (the first is on line {}): expected one "
                               "call (a second run starts from wherever the first ended, which "
                               "no validation saw)",
                               calls_[0].second));
    }
    if (calls_[0].first != scan) {
      r_.in.failAt(calls_[0].second, "'" + calls_[0].first + ";': expected '" + scan + ";'");
    }
  }

  // The motion lives in the scan procedure alone (not in main(), not outside a procedure).
  void requireScanProcedure(const std::string& s) {
    if (proc_.empty() || proc_ == "MAIN") {
      r_.in.fail("'" + clipForMessage(s) +
                 "': outside the scan procedure: expected every MoveAbsJ and SetDO in the "
                 "procedure main() calls");
    }
  }

  // MoveAbsJ [[j1..j6],[eax_a,9E9 x5]]\NoEOffs, v..[\T:=s], zone, tool;
  void move(const std::string& s) {
    static const std::regex kMove(
        R"(MoveAbsJ\s*\[\[([^\]]*)\]\s*,\s*\[([^\]]*)\]\]\s*(\\NoEOffs)?\s*,\s*v[0-9]+(\\T\s*:=\s*([^,]+))?\s*,\s*(z[0-9]+|fine)\s*,\s*[A-Za-z][A-Za-z0-9_]*\s*;)",
        std::regex::icase);
    std::smatch m;
    if (!std::regex_match(s, m, kMove)) {
      r_.in.fail("'" + clipForMessage(s) +
                 "': expected 'MoveAbsJ [[j1,...,j6],[eax_a,9E9,...]]\\NoEOffs, v..[\\T:=s], "
                 "zone, tool;'");
    }
    checkZone(s, m[6].str());
    const std::vector<double> q = numberList(r_.in, m[1].str(), kNumJoints, "MoveAbsJ robax");
    const std::vector<double> eax = numberList(r_.in, m[2].str(), 6, "MoveAbsJ extax");
    const PendingStep p = r_.takeStep("MoveAbsJ");
    double t = p.t;
    const auto& samples = r_.reading.trajectory.samples;
    if (!samples.empty() && !m[4].matched) {
      r_.in.fail("'" + clipForMessage(s) +
                 "': a MoveAbsJ after the first without \\T: expected \\T:= the step's time");
    }
    if (!samples.empty()) {
      double dt = 0.0;
      if (!parseNumber(m[5].str(), dt) || !(dt > 0.0))
        r_.in.fail("'" + clipForMessage(s) + "': \\T must be a positive time");
      t = samples.back().t + dt;
    }
    r_.append(t, q, eax[0], p);
  }

  // z0 passes through the point, fine stops there, which only the first and the last move may
  // do (the plan moves on without stopping); a larger zone rounds the corner, a path the reader
  // does not model.
  void checkZone(const std::string& s, const std::string& zone) {
    const std::string u = upper(zone);
    if (u != "Z0" && u != "FINE") {
      r_.in.fail("'" + clipForMessage(s) + "': zone " + zone +
                 " rounds the corner at this point, a path the reader does not model: expected "
                 "z0 (or fine, on the first and the last MoveAbsJ)");
    }
    if (stop_line_) {
      r_.in.failAt(*stop_line_,
                   "zone fine between timed moves: the arm would stop here, where the plan moves "
                   "on without stopping (expected z0, fine only on the first and the last "
                   "MoveAbsJ)");
    }
    if (u == "FINE" && !r_.reading.trajectory.samples.empty()) stop_line_ = r_.in.lineNumber();
  }

  void setDo(const std::string& s) {
    static const std::regex kSet(R"(SetDO\s+([A-Za-z][A-Za-z0-9_]*)\s*,\s*([01])\s*;)",
                                 std::regex::icase);
    std::smatch m;
    if (!std::regex_match(s, m, kSet))
      r_.in.fail("'" + clipForMessage(s) + "': expected 'SetDO signal, 0|1;'");
    const std::string name = m[1].str();
    const auto digits = name.find_last_not_of("0123456789");
    const std::size_t count = name.size() - digits - 1;
    const int n = count > 0 && count <= 6 ? std::stoi(name.substr(digits + 1)) : 0;
    r_.addSwitch(r_.lastTime(), n, m[2].str() == "1");
  }

  // PERS tooldata name:=[TRUE,[[x,y,z],[q1,q2,q3,q4]],[mass,[cx,cy,cz],[1,0,0,0],ix,iy,iz]];
  void toolData(const std::string& s) {
    static const std::regex kTool(
        R"(PERS\s+tooldata\s+[A-Za-z][A-Za-z0-9_]*\s*:=\s*\[\s*(TRUE|FALSE)\s*,\s*\[\[([^\]]*)\]\s*,\s*\[([^\]]*)\]\]\s*,\s*\[([^,\[]*),\s*\[([^\]]*)\].*\]\s*;)",
        std::regex::icase);
    std::smatch m;
    if (!std::regex_match(s, m, kTool))
      r_.in.fail("'" + clipForMessage(s) + "': expected a tooldata value");
    const std::vector<double> p = numberList(r_.in, m[2].str(), 3, "tframe.trans");
    const std::vector<double> q = numberList(r_.in, m[3].str(), 4, "tframe.rot");
    const std::vector<double> c = numberList(r_.in, m[5].str(), 3, "tload.cog");
    double mass = 0.0;
    if (!parseNumber(m[4].str(), mass) || mass < 0.0)
      r_.in.fail("tload.mass: expected a mass in kg");
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Eigen::Vector3d(p[0], p[1], p[2]) / 1000.0;
    X.linear() = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
    r_.reading.tool = X;
    r_.reading.payload_kg = mass;
    r_.reading.payload_cog = Eigen::Vector3d(c[0], c[1], c[2]) / 1000.0;
  }

  ReaderState r_;
  bool module_ = false, ended_ = false;
  std::optional<int> stop_line_;                    // a timed MoveAbsJ with zone fine
  std::string proc_;                                // the procedure being read (upper case)
  std::vector<std::string> procs_;                  // every procedure's name
  std::vector<std::pair<std::string, int>> calls_;  // main()'s calls and their lines
};

// ---------------------------------------------------------------------------------------------
// URScript: movej to the start, then data rows `a = seg(a, [...])`, each played by seg() as
// servo steps every period along the joint-linear path from the previous row; the table follows
// its table_move() targets linearly.
class UrscriptReader {
 public:
  UrscriptReader(const std::string& text, const std::string& source) : r_(text, source) {}

  ProgramReading read() {
    std::string line;
    while (!ended_ && r_.in.next(line)) {
      if (line.empty()) continue;
      if (line[0] == '#') {
        step(line.substr(1));
      } else if (!in_program_) {
        static const std::regex kDef(R"(def ([A-Za-z_][A-Za-z0-9_]*)\(\):)");
        std::smatch m;
        if (!std::regex_match(line, m, kDef))
          r_.in.fail("'" + clipForMessage(line) + "': expected 'def name():' first");
        name_ = m[1].str();
        in_program_ = true;
      } else if (line.rfind("def ", 0) == 0) {
        helper(line);
      } else if (line == "end") {
        ended_ = true;
      } else if (line.rfind("if ", 0) == 0) {
        lastStep(line);
      } else {
        instruction(line);
      }
    }
    if (!in_program_) r_.in.fail("no 'def name():' line: expected a URScript program");
    if (!ended_) r_.in.fail("the program has no end");
    callAfterEnd();
    if (!last_step_)
      r_.in.fail("no step to the last sample ('" + firstLine(urscriptLastStep(1)) +
                 "' after the last row)");
    r_.reading.servo_steps = true;
    return r_.finish();
  }

 private:
  static std::string firstLine(const std::string& text) {
    return trim(text.substr(0, text.find('\n')));
  }

  // After the program's end: the one line that runs it, `name()`, and nothing else.
  void callAfterEnd() {
    std::string line;
    bool called = false;
    while (r_.in.next(line)) {
      if (line.empty() || line[0] == '#') continue;
      if (line != name_ + "()" || called)
        r_.in.fail("'" + clipForMessage(line) + "': expected only '" + name_ +
                   "()' after the program's end");
      called = true;
    }
    if (!called)
      r_.in.fail("the program '" + name_ + "' is defined but never run: expected a line '" + name_ +
                 "()' after its end");
  }

  // The start's step comment: its time.
  void step(const std::string& body) {
    PendingStep p;
    if (!readStepComment(r_.in, body, p.t, p.table_deg, p.scanning)) return;
    if (start_t_) r_.in.fail("a second step comment: the data rows time the motion");
    start_t_ = p.t;
    start_scanning_ = p.scanning;
  }

  // The lines up to the `end` that closes `first` (nested blocks counted), trimmed.
  std::vector<std::string> block(const std::string& first) {
    std::vector<std::string> lines{first};
    std::string line;
    for (int depth = 1; depth > 0;) {
      if (!r_.in.next(line)) r_.in.fail("'" + clipForMessage(first) + "' has no end");
      if (line.empty() || line[0] == '#') continue;
      if (line.rfind("def ", 0) == 0 || line.rfind("if ", 0) == 0 || line.rfind("while ", 0) == 0) {
        ++depth;
      }
      if (line == "end") --depth;
      lines.push_back(line);
    }
    return lines;
  }

  // `expected` (as written) against the block read, line by line.
  void same(const std::vector<std::string>& read,
            const std::string& expected,
            int first_line,
            const std::string& what) {
    std::vector<std::string> want;
    std::istringstream in(expected);
    for (std::string line; std::getline(in, line);) want.push_back(trim(line));
    for (std::size_t i = 0; i < std::max(read.size(), want.size()); ++i) {
      if (i < read.size() && i < want.size() && read[i] == want[i]) continue;
      r_.in.failAt(first_line + static_cast<int>(i),
                   fmt::format("{}: '{}' where scanplan writes '{}' (the reader models only the {} "
                               "scanplan writes)",
                               what, i < read.size() ? clipForMessage(read[i]) : "(nothing)",
                               i < want.size() ? want[i] : "end", what));
    }
  }

  // A helper function: seg() must be the one written (its period and output read from it); the
  // table functions' bodies are the cell's.
  void helper(const std::string& first) {
    const int at = r_.in.lineNumber();
    const std::vector<std::string> lines = block(first);
    if (first.rfind("def seg(", 0) != 0) return;
    static const std::regex kPeriod("servoj\\(.*\\], t=(" + kNum + "),.*");
    static const std::regex kOut(R"(set_standard_digital_out\(([0-9]{1,2}), .*)");
    std::smatch m;
    for (const std::string& line : lines) {
      if (std::regex_match(line, m, kPeriod)) period_ = std::strtod(m[1].str().c_str(), nullptr);
      if (std::regex_match(line, m, kOut)) output_ = std::stoi(m[1].str());
    }
    if (!period_ || !(*period_ >= 0.001 && *period_ <= 0.1))
      r_.in.failAt(at, "seg(): expected servoj(..., t=<period in 0.001 ... 0.1 s>, ...)");
    same(lines, urscriptStepFunction(*period_, output_), at, "seg() function");
  }

  // The step after the last row: one more servo step to the last sample unless one reached it.
  void lastStep(const std::string& first) {
    const int at = r_.in.lineNumber();
    if (!period_) r_.in.fail("'" + clipForMessage(first) + "' before seg() is defined");
    same(block(first), urscriptLastStep(*period_), at, "last step");
    if (!row_) r_.in.fail("the last step before any data row");
    if (static_cast<double>(steps_) * *period_ < (*row_)[0] - 1e-6)
      servoStep(steps_ + 1, *row_, *row_);
    last_step_ = true;
  }

  void instruction(const std::string& s) {
    static const std::regex kCall(R"(([a-z_]+)\((.*)\))");
    static const std::regex kRow(R"(a = seg\(a, \[(.*)\]\))");
    static const std::regex kState(R"(a = \[(.*)\])");
    std::smatch m;
    if (last_step_ && s != "stopj(2.0)" && s.rfind("set_standard_digital_out(", 0) != 0)
      r_.in.fail("'" + clipForMessage(s) + "' after the last step: expected stopj and the output");
    if (std::regex_match(s, m, kRow)) return row(m[1].str());
    if (std::regex_match(s, m, kState)) return state(m[1].str());
    if (!std::regex_match(s, m, kCall))
      r_.in.fail("'" + clipForMessage(s) + "': expected a function call or a data row");
    const std::string f = m[1].str(), args = m[2].str();
    if (f == "movej") {
      movej(args);
    } else if (f == "table_start" || f == "table_move") {
      table(f, args);
    } else if (f == "set_standard_digital_out" || f == "set_digital_out") {
      digitalOut(f, args);
    } else if (f == "set_tcp") {
      tcp(args);
    } else if (f == "set_target_payload" || f == "set_payload") {
      payload(f, args);
    } else if (f != "stopj") {
      r_.in.fail("'" + clipForMessage(s) +
                 "': not a call this reader knows (movej, table_start, table_move, "
                 "set_standard_digital_out, set_tcp, set_target_payload, stopj, data rows "
                 "'a = seg(a, [...])'; or the deprecated set_digital_out, set_payload)");
    }
  }

  std::vector<double> bracketed(const std::string& args, std::size_t n, const std::string& what) {
    const auto open = args.find('['), close = args.find(']');
    if (open == std::string::npos || close == std::string::npos || close < open) {
      r_.in.fail(what + ": expected [..]");
    }
    return numberList(r_.in, args.substr(open + 1, close - open - 1), n, what);
  }

  void add(double t, const std::vector<double>& q_rad, bool scanning) {
    std::vector<double> q(q_rad.size());
    for (std::size_t j = 0; j < q.size(); ++j) q[j] = q_rad[j] * kRadToDeg;
    appendSample(r_.in, r_.reading.trajectory, t, q, tableAt(t), scanning);
    now_ = t;
  }

  void movej(const std::string& args) {
    if (!r_.reading.trajectory.samples.empty())
      r_.in.fail("movej after the start: expected data rows");
    now_ = start_t_.value_or(0.0);
    add(now_, bracketed(args, kNumJoints, "movej joints"), start_scanning_);
  }

  // a = [0, row 0]: the state before the first row (no servo step yet, the start sample).
  void state(const std::string& list) {
    if (row_) r_.in.fail("a second 'a = [...]': the state is set once, before the rows");
    const std::vector<double> v = numberList(r_.in, list, kUrscriptRow + 1, "the state a");
    if (v[0] != 0.0 || v[1] != 0.0) r_.in.fail("the state a: expected [0, 0, ...] (the start)");
    if (r_.reading.trajectory.samples.empty()) r_.in.fail("the state a before the movej");
    row_.emplace(v.begin() + 1, v.end());
    r_.reading.step_times.push_back(start_t_.value_or(0.0));
  }

  // A data row: seg() as the controller runs it.
  void row(const std::string& list) {
    if (!period_) r_.in.fail("a data row before seg() is defined");
    if (!row_) r_.in.fail("a data row before the state 'a = [0, ...]'");
    const std::vector<double> d = numberList(r_.in, list, kUrscriptRow, "the data row");
    const std::vector<double> a = *row_;
    if (!(d[0] > a[0])) r_.in.fail("the data row's time is not after the previous row's");
    tableMove(d[1], d[0]);
    std::size_t i = steps_ + 1;
    for (; static_cast<double>(i) * *period_ <= d[0] + 1e-6; ++i) servoStep(i, a, d);
    steps_ = i - 1;
    if (output_ > 0 && d[9] != a[9]) r_.addSwitch(now_, output_, d[9] == 1.0);
    r_.reading.step_times.push_back(start_t_.value_or(0.0) + d[0]);
    row_ = d;
  }

  // Servo step i: the joints w of the way from row a to row d at i periods from the start.
  void servoStep(std::size_t i, const std::vector<double>& a, const std::vector<double>& d) {
    const double tau = static_cast<double>(i) * *period_;
    const double w = d[0] > a[0] ? (tau - a[0]) / (d[0] - a[0]) : 1.0;
    std::vector<double> q(kNumJoints);
    for (int j = 0; j < kNumJoints; ++j) {
      const auto k = static_cast<std::size_t>(j + 2);
      q[static_cast<std::size_t>(j)] = a[k] + w * (d[k] - a[k]);
    }
    add(start_t_.value_or(0.0) + tau, q, d[8] != 0.0);
    steps_ = i;
  }

  // table_start(deg): the table's angle at the start; table_move(deg, t): at deg t s after the
  // servo motion starts (the start's time), linearly between these points, the shorter way.
  void table(const std::string& f, const std::string& args) {
    const bool start = f == "table_start";
    const std::vector<double> v = numberList(r_.in, args, start ? 1 : 2, f);
    if (start) {
      timeline_ = {{start_t_.value_or(0.0), v[0]}};
      cursor_ = 0;
      return;
    }
    tableMove(v[0], v[1]);
  }

  void tableMove(double deg, double t_from_start) {
    if (timeline_.empty()) r_.in.fail("table_move before table_start");
    const auto& [t_prev, deg_prev] = timeline_.back();
    const double t = start_t_.value_or(0.0) + t_from_start;
    if (!(t > t_prev)) r_.in.fail("table_move: its time is not after the previous point's");
    timeline_.emplace_back(t, deg_prev + std::remainder(deg - deg_prev, 360.0));
  }

  // The times asked only grow: a cursor walks the points.
  double tableAt(double t) {
    if (timeline_.empty()) return 0.0;
    if (t <= timeline_.front().first) return timeline_.front().second;
    while (cursor_ + 1 < timeline_.size() && timeline_[cursor_ + 1].first < t) ++cursor_;
    if (cursor_ + 1 >= timeline_.size()) return timeline_.back().second;
    const auto& [t0, d0] = timeline_[cursor_];
    const auto& [t1, d1] = timeline_[cursor_ + 1];
    return d0 + (t - t0) / (t1 - t0) * (d1 - d0);
  }

  void digitalOut(const std::string& f, const std::string& args) {
    static const std::regex kOut(R"(\s*([0-9]{1,6})\s*,\s*(True|False)\s*)");
    std::smatch m;
    if (!std::regex_match(args, m, kOut)) r_.in.fail(f + ": expected (n, True|False)");
    r_.addSwitch(now_, std::stoi(m[1].str()), m[2].str() == "True");
  }

  void tcp(const std::string& args) {
    const auto open = args.find("p[");
    if (open == std::string::npos) r_.in.fail("set_tcp: expected p[x, y, z, rx, ry, rz]");
    const std::vector<double> v = bracketed(args.substr(open + 1), 6, "set_tcp");
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
    X.linear() = fromRotationVector(Eigen::Vector3d(v[3], v[4], v[5]));
    r_.reading.tool = X;
  }

  void payload(const std::string& f, const std::string& args) {
    double m = 0.0;
    if (!parseNumber(args.substr(0, args.find(',')), m) || m < 0.0)
      r_.in.fail(f + ": expected a mass in kg");
    const std::vector<double> c = bracketed(args, 3, f + " centre of gravity");
    r_.reading.payload_kg = m;
    r_.reading.payload_cog = Eigen::Vector3d(c[0], c[1], c[2]);
  }

  static constexpr std::size_t kUrscriptRow = 10;  // t, table, j1..j6, scan, out
  ReaderState r_;
  std::string name_;  // the program's, from its def line
  bool in_program_ = false, ended_ = false, last_step_ = false, start_scanning_ = false;
  std::optional<double> start_t_, period_;
  int output_ = 0;                          // the trigger output seg() switches; 0: none
  std::optional<std::vector<double>> row_;  // the last data row
  std::size_t steps_ = 0;                   // servo steps so far
  double now_ = 0.0;
  std::vector<std::pair<double, double>> timeline_;  // the table's (t, deg) points so far
  std::size_t cursor_ = 0;
};

}  // namespace

ProgramReading readVplus(const std::string& text,
                         const std::string& source,
                         const RobotModel* robot) {
  return VplusReader(text, source, robot).read();
}

ProgramReading readKrl(const std::string& text, const std::string& source) {
  return KrlReader(text, source).read();
}

ProgramReading readRapid(const std::string& text, const std::string& source) {
  return RapidReader(text, source).read();
}

ProgramReading readUrscript(const std::string& text, const std::string& source) {
  return UrscriptReader(text, source).read();
}

}  // namespace scanplan::programs::detail
