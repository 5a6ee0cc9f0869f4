#pragma once
// Shared by the libFuzzer harnesses: a per-process scratch folder that mirrors data/ (so the
// relative paths of the bundled jobs and sweeps resolve), the input written to a file there,
// and the one rule for exceptions: scanplan::InputError is the documented answer to bad input
// and is ignored; anything else escapes to libFuzzer, which reports it as a crash.

#include <signal.h>
#include <sys/types.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

#include <scanplan/kinematics/error.h>

namespace scanplan::fuzz {

namespace fs = std::filesystem;

/// Removes the scratch folders of harnesses that are no longer running: libFuzzer may end a
/// run without the exit handlers that remove a process's own folder.
inline void removeStaleScratch() {
  const std::string prefix = "scanplan-fuzz-";
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(fs::temp_directory_path(), ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string digits = name.substr(prefix.size());
    if (digits.empty() || digits.size() > 9 ||
        digits.find_first_not_of("0123456789") != std::string::npos)
      continue;
    const auto pid = static_cast<pid_t>(std::stol(digits));
    if (pid == getpid() || kill(pid, 0) == 0 || errno != ESRCH) continue;
    std::error_code remove_ec;
    fs::remove_all(e.path(), remove_ec);
  }
}

/// The scratch folder of this process: /tmp/scanplan-fuzz-<pid>/ with data/robots and
/// data/parts linked in and data/jobs/* linked file by file (so a harness may add its input
/// beside them). Removed at exit; folders that earlier harnesses left behind are removed when
/// it is made.
inline const fs::path& scratch() {
  static const fs::path dir = [] {
    removeStaleScratch();
    const fs::path d = fs::temp_directory_path() / ("scanplan-fuzz-" + std::to_string(getpid()));
    const fs::path data = fs::path(SCANPLAN_SOURCE_DIR) / "data";
    fs::remove_all(d);
    fs::create_directories(d / "jobs");
    fs::create_directories(d / "sweeps");
    fs::create_directories(d / "input");
    fs::create_directory_symlink(data / "robots", d / "robots");
    fs::create_directory_symlink(data / "parts", d / "parts");
    for (const auto& e : fs::directory_iterator(data / "jobs")) {
      fs::create_symlink(e.path(), d / "jobs" / e.path().filename());
    }
    std::atexit([] {
      std::error_code ec;
      fs::remove_all(scratch(), ec);
    });
    return d;
  }();
  return dir;
}

/// Writes the input to `relative` under the scratch folder (the same file every time).
inline fs::path writeInput(const std::string& relative,
                           const std::uint8_t* data,
                           std::size_t size) {
  const fs::path file = scratch() / relative;
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return file;
}

/// The input as text.
inline std::string text(const std::uint8_t* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

/// Runs `read`, ignoring the documented InputError; every other exception escapes.
template <class Read>
int expectInputErrors(Read&& read) {
  try {
    read();
  } catch (const InputError&) {
  }
  return 0;
}

}  // namespace scanplan::fuzz
