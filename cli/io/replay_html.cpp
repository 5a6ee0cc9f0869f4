#include "cli/io/replay_html.h"

#include <array>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

#include <Eigen/Geometry>

#include "cli/io/json.h"
#include "cli/io/replay_viewer_js.h"  // generated: kReplayViewerJs
#include "pipeline/certificate.h"

namespace scanplan::cli {

namespace {

std::string readText(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string base64(const void* data, std::size_t size) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* p = static_cast<const unsigned char*>(data);
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  for (std::size_t i = 0; i < size; i += 3) {
    const auto byte = [&](std::size_t k) { return k < size ? static_cast<unsigned>(p[k]) : 0u; };
    const unsigned v = (byte(i) << 16u) | (byte(i + 1) << 8u) | byte(i + 2);
    out += kAlphabet[(v >> 18u) & 63u];
    out += kAlphabet[(v >> 12u) & 63u];
    out += i + 1 < size ? kAlphabet[(v >> 6u) & 63u] : '=';
    out += i + 2 < size ? kAlphabet[v & 63u] : '=';
  }
  return out;
}

template <class T>
std::string base64(const std::vector<T>& v) {
  return base64(v.data(), v.size() * sizeof(T));
}

Json bodyJson(const pipeline::ReplayBody& b) {
  std::vector<float> vertices;
  for (const Eigen::Vector3d& v : b.mesh.vertices) {
    for (int a = 0; a < 3; ++a) vertices.push_back(static_cast<float>(v[a]));
  }
  std::vector<std::uint32_t> triangles;
  for (const Eigen::Vector3i& t : b.mesh.triangles) {
    for (int a = 0; a < 3; ++a) triangles.push_back(static_cast<std::uint32_t>(t[a]));
  }
  Json j = {{"name", b.name},
            {"frame", b.frame},
            {"vertices", base64(vertices)},
            {"triangles", base64(triangles)}};
  if (!b.colours.empty()) {
    std::vector<std::uint8_t> c;
    for (const auto& rgb : b.colours) c.insert(c.end(), rgb.begin(), rgb.end());
    j["colours"] = base64(c);
  }
  return j;
}

Json framesJson(const pipeline::ReplayScene& s) {
  std::vector<float> t, poses;
  std::vector<std::uint8_t> scanning;
  for (const pipeline::ReplayFrame& f : s.frames) {
    t.push_back(static_cast<float>(f.t));
    scanning.push_back(f.scanning ? 1 : 0);
    for (const Eigen::Isometry3d& X : f.poses) {
      const Eigen::Quaterniond q(X.linear());
      for (const double v : {X.translation().x(), X.translation().y(), X.translation().z(), q.x(),
                             q.y(), q.z(), q.w()}) {
        poses.push_back(static_cast<float>(v));
      }
    }
  }
  return {{"t", base64(t)}, {"poses", base64(poses)}, {"scanning", base64(scanning)}};
}

// The bodies' bounds at the first frame (world frame).
Eigen::AlignedBox3d bounds(const pipeline::ReplayScene& s) {
  Eigen::AlignedBox3d box;
  for (const pipeline::ReplayBody& b : s.bodies) {
    const Eigen::Isometry3d X = b.frame < 0
                                    ? Eigen::Isometry3d::Identity()
                                    : s.frames.front().poses[static_cast<std::size_t>(b.frame)];
    for (const Eigen::Vector3d& v : b.mesh.vertices) box.extend(X * v);
  }
  return box;
}

Json sceneJson(const pipeline::ReplayScene& s, const std::string& title) {
  Json bodies = Json::array();
  for (const pipeline::ReplayBody& b : s.bodies) bodies.push_back(bodyJson(b));
  std::vector<float> fan, cloud, uncovered;
  for (const Eigen::Vector3d& p : s.fan)
    fan.insert(fan.end(), {float(p.x()), float(p.y()), float(p.z())});
  for (const Eigen::Vector3f& p : s.cloud) cloud.insert(cloud.end(), {p.x(), p.y(), p.z()});
  for (const Eigen::Vector3f& p : s.uncovered)
    uncovered.insert(uncovered.end(), {p.x(), p.y(), p.z()});
  Json closest = Json::array();
  for (const auto& c : s.closest) {
    closest.push_back({{"a", c.a}, {"b", c.b}, {"t", c.t}, {"distance", c.distance}});
  }
  const std::array<const char*, pipeline::kCoverageClasses> colours = {
      "#1f5fbf", "#e6194b", "#911eb4", "#f58231", "#1cb5c9", "#222222"};
  Json classes = Json::array();
  for (std::size_t c = 0; c < pipeline::kCoverageClasses; ++c) {
    classes.push_back(
        {{"name", pipeline::coverageClassName(static_cast<pipeline::CoverageClass>(c))},
         {"colour", colours[c]}});
  }
  const Eigen::AlignedBox3d box = bounds(s);
  const Eigen::Vector3d look_at = box.center();
  const Eigen::Vector3d eye =
      look_at + 0.42 * box.diagonal().norm() * Eigen::Vector3d(1.2, -1.9, 1.0);
  std::vector<double> X_RP(s.X_RP.matrix().data(), s.X_RP.matrix().data() + 16);
  Json j = {{"title", title},
            {"bodies", bodies},
            {"X_RP", X_RP},
            {"frames", framesJson(s)},
            {"fan", base64(fan)},
            {"cloud", base64(cloud)},
            {"cloud_t", base64(s.cloud_t)},
            {"cloud_total", s.cloud_total},
            {"classes", classes},
            {"closest", closest},
            {"look_at", {look_at.x(), look_at.y(), look_at.z()}},
            {"eye", {eye.x(), eye.y(), eye.z()}},
            {"floor", box.min().z()}};
  if (!s.uncovered.empty()) {
    j["uncovered"] = base64(uncovered);
    j["uncovered_class"] = base64(s.uncovered_class);
  }
  return j;
}

// OrbitControls.js is an ES module importing from 'three': the same code reading THREE.
std::string orbitControls(std::string module) {
  const auto from = module.find("import {");
  const auto to = module.find("} from 'three';");
  if (from == std::string::npos || to == std::string::npos) return {};
  module.replace(to, 15, "} = THREE;");
  module.replace(from, 8, "const {");
  const auto exported = module.find("export { OrbitControls };");
  if (exported != std::string::npos) module.erase(exported, 25);
  return "(function () {\n" + module + "\nTHREE.OrbitControls = OrbitControls;\n})();\n";
}

std::string htmlText(const std::string& text) {
  std::string out;
  for (const char c : text) {
    out += c == '<'   ? std::string("&lt;")
           : c == '>' ? std::string("&gt;")
           : c == '&' ? std::string("&amp;")
                      : std::string(1, c);
  }
  return out;
}

// Text inside <script>: no "</" (a "</script>" would end the element).
std::string scriptSafe(std::string text) {
  for (std::size_t at = text.find("</"); at != std::string::npos; at = text.find("</", at + 3)) {
    text.replace(at, 2, "<\\/");
  }
  return text;
}

const char* kStyle = R"(
  html, body { margin: 0; height: 100%; font: 14px/1.4 "DejaVu Sans", Arial, sans-serif; }
  #view { position: absolute; inset: 0 0 64px 0; }
  #bar { position: absolute; left: 0; right: 0; bottom: 0; height: 64px; padding: 6px 12px;
         box-sizing: border-box; background: #fff; border-top: 1px solid #ccc; }
  #bar input[type=range] { width: 55%; vertical-align: middle; }
  #legend { position: absolute; top: 8px; left: 8px; background: rgba(255,255,255,0.9);
            padding: 6px 10px; border: 1px solid #ccc; font-size: 12px; }
  #legend i { display: inline-block; width: 12px; height: 12px; margin-right: 5px;
              vertical-align: -2px; }
  #note { color: #b00; font-weight: bold; }
)";

std::string legend(const Json& data) {
  std::string s =
      "<div id=\"legend\"><b>" + htmlText(data["title"].get<std::string>()) + "</b><br>";
  s +=
      "<i style=\"background:linear-gradient(90deg,#440154,#21918c,#fde725)\"></i>part: points/mm² "
      "(covered triangles)<br><i style=\"background:#dc4628\"></i>part: not covered<br>";
  s += "<i style=\"background:#1f5fbf\"></i>cloud, growing with time<br>";
  s += "<i style=\"background:#ff2020\"></i>laser fan (while scanning)<br>";
  if (data.contains("uncovered")) {
    s += "certificate, uncovered samples:<br>";
    for (std::size_t c = 1; c < data["classes"].size(); ++c) {
      s += "<i style=\"background:" + data["classes"][c]["colour"].get<std::string>() + "\"></i>" +
           data["classes"][c]["name"].get<std::string>() + "<br>";
    }
  }
  return s + "drag: turn · wheel: zoom · right-drag: pan</div>\n";
}

}  // namespace

std::optional<std::filesystem::path> replayAssetsDir() {
  std::vector<std::filesystem::path> candidates;
  if (const char* env = std::getenv("SCANPLAN_WEB_DIR")) candidates.emplace_back(env);
  candidates.emplace_back(SCANPLAN_WEB_BUILD_DIR);
  candidates.emplace_back(SCANPLAN_WEB_INSTALL_DIR);
  for (const auto& dir : candidates) {
    if (std::filesystem::exists(dir / "three.cjs") &&
        std::filesystem::exists(dir / "OrbitControls.js") &&
        std::filesystem::exists(dir / "LICENSE")) {
      return dir;
    }
  }
  return std::nullopt;
}

std::optional<std::string> replayHtml(const pipeline::ReplayScene& scene,
                                      const std::string& title) {
  const auto dir = replayAssetsDir();
  if (!dir || scene.frames.empty()) return std::nullopt;
  const std::string controls = orbitControls(readText(*dir / "OrbitControls.js"));
  if (controls.empty()) return std::nullopt;
  const Json data = sceneJson(scene, title);
  std::string licence = readText(*dir / "LICENSE");
  for (std::size_t at = licence.find("*/"); at != std::string::npos; at = licence.find("*/")) {
    licence.replace(at, 2, "* /");
  }
  std::string html = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  html += "<title>scanplan replay: " + htmlText(title) + "</title>\n<style>" + std::string(kStyle) +
          "</style>\n</head>\n<body>\n<div id=\"view\"></div>\n" + legend(data);
  html +=
      "<div id=\"bar\"><button id=\"play\">▶ Play</button> <input id=\"time\" type=\"range\" "
      "min=\"0\" max=\"0\" value=\"0\" step=\"1\"> speed <select id=\"speed\"><option "
      "value=\"1\">1×</option><option value=\"10\" selected>10×</option><option "
      "value=\"50\">50×</option></select> <button id=\"closest\">closest approach</button><br>"
      "<span id=\"label\"></span> <span id=\"note\"></span></div>\n";
  html += "<script>\n/* three.js, from its npm package (three/build/three.cjs). Its licence:\n" +
          licence +
          "*/\n(function () {\nvar module = { exports: {} }, exports = module.exports;\n" +
          scriptSafe(readText(*dir / "three.cjs")) +
          "\nwindow.THREE = module.exports;\n})();\n</script>\n";
  html += "<script>\n/* three.js OrbitControls (three/examples/jsm/controls), same licence */\n" +
          scriptSafe(controls) + "</script>\n";
  html += "<script type=\"application/json\" id=\"scanplan-data\">" + scriptSafe(jsonLine(data)) +
          "</script>\n<script>\n" + scriptSafe(kReplayViewerJs) + "</script>\n</body>\n</html>\n";
  return html;
}

}  // namespace scanplan::cli
