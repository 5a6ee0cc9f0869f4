#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace scanplan::cli {

/// Writes `content` to `file` through a temporary name in the same folder, then renames it
/// into place, so an interrupted run never leaves a half-written file.
void writeFileAtomically(const std::filesystem::path& file, const std::string& content);

/// Creates the output folder (and parents); an existing file in the way is an InputError.
void prepareOutputDir(const std::filesystem::path& dir);

/// One command run's outputs, written into a staging folder inside the output folder and moved
/// into place together by commit(). The folder is locked meanwhile (OUT/.scanplan-lock holds
/// the pid): a second run into it is an InputError "OUT is in use by pid N"; the lock of a
/// killed run is stale and taken over. A run that fails or is interrupted leaves the output folder
/// as it was (and removes it again if the run created it); on commit, files of an earlier run
/// that this run does not write are removed, so a stale trajectory.csv or program never sits
/// next to a new report.
class OutputStage {
 public:
  /// `owned`: the names this command writes into the folder (files or folders; a trailing '*'
  /// matches any name with that prefix). Creates the output folder and the staging folder; an
  /// existing file in the way is an InputError.
  OutputStage(std::filesystem::path out_dir, std::vector<std::string> owned);
  ~OutputStage();
  OutputStage(const OutputStage&) = delete;
  OutputStage& operator=(const OutputStage&) = delete;

  /// Where to write this run's outputs.
  const std::filesystem::path& dir() const { return stage_; }
  /// Moves every staged entry into the output folder and removes the owned entries it did not
  /// stage.
  void commit();

 private:
  bool owned(const std::string& name) const;
  void lock();
  void unlock();

  std::filesystem::path out_;
  std::filesystem::path stage_;
  std::vector<std::string> owned_;
  bool created_out_ = false;
  bool committed_ = false;
  bool locked_ = false;
};

/// Quaternion (w, x, y, z) with w ≥ 0.
Eigen::Vector4d quaternionWxyz(const Eigen::Matrix3d& R);

}  // namespace scanplan::cli
