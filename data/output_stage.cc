#include "jointlab/data/output_stage.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <set>
#include <system_error>
#include <vector>

#include <fmt/format.h>

#include "jointlab/core/error.h"

namespace jointlab::data {

namespace fs = std::filesystem;

namespace {

// The commands that commit their outputs through an OutputStage (require_committed looks for
// their unfinished commits).
constexpr const char* kCommittingCommands[] = {"process", "run", "build-model"};

// Serialises the commits (and their recovery) of concurrent runs into one folder.
class FolderLock {
 public:
  explicit FolderLock(const fs::path& dir)
      : fd_(::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC)) {
    if (fd_ < 0 || ::flock(fd_, LOCK_EX) != 0)
      throw InputError(where(dir.string(), 0, "cannot lock the output folder"));
  }
  ~FolderLock() { ::close(fd_); }
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_;
};

std::set<std::string> read_list(const fs::path& file) {
  std::set<std::string> names;
  std::ifstream in(file);
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) names.insert(line);
  return names;
}

// Completes a commit whose staging folder was renamed to `commit_dir` (idempotent, so a
// commit killed half-way is finished by the next run).
void roll_forward(const fs::path& dir, const fs::path& commit_dir, const std::string& command,
                  const std::function<bool(const std::string&)>& owned) {
  const fs::path manifest = commit_dir / ".manifest";
  const fs::path record = dir / fmt::format(".{}.outputs", command);
  std::error_code ec;
  // Killed after the manifest became the record: every new output is in place already (an
  // empty "fresh" list here would remove them all).
  if (!fs::exists(manifest)) {
    fs::remove_all(commit_dir, ec);
    return;
  }
  const std::set<std::string> fresh = read_list(manifest);
  std::set<std::string> old = read_list(record);
  if (owned && !fs::exists(record)) {  // a folder written before outputs were recorded
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
      const std::string name = it->path().filename().string();
      if ((it->is_regular_file() || it->is_directory()) && owned(name)) old.insert(name);
    }
  }
  for (const std::string& name : old) {
    if (!fresh.count(name) && name.find('/') == std::string::npos) fs::remove_all(dir / name, ec);
  }
  for (const std::string& name : fresh) {
    if (fs::exists(commit_dir / name)) {
      // A folder replaces the previous one whole (rename cannot replace a non-empty folder);
      // killed in between, the next run finishes the move from the commit folder.
      if (fs::is_directory(commit_dir / name) && fs::exists(dir / name))
        fs::remove_all(dir / name, ec);
      fs::rename(commit_dir / name, dir / name, ec);
      if (ec)
        throw InputError(
            where((dir / name).string(), 0, "cannot move the output into place: " + ec.message()));
    }
  }
  fs::rename(manifest, record, ec);
  fs::remove_all(commit_dir, ec);
}

}  // namespace

void require_complete_outputs(const fs::path& dir) {
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    const std::string suffix = ".commit";
    if (name.size() > suffix.size() + 1 && name.front() == '.' &&
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0 &&
        fs::exists(it->path() / ".manifest", ec)) {  // without it: nothing or all moved
      const std::string command = name.substr(1, name.size() - suffix.size() - 1);
      throw InputError(
          where(dir.string(), 0,
                fmt::format("a '{0}' run was killed while putting its results in place ({1} is "
                            "left): the folder may mix old and new results; re-run {0} into it",
                            command, name)));
    }
  }
}

void require_committed(const fs::path& file) {
  std::error_code ec;
  // Links resolved: a path through a link to the folder is the folder.
  const fs::path path = fs::weakly_canonical(fs::absolute(file, ec), ec);
  if (ec || path.empty()) return;
  // `inner`: the entry of `dir` that holds the file (its first component below dir).
  fs::path inner = path.filename();
  for (fs::path dir = path.parent_path(); !dir.empty(); dir = dir.parent_path()) {
    for (const char* command : kCommittingCommands) {
      const fs::path pending = dir / fmt::format(".{}.commit", command);
      // Without its manifest a commit folder has moved nothing yet or everything already
      // (roll_forward): the folder holds one run's results.
      if (!fs::exists(pending, ec) || !fs::exists(pending / ".manifest", ec)) continue;
      // Only the interrupted command's outputs, old or new, may be mixed; other files of the
      // folder (its inputs, the user's) are read as usual.
      std::set<std::string> outputs = read_list(pending / ".manifest");
      outputs.merge(read_list(dir / fmt::format(".{}.outputs", command)));
      if (!outputs.count(inner.string())) continue;
      throw InputError(where(
          file.string(), 0,
          fmt::format("this is a result of a '{0}' run into {1} that was killed while putting its "
                      "results in place ({2} is left): the folder may mix old and new results; "
                      "re-run {0} into {1}",
                      command, dir.string(), pending.filename().string())));
    }
    if (dir == dir.parent_path()) break;
    inner = dir.filename();
  }
}

OutputStage::OutputStage(fs::path dir, std::string command,
                         std::function<bool(const std::string&)> owned)
    : dir_(std::move(dir)), command_(std::move(command)), owned_(std::move(owned)) {
  std::error_code ec;
  // The outermost folder this stage creates, removed again if the command fails before
  // anything is in it.
  for (fs::path p = dir_; !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
    created_ = p;
    if (p == p.parent_path()) break;
  }
  fs::create_directories(dir_, ec);
  if (!fs::is_directory(dir_))
    throw InputError(where(dir_.string(), 0, "cannot create output directory"));
  {
    FolderLock lock(dir_);
    const fs::path pending = dir_ / fmt::format(".{}.commit", command_);
    if (fs::exists(pending)) roll_forward(dir_, pending, command_, owned_);
    remove_stale_temporaries(dir_);
  }
  stage_ = temporary_name(dir_, fmt::format(".{}.stage-", command_));
  claim_ = TemporaryClaim(stage_, true);
}

OutputStage::~OutputStage() {
  if (committed_) return;
  std::error_code ec;
  fs::remove_all(stage_, ec);
  if (created_.empty()) return;
  // Folders this stage created, from dir() up, while they are empty (fs::remove leaves a
  // folder that is not: another run may have put its stage there meanwhile).
  for (fs::path p = dir_;; p = p.parent_path()) {
    if (!fs::remove(p, ec) || p == created_ || p == p.parent_path()) break;
  }
}

void OutputStage::commit() {
  std::vector<std::string> names;
  std::error_code ec;
  for (fs::directory_iterator it(stage_, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (!(it->is_regular_file() || it->is_directory()) || is_temporary_name(name))
      throw InputError(where((stage_ / name).string(), 0, "unfinished output"));
    names.push_back(name);
  }
  if (ec) throw InputError(where(stage_.string(), 0, "cannot list the outputs: " + ec.message()));
  std::sort(names.begin(), names.end());
  std::string list;
  for (const std::string& n : names) list += n + "\n";
  write_file_atomically(stage_ / ".manifest", list);

  FolderLock lock(dir_);
  const fs::path pending = dir_ / fmt::format(".{}.commit", command_);
  if (fs::exists(pending)) roll_forward(dir_, pending, command_, owned_);
  fs::rename(stage_, pending, ec);  // the commit point
  if (ec) throw InputError(where(dir_.string(), 0, "cannot commit the outputs: " + ec.message()));
  committed_ = true;
  claim_.release();
  roll_forward(dir_, pending, command_, owned_);
}

}  // namespace jointlab::data
