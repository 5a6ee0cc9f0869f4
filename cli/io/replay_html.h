#pragma once
// OUT/replay.html: a single self-contained page that replays a plan in 3D (three.js, vendored
// from its npm package by the build with its licence; the viewer in replay_viewer.js).

#include <filesystem>
#include <optional>
#include <string>

#include <scanplan/pipeline/replay.h>

namespace scanplan::cli {

/// Where three.js is: $SCANPLAN_WEB_DIR, else the build tree's copy, else the installed one
/// (each a folder with three.cjs, OrbitControls.js and LICENSE); nullopt when none has it.
std::optional<std::filesystem::path> replayAssetsDir();

/// The page: three.js and its orbit controls inline, the scene as JSON (binary arrays in
/// base64), the viewer. `title` names the job. nullopt without the assets.
std::optional<std::string> replayHtml(const pipeline::ReplayScene& scene, const std::string& title);

}  // namespace scanplan::cli
