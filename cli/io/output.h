#pragma once

#include <filesystem>
#include <functional>
#include <initializer_list>
#include <memory>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

namespace scanplan::cli {

/// Writes `content` to `file` through a temporary name in the same folder, then renames it
/// into place, so an interrupted run never leaves a half-written file. A failure is an
/// InputError naming the file and the OS's reason (e.g. "No space left on device").
void writeFileAtomically(const std::filesystem::path& file, const std::string& content);
/// The same for the concatenation of `pieces`, written one after the other (no joined copy).
void writeFileAtomically(const std::filesystem::path& file,
                         std::initializer_list<std::string_view> pieces);
/// The same for what `fill` writes to the stream it is given: a binary stream buffered straight
/// onto the temporary file, so a large file is never held whole in memory. An exception from
/// `fill` removes the temporary file and passes on.
void writeFileAtomically(const std::filesystem::path& file,
                         const std::function<void(std::ostream&)>& fill);

/// Whether `file` is a regular file (following links). Never throws: a path the OS cannot
/// look at (too long, a component not a folder, no permission) is not one.
bool isRegularFile(const std::filesystem::path& file) noexcept;

/// Refuses (InputError) an output path that is one of `inputs`, or a folder that holds one at
/// any depth, or lies inside one: writing there could replace a file the user gave. The error
/// names `option` (e.g. "-o"), the output, and the input it would clash with.
void checkOutputApartFromInputs(const std::filesystem::path& out,
                                const std::vector<std::filesystem::path>& inputs,
                                const std::string& option = "-o");

/// Creates the output folder (and parents); an existing file in the way is an InputError.
void prepareOutputDir(const std::filesystem::path& dir);

/// An exclusive claim on an output folder OUT: the file `.NAME.scanplan-lock` beside it (NAME is
/// OUT's name) holds our pid, created with O_EXCL. A second claim while the holder lives is an
/// InputError "OUT is in use by pid N"; the lock of a run that is gone is stale and taken over.
/// Released (and unregistered from the interrupt handler) on destruction.
class OutputLock {
 public:
  explicit OutputLock(const std::filesystem::path& out_dir);
  ~OutputLock();
  OutputLock(const OutputLock&) = delete;
  OutputLock& operator=(const OutputLock&) = delete;

 private:
  std::filesystem::path file_;
};

/// One command run's outputs, written into a staging folder beside OUT
/// (`.NAME.scanplan-staging-<pid>`, same file system) and published by commit() in one step:
/// the staging folder, completed with hard links to the files of OUT this command does not own,
/// takes OUT's place by an atomic exchange of the two folders (renameat2 RENAME_EXCHANGE), or by
/// one rename when OUT is new. A kill at any moment leaves the old complete OUT or the new one.
/// Where the file system cannot exchange folders (or OUT is the working folder or a mount
/// point), commit() falls back to one rename per entry and says so in a warning. OUT is locked
/// meanwhile (OutputLock). A run that fails or is interrupted leaves OUT as it was, and no OUT
/// when it did not exist; staging folders of runs that are gone are removed by the next run.
class OutputStage {
 public:
  /// `owned`: the names this command writes into the folder, as paths relative to OUT ("cloud.ply",
  /// "programs/scan.v2"; a trailing '*' matches any path with that prefix): on commit, the owned
  /// entries it did not write again are dropped, and everything else in OUT is kept, in the
  /// folders it writes into too ("programs/": a user's note there stays). An existing file in
  /// OUT's place is an InputError.
  OutputStage(std::filesystem::path out_dir, std::vector<std::string> owned);
  ~OutputStage();
  OutputStage(const OutputStage&) = delete;
  OutputStage& operator=(const OutputStage&) = delete;

  /// Where to write this run's outputs.
  const std::filesystem::path& dir() const { return stage_; }
  /// Publishes the staged outputs as OUT (see the class comment).
  void commit();

 private:
  bool owned(const std::string& name) const;
  bool bothFolders(const std::filesystem::path& rel) const;
  bool dropped(const std::filesystem::path& rel) const;
  void dropOwned(const std::filesystem::path& rel, bool remove_emptied) const;
  bool mergeFolder(const std::filesystem::path& rel, std::size_t& entries) const;
  bool exchange();
  void moveInto(const std::filesystem::path& rel) const;
  void commitByEntries();

  std::filesystem::path out_;
  std::filesystem::path stage_;
  std::vector<std::string> owned_;
  std::vector<std::filesystem::path> carried_;          // OUT's other entries, linked in
  std::vector<std::filesystem::path> created_parents_;  // made for OUT, removed on failure
  std::unique_ptr<OutputLock> lock_;
  std::string why_;  // why the folders were not exchanged
  bool committed_ = false;
};

/// SIGINT and SIGTERM end the process cleanly: the staging folders and locks of the running
/// command are removed (a publish under way finishes first), a line says so on stderr, and the
/// exit code is 130 (SIGINT) or 143 (SIGTERM). Call once, first thing in main(), before any
/// thread starts: it blocks both signals in every thread and waits for them in its own.
void installInterruptHandler();

/// Quaternion (w, x, y, z) with w ≥ 0.
Eigen::Vector4d quaternionWxyz(const Eigen::Matrix3d& R);

}  // namespace scanplan::cli
