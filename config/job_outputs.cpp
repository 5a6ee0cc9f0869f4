// The outputs section of a job file: robot programs and their trigger (describe).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <regex>
#include <set>
#include <sstream>
#include <type_traits>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <scanplan/config/detail/job_sections.h>
#include <scanplan/config/robot_urdf.h>
#include <scanplan/config/text.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/placement.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/programs/programs.h>

namespace scanplan::config {
namespace {

template <class A>
void describeTrigger(A& a, TriggerSpec& s) {
  a.field("output", s.output, Expect::range(0, 4096));
  a.field("on_at_scan_start", s.on_at_scan_start);
  a.field("rapid_signal", s.rapid_signal);
  if constexpr (A::kReading) {
    static const std::regex kName("[A-Za-z][A-Za-z0-9_]{0,31}");
    if (!s.rapid_signal.empty() && !std::regex_match(s.rapid_signal, kName))
      a.fail("rapid_signal", "'" + clipForMessage(s.rapid_signal) + "'",
             "a RAPID identifier: a letter, then letters, digits or _, at most 32 characters");
  }
}

template <class A>
void describeOutputs(A& a, OutputsSpec& s) {
  a.field("programs", s.programs, Expect::oneOf(programs::programFormatNames()));
  a.field("program_name", s.program_name);
  a.section("trigger", s.trigger);
  a.field("servo_period_s", s.servo_period_s, Expect::range(0.001, 0.1));
}

}  // namespace

void describe(YamlIn& a, TriggerSpec& s) { describeTrigger(a, s); }
void describe(YamlOut& a, TriggerSpec& s) { describeTrigger(a, s); }
void describe(SchemaOut& a, TriggerSpec& s) { describeTrigger(a, s); }
void describe(YamlIn& a, OutputsSpec& s) { describeOutputs(a, s); }
void describe(YamlOut& a, OutputsSpec& s) { describeOutputs(a, s); }
void describe(SchemaOut& a, OutputsSpec& s) { describeOutputs(a, s); }

}  // namespace scanplan::config
