#include "cli/io/replay_html.h"

#include <algorithm>
#include <array>
#include <cstdlib>
#include <fstream>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <Eigen/Geometry>

#include <scanplan/pipeline/certificate.h>
#include "cli/io/json.h"
#include "cli/io/replay_viewer_js.h"  // generated: kReplayViewerJs

namespace scanplan::cli {

namespace {

// The whole file as it is on disk (empty when it cannot be read).
std::string readText(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary | std::ios::ate);
  if (!in) return {};
  std::string text(static_cast<std::size_t>(std::max<std::streamoff>(in.tellg(), 0)), '\0');
  in.seekg(0);
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  return text;
}

// Appends `size` bytes at `data` in base64 (RFC 4648, padded) to `out`, in one pass.
void appendBase64(std::string& out, const void* data, std::size_t size) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* p = static_cast<const unsigned char*>(data);
  std::size_t at = out.size();
  out.resize(at + (size + 2) / 3 * 4);
  char* o = out.data() + at;
  std::size_t i = 0;
  for (; i + 2 < size; i += 3, o += 4) {
    const unsigned v = (unsigned{p[i]} << 16u) | (unsigned{p[i + 1]} << 8u) | p[i + 2];
    o[0] = kAlphabet[(v >> 18u) & 63u];
    o[1] = kAlphabet[(v >> 12u) & 63u];
    o[2] = kAlphabet[(v >> 6u) & 63u];
    o[3] = kAlphabet[v & 63u];
  }
  if (i < size) {  // one or two bytes left
    const unsigned v = (unsigned{p[i]} << 16u) | (i + 1 < size ? unsigned{p[i + 1]} << 8u : 0u);
    o[0] = kAlphabet[(v >> 18u) & 63u];
    o[1] = kAlphabet[(v >> 12u) & 63u];
    o[2] = i + 1 < size ? kAlphabet[(v >> 6u) & 63u] : '=';
    o[3] = '=';
  }
}

// Text inside <script>: no "</" (a "</script>" would end the element).
std::string scriptSafe(std::string text) {
  for (std::size_t at = text.find("</"); at != std::string::npos; at = text.find("</", at + 3)) {
    text.replace(at, 2, "<\\/");
  }
  return text;
}

// A JSON object written member by member onto `out`, compact as jsonLine has it: small values
// through nlohmann::json, binary arrays as base64 strings appended in place (the bulk of the
// scene: no copy through a JSON value and its escaping). Safe inside <script>.
class ObjectWriter {
 public:
  explicit ObjectWriter(std::string& out) : out_(out) { out_ += '{'; }
  ~ObjectWriter() { out_ += '}'; }
  ObjectWriter(const ObjectWriter&) = delete;
  ObjectWriter& operator=(const ObjectWriter&) = delete;

  void value(const char* key, const Json& value) {
    this->key(key);
    out_ += scriptSafe(value.dump(-1, ' ', false, Json::error_handler_t::replace));
  }
  template <class T>
  void base64(const char* key, const std::vector<T>& v) {
    this->key(key);
    out_ += '"';
    appendBase64(out_, v.data(), v.size() * sizeof(T));
    out_ += '"';
  }
  // The key of a member whose value the caller writes next.
  void key(const char* key) {
    if (!first_) out_ += ',';
    first_ = false;
    out_ += Json(key).dump();
    out_ += ':';
  }

 private:
  std::string& out_;
  bool first_ = true;
};

void appendBody(std::string& out, const pipeline::ReplayBody& b) {
  std::vector<float> vertices;
  vertices.reserve(3 * b.mesh.vertices.size());
  for (const Eigen::Vector3d& v : b.mesh.vertices) {
    for (int a = 0; a < 3; ++a) vertices.push_back(static_cast<float>(v[a]));
  }
  std::vector<std::uint32_t> triangles;
  triangles.reserve(3 * b.mesh.triangles.size());
  for (const Eigen::Vector3i& t : b.mesh.triangles) {
    for (int a = 0; a < 3; ++a) triangles.push_back(static_cast<std::uint32_t>(t[a]));
  }
  ObjectWriter j(out);
  j.value("name", b.name);
  j.value("frame", b.frame);
  if (b.standin) j.value("standin", true);
  j.base64("vertices", vertices);
  j.base64("triangles", triangles);
  if (!b.colours.empty()) {
    std::vector<std::uint8_t> c;
    c.reserve(3 * b.colours.size());
    for (const auto& rgb : b.colours) c.insert(c.end(), rgb.begin(), rgb.end());
    j.base64("colours", c);
  }
  if (!b.covered_t.empty()) j.base64("covered_t", b.covered_t);
}

void appendFrames(std::string& out, const pipeline::ReplayScene& s) {
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
  ObjectWriter j(out);
  j.base64("t", t);
  j.base64("poses", poses);
  j.base64("scanning", scanning);
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

std::vector<float> flat(const std::vector<Eigen::Vector3f>& points) {
  std::vector<float> out;
  out.reserve(3 * points.size());
  for (const Eigen::Vector3f& p : points) out.insert(out.end(), {p.x(), p.y(), p.z()});
  return out;
}

// The certificate's classes: key, words and colour (as certificate.png), in CoverageClass order.
Json coverageClasses() {
  Json classes = Json::array();
  for (std::size_t c = 0; c < pipeline::kCoverageClasses; ++c) {
    const auto cls = static_cast<pipeline::CoverageClass>(c);
    const auto rgb = pipeline::coverageClassColour(cls);
    classes.push_back({{"name", pipeline::coverageClassName(cls)},
                       {"words", pipeline::coverageClassWords(cls)},
                       {"colour", fmt::format("#{:02x}{:02x}{:02x}", rgb[0], rgb[1], rgb[2])}});
  }
  return classes;
}

// The scene as one line of JSON (binary arrays in base64), appended to `out`.
void appendScene(std::string& out,
                 const pipeline::ReplayScene& s,
                 const std::string& title,
                 const Json& classes) {
  std::vector<float> fan;
  for (const Eigen::Vector3d& p : s.fan)
    fan.insert(fan.end(), {float(p.x()), float(p.y()), float(p.z())});
  Json closest = Json::array();
  for (const auto& c : s.closest) {
    closest.push_back({{"a", c.a}, {"b", c.b}, {"t", c.t}, {"distance", c.distance}});
  }
  const Eigen::AlignedBox3d box = bounds(s);
  std::vector<double> X_RP(s.X_RP.matrix().data(), s.X_RP.matrix().data() + 16);
  ObjectWriter j(out);
  j.value("title", title);
  j.key("bodies");
  out += '[';
  for (const pipeline::ReplayBody& b : s.bodies) {
    if (&b != &s.bodies.front()) out += ',';
    appendBody(out, b);
  }
  out += ']';
  j.value("X_RP", X_RP);
  j.key("frames");
  appendFrames(out, s);
  j.base64("fan", fan);
  j.base64("cloud", flat(s.cloud));
  j.base64("cloud_t", s.cloud_t);
  j.value("cloud_total", s.cloud_total);
  j.value("density_top", s.density_top_per_mm2);
  j.value("classes", classes);
  j.value("closest", closest);
  j.value("floor", box.min().z());
  if (!s.uncovered.empty()) {
    j.base64("uncovered", flat(s.uncovered));
    j.base64("uncovered_class", s.uncovered_class);
  }
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

const char* kStyle = R"(
  html, body { margin: 0; height: 100%; font: 14px/1.4 "DejaVu Sans", Arial, sans-serif; }
  #view { position: absolute; inset: 0 0 64px 0; }
  #bar { position: absolute; left: 0; right: 0; bottom: 0; height: 64px; padding: 6px 12px;
         box-sizing: border-box; background: #fff; border-top: 1px solid #ccc; }
  #track { position: relative; display: inline-block; width: 55%; vertical-align: middle; }
  #track input { width: 100%; margin: 0; vertical-align: middle; }
  #ticks i { position: absolute; top: -3px; bottom: -3px; width: 3px; margin-left: -1px;
             background: #d00; pointer-events: none; }
  #legend { position: absolute; top: 8px; left: 8px; background: rgba(255,255,255,0.9);
            padding: 6px 10px; border: 1px solid #ccc; font-size: 12px; }
  #legend summary { cursor: pointer; }
  #legend i { display: inline-block; width: 12px; height: 12px; margin-right: 5px;
              vertical-align: -2px; }
  #scale { position: relative; display: inline-block; width: 160px; height: 27px;
           margin: 3px 12px 0 6px; vertical-align: top; }
  #ramp { height: 11px; border: 1px solid #777; box-sizing: border-box;
          background: linear-gradient(90deg, #440154, #3b528b, #21918c, #5ec962, #fde725); }
  #scale span { position: absolute; top: 13px; transform: translateX(-50%); font-size: 11px;
                white-space: nowrap; }
  #scale span::before { content: ""; position: absolute; left: 50%; top: -4px; height: 4px;
                        border-left: 1px solid #333; }
  #legend label { white-space: nowrap; }
  #legend input { margin: 0 2px 0 6px; vertical-align: -2px; }
  #note { color: #c00; font-weight: bold; font-size: 16px; }
)";

// The legend: what each colour means, in words for someone who has never seen scanplan; a click
// on the title folds it. The viewer writes the density scale's numbers (#scale-mid, #scale-top)
// from the scene's data.
std::string legend(const std::string& title, const Json& classes, bool uncovered, bool standins) {
  std::string s =
      "<div id=\"legend\"><details open><summary><b>" + htmlText(title) + "</b></summary>";
  s += "<i style=\"background:#f39c34\"></i>robot arm <i style=\"background:#333a44\"></i>laser "
       "scanner <i style=\"background:#9a9a9a\"></i>rotary table<br>";
  s += "part surface, once scanned: its point density<br>";
  s += "<div id=\"scale\"><div id=\"ramp\"></div><span style=\"left:0\">0</span>"
       "<span id=\"scale-mid\" style=\"left:50%\"></span>"
       "<span id=\"scale-top\" style=\"left:100%\"></span></div> points/mm²<br>";
  s += "<i style=\"background:#d0d0d0\"></i>not yet scanned<br>";
  s += "<i style=\"background:#dc4628\"></i>never covered (shown at the end)<br>";
  s += "<i style=\"background:#1f5fbf\"></i>latest scanned points <label><input "
       "type=\"checkbox\" id=\"all-points\">all</label><br>";
  s += "<i style=\"background:#ff2020\"></i>laser fan (while scanning)<br>";
  if (standins) {
    s += "<i style=\"background:#0072b2\"></i>what the maps measure for the link meshes (hulls "
         "or convex pieces) <label><input type=\"checkbox\" id=\"standins\">show</label><br>";
  }
  s += "<i style=\"background:#ff0000;border-radius:6px\"></i>glowing red, red tick on the time "
       "bar: closest approach<br>";
  if (uncovered) {
    s += "at the end, uncovered area samples, by reason:<br>";
    for (std::size_t c = 1; c < classes.size(); ++c) {
      s += "<i style=\"background:" + classes[c]["colour"].get<std::string>() + "\"></i>" +
           htmlText(classes[c]["words"].get<std::string>()) + "<br>";
    }
  }
  return s + "drag: turn · wheel: zoom · right-drag: pan</details></div>\n";
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
  const Json classes = coverageClasses();
  std::string licence = readText(*dir / "LICENSE");
  for (std::size_t at = licence.find("*/"); at != std::string::npos; at = licence.find("*/")) {
    licence.replace(at, 2, "* /");
  }
  const std::string three = scriptSafe(readText(*dir / "three.cjs"));
  // One string, sized once: three.js, the scene's base64 arrays (4 characters per 3 bytes) and
  // the viewer are nearly all of it.
  std::string html;
  html.reserve(three.size() + controls.size() + licence.size() +
               std::string_view(kReplayViewerJs).size() +
               4 * (sizeof(Eigen::Vector3f) + sizeof(float)) * scene.cloud.size() / 3 +
               (std::size_t{1} << 20));
  html += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  html += "<title>scanplan replay: " + htmlText(title) + "</title>\n<style>";
  html += kStyle;
  html += "</style>\n</head>\n<body>\n<div id=\"view\"></div>\n";
  const bool standins = std::any_of(scene.bodies.begin(), scene.bodies.end(),
                                    [](const pipeline::ReplayBody& b) { return b.standin; });
  html += legend(title, classes, !scene.uncovered.empty(), standins);
  html +=
      "<div id=\"bar\"><button id=\"play\">▶ Play</button> <span id=\"track\"><input "
      "id=\"time\" type=\"range\" min=\"0\" max=\"0\" value=\"0\" step=\"1\"><span "
      "id=\"ticks\"></span></span> speed <select id=\"speed\"><option "
      "value=\"1\">1×</option><option value=\"10\" selected>10×</option><option "
      "value=\"50\">50×</option></select> <button id=\"closest\">closest approach</button><br>"
      "<span id=\"label\"></span> <span id=\"note\"></span></div>\n";
  html += "<script>\n/* three.js, from its npm package (three/build/three.cjs). Its licence:\n";
  html += licence;
  html += "*/\n(function () {\nvar module = { exports: {} }, exports = module.exports;\n";
  html += three;
  html += "\nwindow.THREE = module.exports;\n})();\n</script>\n";
  html += "<script>\n/* three.js OrbitControls (three/examples/jsm/controls), same licence */\n";
  html += scriptSafe(controls);
  html += "</script>\n<script type=\"application/json\" id=\"scanplan-data\">";
  appendScene(html, scene, title, classes);
  html += "\n</script>\n<script>\n";
  html += scriptSafe(kReplayViewerJs);
  html += "</script>\n</body>\n</html>\n";
  return html;
}

}  // namespace scanplan::cli
