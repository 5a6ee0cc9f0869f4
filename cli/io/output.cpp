#include "cli/io/output.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <mutex>
#include <sstream>
#include <streambuf>
#include <string_view>
#include <system_error>
#include <thread>

#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <scanplan/kinematics/error.h>

namespace scanplan::cli {
namespace {

std::mutex& creationMutex() {
  static std::mutex m;
  return m;
}

// Staging folders and the OUT each stands for, so messages name the file the user asked for.
struct Shown {
  std::mutex mutex;
  std::vector<std::pair<std::filesystem::path, std::filesystem::path>> stage_to_out;
};

Shown& shown() {
  static Shown s;
  return s;
}

// Creates (or truncates) the file `path` for writing: its descriptor, or -1 with errno set.
int createFile(const std::filesystem::path& path) {
  // Folders and files come into being under this lock, which an interrupt takes and keeps:
  // nothing appears in a staging folder while, or after, it is removed.
  const std::lock_guard<std::mutex> guard(creationMutex());
  std::error_code ec;
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path(), ec);
  return ::open(path.c_str(), O_CREAT | O_TRUNC | O_WRONLY | O_CLOEXEC, 0644);
}

// Writes all `size` bytes at `data` to `fd`; the OS's reason on failure, or nothing.
std::string writeBytes(int fd, const char* data, std::size_t size) {
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(fd, data + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return n < 0 ? std::strerror(errno) : "the disk took nothing";
    done += static_cast<std::size_t>(n);
  }
  return {};
}

// Closes `fd` after a write that failed for `why` (kept) or succeeded: close() reports deferred
// write errors (e.g. a full disk on a network file system).
std::string closeFile(int fd, std::string why) {
  const int closed = ::close(fd);
  if (why.empty() && closed != 0) why = std::strerror(errno);
  return why;
}

// A stream buffer onto a file descriptor: 1 MiB buffered, larger writes passed straight
// through; the first error is kept and ends all writing.
class FileBuffer : public std::streambuf {
 public:
  explicit FileBuffer(int fd) : fd_(fd), buffer_(kSize) { reset(); }
  const std::string& error() const { return error_; }

 protected:
  int_type overflow(int_type c) override {
    if (!drain()) return traits_type::eof();
    if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
    *pptr() = traits_type::to_char_type(c);
    pbump(1);
    return c;
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    if (n < static_cast<std::streamsize>(kSize) / 4) return std::streambuf::xsputn(s, n);
    if (!drain() || !put(s, static_cast<std::size_t>(n))) return 0;
    return n;
  }
  int sync() override { return drain() ? 0 : -1; }

 private:
  static constexpr std::size_t kSize = std::size_t{1} << 20;
  void reset() { setp(buffer_.data(), buffer_.data() + buffer_.size()); }
  bool put(const char* data, std::size_t size) {
    if (error_.empty()) error_ = writeBytes(fd_, data, size);
    return error_.empty();
  }
  bool drain() {
    const bool ok = put(pbase(), static_cast<std::size_t>(pptr() - pbase()));
    reset();
    return ok;
  }

  int fd_;
  std::vector<char> buffer_;
  std::string error_;
};

// Writes the new file `path` with `write`, which puts bytes into the descriptor it is given and
// returns the OS's reason when that failed; the reason, or nothing.
std::string writeAll(const std::filesystem::path& path,
                     const std::function<std::string(int)>& write) {
  const int fd = createFile(path);
  if (fd < 0) return std::strerror(errno);
  std::string why;
  try {
    why = write(fd);
  } catch (...) {
    ::close(fd);
    throw;
  }
  return closeFile(fd, why);
}

}  // namespace

// `file` as the user will find it: under OUT, not under its staging folder.
std::string shownName(const std::filesystem::path& file) {
  const std::lock_guard<std::mutex> guard(shown().mutex);
  for (const auto& [stage, out] : shown().stage_to_out) {
    const auto [s, f] = std::mismatch(stage.begin(), stage.end(), file.begin(), file.end());
    if (s != stage.end()) continue;
    std::filesystem::path p = out;
    for (auto it = f; it != file.end(); ++it) p /= *it;
    return p.string();
  }
  return file.string();
}

namespace {

// Writes `file` through `file`.tmp (see writeAll) and renames it into place.
void publishFile(const std::filesystem::path& file, const std::function<std::string(int)>& write) {
  std::error_code ec;
  const std::filesystem::path tmp = file.string() + ".tmp";
  std::string why;
  try {
    why = writeAll(tmp, write);
  } catch (...) {
    std::filesystem::remove(tmp, ec);
    throw;
  }
  if (!why.empty()) {
    std::filesystem::remove(tmp, ec);
    throw InputError(fmt::format("{}: cannot write the file: {}", shownName(file), why));
  }
  std::filesystem::rename(tmp, file, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw InputError(fmt::format("{}: cannot move the finished file into place: {}", file.string(),
                                 ec.message()));
  }
}

}  // namespace

// No fsync: a file is complete once the process has written it, and the output folder is
// published as a whole (OutputStage), so a killed run leaves the old outputs or the new ones.
// What survives a power cut is left to the file system, as for every other program's output.
void writeFileAtomically(const std::filesystem::path& file, const std::string& content) {
  writeFileAtomically(file, {std::string_view(content)});
}

void writeFileAtomically(const std::filesystem::path& file,
                         std::initializer_list<std::string_view> pieces) {
  publishFile(file, [&](int fd) {
    for (const std::string_view piece : pieces) {
      std::string why = writeBytes(fd, piece.data(), piece.size());
      if (!why.empty()) return why;
    }
    return std::string();
  });
}

void writeFileAtomically(const std::filesystem::path& file,
                         const std::function<void(std::ostream&)>& fill) {
  publishFile(file, [&](int fd) {
    FileBuffer buffer(fd);
    std::ostream out(&buffer);
    fill(out);
    out.flush();
    if (!buffer.error().empty()) return buffer.error();
    return out ? std::string() : std::string("the stream failed");
  });
}

bool isRegularFile(const std::filesystem::path& file) noexcept {
  std::error_code ec;
  return std::filesystem::is_regular_file(file, ec);
}

namespace {

namespace fs = std::filesystem;

// `inner` is `outer` or lies inside it (both absolute and normal).
bool within(const fs::path& inner, const fs::path& outer) {
  const auto [o, i] = std::mismatch(outer.begin(), outer.end(), inner.begin(), inner.end());
  return o == outer.end();
}

}  // namespace

void checkOutputApartFromInputs(const fs::path& out,
                                const std::vector<fs::path>& inputs,
                                const std::string& option) {
  std::error_code ec;
  const fs::path o = fs::weakly_canonical(fs::absolute(out, ec), ec);
  if (ec) return;  // the output's own checks report what is wrong with it
  for (const fs::path& input : inputs) {
    std::error_code ie;
    const fs::path i = fs::weakly_canonical(fs::absolute(input, ie), ie);
    if (ie || i.empty()) continue;
    const bool clash = within(i, o) || within(o, i);
    if (!clash) continue;
    throw InputError(fmt::format(
        "{} {}: {} the input {}: writing there could replace it; expected an output apart from "
        "the inputs",
        option, out.string(),
        i == o         ? "is"
        : within(i, o) ? "holds"
                       : "lies inside",
        input.string()));
  }
}

void prepareOutputDir(const std::filesystem::path& dir) {
  std::error_code ec;
  if (std::filesystem::exists(dir, ec) && !std::filesystem::is_directory(dir, ec)) {
    throw InputError(
        fmt::format("{}: output folder is an existing file: expected a folder path", dir.string()));
  }
  std::filesystem::create_directories(dir, ec);
  if (ec) {
    throw InputError(
        fmt::format("{}: cannot create the output folder: {}", dir.string(), ec.message()));
  }
}

namespace {

namespace fs = std::filesystem;

// What an interrupt removes: staging folders and locks (whole), folders made for OUT (if empty).
// Publishing holds the mutex, so an interrupt waits for it to finish.
struct Cleanup {
  std::mutex mutex;
  std::vector<fs::path> remove;
  std::vector<fs::path> remove_if_empty;
};

Cleanup& cleanup() {
  static Cleanup c;
  return c;
}

void track(std::vector<fs::path> Cleanup::*list, const fs::path& p) {
  const std::lock_guard<std::mutex> guard(cleanup().mutex);
  (cleanup().*list).push_back(p);
}

void untrack(std::vector<fs::path> Cleanup::*list, const fs::path& p) {
  const std::lock_guard<std::mutex> guard(cleanup().mutex);
  auto& v = cleanup().*list;
  v.erase(std::remove(v.begin(), v.end(), p), v.end());
}

bool alive(long pid) {
  return pid > 0 && (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH);
}

// The start time of process `pid` (clock ticks after boot, /proc/<pid>/stat field 22), or -1
// when there is no such process. It tells a run from a later process that reuses its pid.
long long startTime(long pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string stat;
  std::getline(in, stat);
  const auto close = stat.rfind(')');  // the name in parentheses may hold spaces
  if (close == std::string::npos) return -1;
  std::istringstream fields(stat.substr(close + 1));
  std::string field;
  for (int i = 3; i <= 22 && fields >> field; ++i) {
    if (i == 22) return std::strtoll(field.c_str(), nullptr, 10);
  }
  return -1;
}

// A lock's holder: the pid and start time of the run that wrote it (0 and -1 when it names none).
struct LockHolder {
  long pid = 0;
  long long start = -1;
};

// The holder a lock file names. Anything but a regular file at the lock's name is not one
// scanplan wrote (a FIFO would block the read): refused, and left alone.
LockHolder lockHolder(const fs::path& lock, const fs::path& out_dir) {
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(lock, ec);
  if (!ec && fs::exists(status) && !fs::is_regular_file(status)) {
    throw InputError(fmt::format(
        "{}: {} is not a lock file scanplan wrote (a folder, link, pipe or device): expected "
        "nothing there, or a lock file; remove it or choose another output folder",
        out_dir.string(), lock.string()));
  }
  std::ifstream in(lock);
  LockHolder holder;
  in >> holder.pid;
  if (!in) return {};
  if (!(in >> holder.start)) holder.start = -1;
  return holder;
}

// The lock's run is still going: its pid names a process started when the run started (a lock
// without a start time: a process named scanplan). Any other process that now has the pid is
// not the run: the lock is stale.
bool holding(const LockHolder& holder) {
  if (holder.pid <= 0 || !alive(holder.pid)) return false;
  const long long start = startTime(holder.pid);
  if (start < 0) return true;  // no /proc to tell: alive is all we know
  if (holder.start >= 0) return start == holder.start;
  std::ifstream comm("/proc/" + std::to_string(holder.pid) + "/comm");
  std::string name;
  std::getline(comm, name);
  return name == "scanplan";
}

// OUT as an absolute path without a trailing separator; a symbolic link to a folder is followed
// (the folder it names is published).
fs::path absoluteOut(const fs::path& out) {
  fs::path p = fs::absolute(out).lexically_normal();
  if (!p.has_filename() && p.has_parent_path() && p != p.root_path()) p = p.parent_path();
  std::error_code ec;
  if (fs::is_symlink(p, ec)) {
    const fs::path target = fs::canonical(p, ec);
    if (ec) throw InputError(fmt::format("{}: the output folder is a broken link", out.string()));
    return target;
  }
  return p;
}

// The start of the hidden names beside OUT: `.NAME`, NAME cut to 150 bytes plus a hash of the
// rest when it is long (a file name holds 255 bytes at most).
std::string hiddenStem(const fs::path& out) {
  const std::string name = out.filename().string();
  if (name.size() <= 150) return "." + name;
  return fmt::format(".{}-{:016x}", name.substr(0, 150), std::hash<std::string>{}(name));
}

// A hidden name beside OUT: `.NAME.scanplan-<what>`.
fs::path beside(const fs::path& out, const std::string& what) {
  return out.parent_path() / (hiddenStem(out) + ".scanplan-" + what);
}

// Names `prefix` followed by a pid whose process is gone (or is ours: an earlier run that had
// our pid). Any other name: false.
bool leftBehind(const std::string& name, const std::string& prefix) {
  if (!name.starts_with(prefix) || name.size() == prefix.size()) return false;
  char* end = nullptr;
  const long pid = std::strtol(name.c_str() + prefix.size(), &end, 10);
  if (*end != '\0' || pid <= 0) return false;
  return pid == static_cast<long>(::getpid()) || !alive(pid);
}

}  // namespace

OutputLock::OutputLock(const fs::path& out_dir) : file_(beside(absoluteOut(out_dir), "lock")) {
  for (int attempt = 0; attempt < 2; ++attempt) {
    const int fd = ::open(file_.c_str(), O_CREAT | O_EXCL | O_WRONLY | O_CLOEXEC, 0644);
    if (fd >= 0) {
      const long self = static_cast<long>(::getpid());
      const std::string pid = fmt::format("{} {}\n", self, startTime(self));
      const bool written = ::write(fd, pid.data(), pid.size()) == static_cast<ssize_t>(pid.size());
      ::close(fd);
      if (!written) break;
      track(&Cleanup::remove, file_);
      return;
    }
    if (errno != EEXIST) break;
    const LockHolder holder = lockHolder(file_, out_dir);
    if (holding(holder)) {
      throw InputError(fmt::format(
          "{} is in use by pid {} (another scanplan run writing there): wait for it, or choose "
          "another output folder",
          out_dir.string(), holder.pid));
    }
    std::error_code ignored;
    fs::remove(file_, ignored);  // stale: its run ended without removing it
  }
  const int error = errno;
  throw InputError(fmt::format("{}: cannot create the lock file {}: {}", out_dir.string(),
                               file_.string(), std::strerror(error)));
}

OutputLock::~OutputLock() {
  std::error_code ec;
  fs::remove(file_, ec);
  untrack(&Cleanup::remove, file_);
}

namespace {

// Removes what killed runs left beside OUT (their staging folders, and the old OUT a fallback
// publish had moved aside) and inside it (staging folders of older versions). An old OUT of a
// run killed between its two renames is put back when OUT is missing.
void removeLeftovers(const fs::path& out) {
  std::error_code ec;
  const std::string name = out.filename().string();
  const std::string staging = "." + name + ".scanplan-staging-",
                    old = "." + name + ".scanplan-old-";
  for (const auto& e : fs::directory_iterator(out.parent_path(), ec)) {
    const std::string n = e.path().filename().string();
    std::error_code ignored;
    if (leftBehind(n, staging)) fs::remove_all(e.path(), ignored);
    if (!leftBehind(n, old)) continue;
    if (!fs::exists(out, ignored)) fs::rename(e.path(), out, ignored);
    fs::remove_all(e.path(), ignored);
  }
  for (const auto& e : fs::directory_iterator(out, ec)) {
    std::error_code ignored;
    if (leftBehind(e.path().filename().string(), ".scanplan-staging-"))
      fs::remove_all(e.path(), ignored);
  }
}

// Copies the tree at `from` to `to` with hard links for its files (a copy where a link is
// refused); false when it holds something else (a device, a FIFO, a socket) or is too deep or
// large to mirror, for the caller to fall back.
bool linkTree(const fs::path& from, const fs::path& to, int depth, std::size_t& entries) {
  constexpr int kMaxDepth = 64;
  constexpr std::size_t kMaxEntries = 100'000;
  if (depth > kMaxDepth || ++entries > kMaxEntries) return false;
  std::error_code ec;
  const fs::file_status st = fs::symlink_status(from, ec);
  if (fs::is_symlink(st)) {
    fs::copy_symlink(from, to, ec);
  } else if (fs::is_directory(st)) {
    fs::create_directory(to, ec);
    for (const auto& e : fs::directory_iterator(from, ec)) {
      if (!linkTree(e.path(), to / e.path().filename(), depth + 1, entries)) return false;
    }
  } else if (fs::is_regular_file(st)) {
    if (::link(from.c_str(), to.c_str()) != 0) fs::copy_file(from, to, ec);
  } else {
    return false;
  }
  return !ec;
}

// The working folder is OUT or inside it: exchanging OUT would leave the shell in the old one.
bool workingInside(const fs::path& out) {
  std::error_code ec;
  const fs::path cwd = fs::current_path(ec);
  const auto [o, c] = std::mismatch(out.begin(), out.end(), cwd.begin(), cwd.end());
  return !ec && o == out.end();
}

}  // namespace

OutputStage::OutputStage(fs::path out_dir, std::vector<std::string> owned)
    : out_(absoluteOut(out_dir)), owned_(std::move(owned)) {
  std::error_code ec;
  if (fs::exists(out_, ec) && !fs::is_directory(out_, ec)) {
    throw InputError(fmt::format("{}: output folder is an existing file: expected a folder path",
                                 out_dir.string()));
  }
  for (fs::path p = out_.parent_path(); !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
    if (p == p.parent_path()) break;
    created_parents_.push_back(p);
  }
  fs::create_directories(out_.parent_path(), ec);
  if (ec) {
    throw InputError(
        fmt::format("{}: cannot create the folder it goes in: {}", out_dir.string(), ec.message()));
  }
  for (const fs::path& p : created_parents_) track(&Cleanup::remove_if_empty, p);
  lock_ = std::make_unique<OutputLock>(out_);
  removeLeftovers(out_);
  stage_ = beside(out_, fmt::format("staging-{}", static_cast<long>(::getpid())));
  track(&Cleanup::remove, stage_);
  {
    const std::lock_guard<std::mutex> guard(shown().mutex);
    shown().stage_to_out.emplace_back(stage_, out_dir);
  }
  fs::create_directory(stage_, ec);
  if (ec) {
    throw InputError(fmt::format("{}: cannot create a staging folder {}: {}", out_dir.string(),
                                 stage_.string(), ec.message()));
  }
}

OutputStage::~OutputStage() {
  std::error_code ec;
  if (!committed_) fs::remove_all(stage_, ec);
  untrack(&Cleanup::remove, stage_);
  {
    const std::lock_guard<std::mutex> guard(shown().mutex);
    auto& v = shown().stage_to_out;
    v.erase(std::remove_if(v.begin(), v.end(), [&](const auto& e) { return e.first == stage_; }),
            v.end());
  }
  lock_.reset();
  for (const fs::path& p : created_parents_) {
    if (!committed_ && fs::is_empty(p, ec)) fs::remove(p, ec);
    untrack(&Cleanup::remove_if_empty, p);
  }
}

bool OutputStage::owned(const std::string& name) const {
  for (const std::string& o : owned_) {
    if (!o.empty() && o.back() == '*' ? name.starts_with(o.substr(0, o.size() - 1)) : name == o)
      return true;
  }
  return false;
}

void OutputStage::commit() {
  const std::lock_guard<std::mutex> guard(cleanup().mutex);  // an interrupt waits for this
  std::error_code ec;
  if (!fs::exists(out_, ec)) {
    fs::rename(stage_, out_, ec);
    if (ec) {
      throw InputError(fmt::format("{}: cannot move the finished output into place: {}",
                                   out_.string(), ec.message()));
    }
  } else if (!exchange()) {
    commitByEntries();
  }
  committed_ = true;
}

namespace {

// `path` is a folder, not a link to one.
bool realFolder(const fs::path& path) {
  std::error_code ec;
  return fs::is_directory(fs::symlink_status(path, ec));
}

bool present(const fs::path& path) {
  std::error_code ec;
  return fs::exists(fs::symlink_status(path, ec));
}

}  // namespace

// `rel` is a folder (not a link to one) both in OUT and in the staging folder.
bool OutputStage::bothFolders(const fs::path& rel) const {
  return realFolder(out_ / rel) && realFolder(stage_ / rel);
}

// An entry of OUT this run drops: one of its own outputs that it did not write again.
bool OutputStage::dropped(const fs::path& rel) const {
  return owned(rel.generic_string()) && !present(stage_ / rel);
}

// OUT's folder `rel`: its entries this run does not write again are linked into the staged folder
// (made if this run wrote none; folders merged the same way), but for those it drops, so that
// publishing keeps a user's files in the folders it writes into. A staged folder left empty of
// a folder that held only dropped entries is removed.
bool OutputStage::mergeFolder(const fs::path& rel, std::size_t& entries) const {
  std::error_code ec;
  const fs::path staged = stage_ / rel;
  const bool made = !present(staged);
  if (made) fs::create_directory(staged, ec);
  bool any = false;
  for (const auto& e : fs::directory_iterator(out_ / rel, ec)) {
    any = true;
    const fs::path sub = rel / e.path().filename();
    if (dropped(sub)) continue;
    if (realFolder(e.path()) && (!present(stage_ / sub) || realFolder(stage_ / sub))) {
      if (!mergeFolder(sub, entries)) return false;
    } else if (!present(stage_ / sub) && !linkTree(e.path(), stage_ / sub, 0, entries)) {
      return false;
    }
  }
  if (made && any && fs::is_empty(staged, ec)) fs::remove(staged, ec);
  return !ec;
}

// The staging folder, with OUT's other entries linked in, exchanged with OUT in one step; false
// when that cannot be done here.
bool OutputStage::exchange() {
  std::size_t entries = 0;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(out_, ec)) {
    const fs::path name = e.path().filename();
    if (dropped(name)) continue;
    if (realFolder(e.path()) && (!present(stage_ / name) || realFolder(stage_ / name))) {
      if (!mergeFolder(name, entries)) {
        why_ = fmt::format("{} holds a special file or too many entries", name.string());
        return false;
      }
      continue;
    }
    if (present(stage_ / name)) continue;
    carried_.push_back(name);
    if (!linkTree(e.path(), stage_ / name, 0, entries)) {
      why_ = fmt::format("{} holds a special file or too many entries", name.string());
      return false;
    }
  }
  if (ec) {
    why_ = ec.message();
    return false;
  }
  if (workingInside(out_)) {
    why_ = "it is the working folder or holds it";
    return false;
  }
  if (::renameat2(AT_FDCWD, stage_.c_str(), AT_FDCWD, out_.c_str(), RENAME_EXCHANGE) != 0) {
    const int error = errno;
    if (error == EINVAL || error == ENOSYS || error == EOPNOTSUPP || error == EBUSY ||
        error == EXDEV || error == EPERM) {
      why_ = std::strerror(error);
      return false;
    }
    throw InputError(fmt::format("{}: cannot publish the finished output: {}", out_.string(),
                                 std::strerror(error)));
  }
  fs::remove_all(stage_, ec);  // the old OUT
  return true;
}

// The fallback, for OUT's folder `rel`: its dropped entries removed (in its folders that this run
// writes nothing into too), and, when this run writes nothing into it (`remove_emptied`), the
// folder itself if that empties it.
void OutputStage::dropOwned(const fs::path& rel, bool remove_emptied) const {
  std::error_code ec;
  std::vector<fs::path> names;
  for (const auto& e : fs::directory_iterator(out_ / rel, ec)) names.push_back(e.path().filename());
  for (const fs::path& name : names) {
    if (dropped(rel / name)) {
      fs::remove_all(out_ / rel / name, ec);
    } else if (realFolder(out_ / rel / name) && !present(stage_ / rel / name)) {
      dropOwned(rel / name, true);
    }
  }
  if (remove_emptied && !names.empty() && fs::is_empty(out_ / rel, ec)) fs::remove(out_ / rel, ec);
}

// The fallback for a folder in both: the staged entries renamed into OUT's folder one by one
// (folders in both merged the same way), its dropped entries removed.
void OutputStage::moveInto(const fs::path& rel) const {
  std::error_code ec;
  std::vector<fs::path> staged;
  for (const auto& e : fs::directory_iterator(stage_ / rel, ec))
    staged.push_back(e.path().filename());
  dropOwned(rel, false);
  for (const fs::path& name : staged) {
    if (bothFolders(rel / name)) {
      moveInto(rel / name);
      continue;
    }
    fs::remove_all(out_ / rel / name, ec);
    fs::rename(stage_ / rel / name, out_ / rel / name, ec);
    if (ec) {
      throw InputError(fmt::format("{}: cannot move the finished output into place: {}",
                                   (out_ / rel / name).string(), ec.message()));
    }
  }
}

// The fallback: one rename per entry (a kill between them can mix old and new files).
void OutputStage::commitByEntries() {
  spdlog::warn("{}: cannot be swapped in one step ({}); moving the outputs one by one",
               out_.string(), why_);
  std::error_code ec;
  std::vector<fs::path> earlier, staged;  // listed first: the loops below change the folders
  for (const fs::directory_entry& e : fs::directory_iterator(out_)) earlier.push_back(e.path());
  for (const fs::directory_entry& e : fs::directory_iterator(stage_)) staged.push_back(e.path());
  for (const fs::path& p : earlier) {
    if (dropped(p.filename())) {
      fs::remove_all(p, ec);
    } else if (realFolder(p) && !present(stage_ / p.filename())) {
      dropOwned(p.filename(), true);
    }
  }
  for (const fs::path& p : staged) {
    if (std::find(carried_.begin(), carried_.end(), p.filename()) != carried_.end())
      continue;  // linked in for an exchange: already in OUT
    const fs::path target = out_ / p.filename();
    if (bothFolders(p.filename())) {  // merged: the user's files in it stay
      moveInto(p.filename());
      continue;
    }
    if (fs::is_directory(p)) fs::remove_all(target, ec);
    fs::rename(p, target, ec);
    if (ec) {
      throw InputError(fmt::format("{}: cannot move the finished output into place: {}",
                                   target.string(), ec.message()));
    }
  }
  fs::remove_all(stage_, ec);
}

void installInterruptHandler() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  std::thread([set] {
    int sig = 0;
    while (sigwait(&set, &sig) != 0) {
    }
    const std::lock_guard<std::mutex> guard(cleanup().mutex);  // a publish finishes first
    creationMutex().lock();  // kept: no writer creates anything from here on
    for (const fs::path& p : cleanup().remove) {
      std::error_code ec;
      for (int attempt = 0; attempt < 5 && fs::exists(p, ec); ++attempt) fs::remove_all(p, ec);
    }
    for (auto it = cleanup().remove_if_empty.rbegin(); it != cleanup().remove_if_empty.rend();
         ++it) {
      std::error_code ec;
      if (fs::is_empty(*it, ec)) fs::remove(*it, ec);
    }
    const char* what = sig == SIGINT ? "SIGINT" : "SIGTERM";
    std::fprintf(stderr, "scanplan: stopped by %s; outputs left as they were\n", what);
    std::fflush(stderr);
    ::_exit(128 + sig);
  }).detach();
}

Eigen::Vector4d quaternionWxyz(const Eigen::Matrix3d& R) {
  Eigen::Quaterniond q(R);
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1.0;
  return {q.w(), q.x(), q.y(), q.z()};
}

}  // namespace scanplan::cli
