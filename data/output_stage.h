// A command's output files and folders, which appear in their folder together or not at all.
//
// The command writes every output into a staging folder inside the output folder
// (DIR/.<command>.stage-XXXXXXXX, claimed while the command runs; a folder in it replaces
// the previous folder of its name whole); commit() lists them
// in a manifest and renames the staging folder to DIR/.<command>.commit, the one atomic
// step that decides between the old and the new set. It then removes the previous
// outputs of the command that the new set does not replace, moves the new files into
// place and keeps the manifest as DIR/.<command>.outputs. A failure before that step
// leaves the previous outputs untouched; a run killed after it is completed by the next
// OutputStage on the folder, which also removes staging folders and temporaries that
// killed runs left behind.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

#include "jointlab/data/atomic_file.h"

namespace jointlab::data {

/// Staging folder for one command's outputs into one folder, committed as a set.
class OutputStage {
 public:
  /// Prepares `dir` (created if missing) for the outputs of `command`; `owned` says which
  /// file names the command writes, so that in a folder written before outputs were
  /// recorded (no DIR/.<command>.outputs) the old ones are replaced as well (none when
  /// empty). Throws InputError if `dir` cannot be made. Folders it creates for `dir` are
  /// removed again when the stage ends uncommitted and they are empty.
  OutputStage(std::filesystem::path dir, std::string command,
              std::function<bool(const std::string&)> owned = {});
  /// Removes the staging folder and everything in it unless committed; then also the
  /// folders the constructor created for `dir`, as far as they are empty.
  ~OutputStage();
  OutputStage(const OutputStage&) = delete;
  OutputStage& operator=(const OutputStage&) = delete;

  /// The folder to write the outputs into, under the names they get in dir().
  const std::filesystem::path& path() const { return stage_; }
  /// The output folder.
  const std::filesystem::path& dir() const { return dir_; }
  /// Makes the staged files the command's outputs in dir(), replacing the previous ones as a
  /// set; throws InputError if that cannot start (the previous outputs stay).
  void commit();

 private:
  std::filesystem::path dir_, stage_;
  std::filesystem::path created_;  // the outermost folder the constructor created, or empty
  std::string command_;
  std::function<bool(const std::string&)> owned_;
  TemporaryClaim claim_;
  bool committed_ = false;
};

/// For readers of a command's output folder: InputError naming `dir` when it holds an
/// unfinished commit (DIR/.<command>.commit: a run was killed while moving its outputs into
/// place, so the folder may mix old and new results), saying to re-run the command, whose
/// OutputStage completes the commit first. A folder without one holds exactly one run's
/// outputs (the rename to .<command>.commit is the commit point).
void require_complete_outputs(const std::filesystem::path& dir);

/// For every reader of a file, before reading it (require_regular_file calls it): InputError
/// naming `file` when it lies in an output of a `process`, `run` or `build-model` commit that
/// was killed half-way (an ancestor folder DIR holds DIR/.<command>.commit and the entry of
/// DIR that holds `file` is among that command's old or new outputs), saying to re-run the
/// command into DIR. So a reader of anything in `run`'s folder (DIR/hits/..., DIR/model/...)
/// sees one run's results or refuses, as summary.json's readers do for `process`. Other files
/// of such a folder (the inputs, the user's own) are not refused.
void require_committed(const std::filesystem::path& file);

}  // namespace jointlab::data
