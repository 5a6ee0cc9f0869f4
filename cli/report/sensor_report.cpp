#include "cli/report/sensor_report.h"

#include <algorithm>
#include <limits>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <scanplan/kinematics/units.h>

namespace scanplan::cli {
namespace {

using kinematics::Sensor;

// Spans shown per sensor in the summary (report.json and sensors.csv hold them all).
constexpr std::size_t kSummarySpans = 4;

std::string bodyName(const collision::Scene& scene, int body) {
  return body < 0 ? std::string() : scene.bodies()[static_cast<std::size_t>(body)].name;
}

std::vector<std::string> bodyNames(const collision::Scene& scene, const std::vector<int>& bodies) {
  std::vector<std::string> out;
  for (int b : bodies) out.push_back(bodyName(scene, b));
  return out;
}

// A CSV field, quoted when it holds a separator, a quote or a line break.
std::string csvField(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

bool isDistance(const Sensor& s) { return s.kind == Sensor::Kind::kDistance; }

// Whether each sensor's rule held (no violation of it).
std::vector<bool> rulesHeld(const collision::Scene& scene, const collision::SensorEvaluation& e) {
  const auto& sensors = scene.cell().sensors;
  std::vector<bool> held(sensors.size(), true);
  for (const auto& v : collision::checkSensorRules(sensors, e)) held[v.sensor] = false;
  return held;
}

// The least and greatest range read during a span (m). The times ascend: only the span's own
// samples are read, so all spans together cost one pass, however many there are.
std::pair<double, double> rangeIn(const collision::SensorEvaluation& e,
                                  std::size_t s,
                                  const collision::SensorSpan& span) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  const auto first = std::lower_bound(e.t.begin(), e.t.end(), span.t_start);
  for (auto k = static_cast<std::size_t>(first - e.t.begin());
       k < e.t.size() && e.t[k] <= span.t_end; ++k) {
    const collision::SensorReading& r = e.readings[s][k];
    if (!r.fires) continue;
    lo = std::min(lo, r.distance);
    hi = std::max(hi, r.distance);
  }
  return {lo, hi};
}

}  // namespace

std::string sensorsCsv(const collision::Scene& scene, const collision::SensorEvaluation& e) {
  const auto& sensors = scene.cell().sensors;
  std::string out = "t_s";
  for (const Sensor& s : sensors) {
    out += isDistance(s) ? fmt::format(",{0}_mm,{0}_status,{0}_body", s.name)
                         : fmt::format(",{0},{0}_bodies", s.name);
  }
  out += '\n';
  for (std::size_t k = 0; k < e.t.size(); ++k) {
    out += fmt::format("{:.9f}", e.t[k]);
    for (std::size_t s = 0; s < sensors.size(); ++s) {
      const collision::SensorReading& r = e.readings[s][k];
      if (isDistance(sensors[s])) {
        out += r.fires ? fmt::format(",{:.6f}", toMm(r.distance)) : std::string(",");
        out += fmt::format(",{},{}", collision::beamStatusName(r.beam),
                           csvField(bodyName(scene, r.body)));
      } else {
        out += fmt::format(",{},{}", r.fires ? 1 : 0,
                           csvField(fmt::format("{}", fmt::join(bodyNames(scene, r.bodies), ";"))));
      }
    }
    out += '\n';
  }
  return out;
}

std::string sensorsSummary(const collision::Scene& scene, const collision::SensorEvaluation& e) {
  const auto& sensors = scene.cell().sensors;
  const std::vector<bool> held = rulesHeld(scene, e);
  std::string out;
  for (std::size_t s = 0; s < sensors.size(); ++s) {
    const Sensor& sensor = sensors[s];
    const std::vector<collision::SensorSpan> spans = collision::firingSpans(e, s);
    std::string line = fmt::format("sensor     {}: ", sensor.name);
    if (spans.empty()) {
      line += isDistance(sensor) ? "never reads" : "never fires";
    } else {
      line += isDistance(sensor) ? "reads " : "fires ";
      for (std::size_t i = 0; i < spans.size() && i < kSummarySpans; ++i) {
        const collision::SensorSpan& span = spans[i];
        if (i > 0) line += ", ";
        line += fmt::format("{:.3f}–{:.3f} s", span.t_start, span.t_end);
        if (isDistance(sensor)) {
          const auto [lo, hi] = rangeIn(e, s, span);
          line += fmt::format(" ({:.1f}–{:.1f} mm)", toMm(lo), toMm(hi));
        } else {
          line += fmt::format(" ({})", fmt::join(bodyNames(scene, span.bodies), ", "));
        }
      }
      if (spans.size() > kSummarySpans) {
        line += fmt::format(" and {} more spans", spans.size() - kSummarySpans);
      }
    }
    if (sensor.expect.kind != kinematics::SensorExpectation::Kind::kAny) {
      line += fmt::format("; expect {}: {}", collision::describeExpectation(sensor.expect),
                          held[s] ? "met" : "BROKEN");
    }
    out += line + "\n";
  }
  return out;
}

Json sensorsJson(const collision::Scene& scene, const collision::SensorEvaluation& e) {
  const auto& sensors = scene.cell().sensors;
  const std::vector<bool> held = rulesHeld(scene, e);
  Json out = Json::array();
  for (std::size_t s = 0; s < sensors.size(); ++s) {
    const Sensor& sensor = sensors[s];
    Json spans = Json::array();
    for (const collision::SensorSpan& span : collision::firingSpans(e, s)) {
      Json j = {{"start_s", span.t_start}, {"end_s", span.t_end}};
      if (isDistance(sensor)) {
        const auto [lo, hi] = rangeIn(e, s, span);
        j["min_mm"] = toMm(lo);
        j["max_mm"] = toMm(hi);
      } else {
        j["bodies"] = bodyNames(scene, span.bodies);
      }
      spans.push_back(std::move(j));
    }
    std::size_t firing = 0;
    for (const auto& r : e.readings[s]) firing += r.fires ? 1 : 0;
    out.push_back({{"name", sensor.name},
                   {"kind", isDistance(sensor) ? "distance" : "presence"},
                   {"carrier", sensor.carrier},
                   {"expect", collision::describeExpectation(sensor.expect)},
                   {"rule_met", held[s]},
                   {"samples", e.t.size()},
                   {"firing_samples", firing},
                   {"spans", std::move(spans)}});
  }
  return out;
}

std::string sensorReadingsText(const collision::Scene& scene,
                               const std::vector<collision::SensorReading>& readings) {
  const auto& sensors = scene.cell().sensors;
  std::string out;
  for (std::size_t s = 0; s < sensors.size() && s < readings.size(); ++s) {
    const collision::SensorReading& r = readings[s];
    std::string what;
    if (!isDistance(sensors[s])) {
      what = r.fires ? fmt::format("fires ({})", fmt::join(bodyNames(scene, r.bodies), ", "))
                     : std::string("clear");
    } else if (r.fires) {
      what = fmt::format("{:.3f} mm ({})", toMm(r.distance), bodyName(scene, r.body));
    } else if (r.body < 0) {
      what = fmt::format("no reading, {}", collision::beamStatusName(r.beam));
    } else {
      what = fmt::format("no reading, {} ({} at {:.3f} mm)", collision::beamStatusName(r.beam),
                         bodyName(scene, r.body), toMm(r.distance));
    }
    out += fmt::format("sensor       {}: {}\n", sensors[s].name, what);
  }
  return out;
}

Json sensorReadingsJson(const collision::Scene& scene,
                        const std::vector<collision::SensorReading>& readings) {
  const auto& sensors = scene.cell().sensors;
  Json out = Json::array();
  for (std::size_t s = 0; s < sensors.size() && s < readings.size(); ++s) {
    const collision::SensorReading& r = readings[s];
    Json j = {{"name", sensors[s].name}, {"fires", r.fires}};
    if (isDistance(sensors[s])) {
      j["status"] = std::string(collision::beamStatusName(r.beam));
      if (r.body >= 0) {
        j["distance_mm"] = toMm(r.distance);
        j["body"] = bodyName(scene, r.body);
      }
    } else {
      j["bodies"] = bodyNames(scene, r.bodies);
    }
    out.push_back(std::move(j));
  }
  return out;
}

}  // namespace scanplan::cli
