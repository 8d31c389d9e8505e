// OutputStage and AtomicFile: outputs appear as a set or not at all, a failed write leaves
// nothing, and what a killed run left is completed or removed by the next one.
#include "jointlab/data/output_stage.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/data/atomic_file.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::data {
namespace {

namespace fs = std::filesystem;

void put(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::directory_iterator(dir))
    files[e.path().filename().string()] = e.is_directory() ? "<dir>" : testing::read_file(e.path());
  return files;
}

fs::path fresh_dir(const std::string& name) {
  const fs::path d = testing::scratch_path("jointlab-stage-test", name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// fresh_dir(name) holding the outputs of a committed run of "cmd": a.csv, "old".
fs::path with_old_output(const std::string& name) {
  const fs::path dir = fresh_dir(name);
  OutputStage s(dir, "cmd");
  put(s.path() / "a.csv", "old");
  s.commit();
  return dir;
}

bool is_csv(const std::string& name) { return name.ends_with(".csv"); }

TEST(OutputStage, CommitReplacesThePreviousSetAsAWhole) {
  const fs::path dir = fresh_dir("replace");
  put(dir / "keep.txt", "not an output");
  {
    OutputStage s(dir, "cmd", is_csv);
    put(s.path() / "a.csv", "a1");
    put(s.path() / "b.csv", "b1");
    EXPECT_FALSE(fs::exists(dir / "a.csv"));  // nothing appears before commit
    s.commit();
  }
  EXPECT_EQ(snapshot(dir), (std::map<std::string, std::string>{{".cmd.outputs", "a.csv\nb.csv\n"},
                                                               {"a.csv", "a1"},
                                                               {"b.csv", "b1"},
                                                               {"keep.txt", "not an output"}}));
  put(dir / "mine.csv", "written by the user after the run");
  {
    OutputStage s(dir, "cmd", is_csv);
    put(s.path() / "b.csv", "b2");
    s.commit();
  }
  EXPECT_EQ(snapshot(dir), (std::map<std::string, std::string>{
                               {".cmd.outputs", "b.csv\n"},
                               {"b.csv", "b2"},
                               {"keep.txt", "not an output"},
                               {"mine.csv", "written by the user after the run"}}));
  // A folder of an older version (no record): the command's own names identify its outputs.
  fs::remove(dir / ".cmd.outputs");
  {
    OutputStage s(dir, "cmd", is_csv);
    put(s.path() / "c.csv", "c3");
    s.commit();
  }
  EXPECT_EQ(snapshot(dir),
            (std::map<std::string, std::string>{
                {".cmd.outputs", "c.csv\n"}, {"c.csv", "c3"}, {"keep.txt", "not an output"}}));
}

// A folder among the outputs replaces the previous folder of its name whole (none of its
// old files survive), also when a killed commit is completed by the next run; an owned
// folder the new set lacks is removed.
TEST(OutputStage, FoldersReplaceThePreviousFolderWhole) {
  const fs::path dir = fresh_dir("folders");
  const auto owned = [](const std::string& n) { return n == "figs" || n == "old"; };
  fs::create_directories(dir / "old");
  put(dir / "old" / "x.png", "from an older version");
  {
    OutputStage s(dir, "cmd", owned);
    fs::create_directories(s.path() / "figs" / "sub");
    put(s.path() / "figs" / "a.png", "a1");
    put(s.path() / "figs" / "sub" / "b.png", "b1");
    s.commit();
  }
  EXPECT_FALSE(fs::exists(dir / "old"));
  EXPECT_EQ(testing::read_file(dir / "figs" / "sub" / "b.png"), "b1");
  {
    OutputStage s(dir, "cmd", owned);
    fs::create_directories(s.path() / "figs");
    put(s.path() / "figs" / "c.png", "c2");
    s.commit();
  }
  EXPECT_EQ(snapshot(dir / "figs"), (std::map<std::string, std::string>{{"c.png", "c2"}}));
  // Killed after the commit point: the next run moves the new folder into place.
  fs::create_directories(dir / ".cmd.commit" / "figs");
  put(dir / ".cmd.commit" / ".manifest", "figs\n");
  put(dir / ".cmd.commit" / "figs" / "d.png", "d3");
  { OutputStage next(dir, "cmd", owned); }
  EXPECT_EQ(snapshot(dir / "figs"), (std::map<std::string, std::string>{{"d.png", "d3"}}));
  EXPECT_EQ(snapshot(dir),
            (std::map<std::string, std::string>{{".cmd.outputs", "figs\n"}, {"figs", "<dir>"}}));
}

TEST(OutputStage, AFailureBeforeCommitLeavesThePreviousOutputs) {
  const fs::path dir = with_old_output("fail");
  const auto before = snapshot(dir);
  try {
    OutputStage s(dir, "cmd");
    put(s.path() / "a.csv", "new");
    write_file_atomically(s.path() / "b.csv", "new");
    throw InputError("the next input is bad");
  } catch (const InputError&) {
  }
  EXPECT_EQ(snapshot(dir), before);
}

TEST(OutputStage, KilledRunsAreCleanedUpOrCompletedByTheNext) {
  const fs::path dir = with_old_output("killed");
  const auto before = snapshot(dir);
  // A run killed while writing: its staging folder and a temporary stay behind.
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    OutputStage s(dir, "cmd");
    put(s.path() / "a.csv", "half");
    AtomicFile f(dir / "other.txt");
    f.stream() << "half";
    f.stream().flush();
    kill(getpid(), SIGKILL);
  }
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_GT(snapshot(dir).size(), before.size());  // the leftovers are there ...
  auto after_kill = snapshot(dir);
  for (const auto& [name, text] : before)
    EXPECT_EQ(after_kill.at(name), text);  // ... beside the old set

  // Killed before its commit point, the folder is still exactly the old set for a reader.
  EXPECT_NO_THROW(require_complete_outputs(dir));

  // A run killed after its commit point (staging folder renamed, files not yet moved): a
  // reader refuses the folder, saying to re-run, until the next run completes the commit.
  fs::create_directory(dir / ".cmd.commit");
  put(dir / ".cmd.commit" / ".manifest", "b.csv\n");
  put(dir / ".cmd.commit" / "b.csv", "new");
  const std::string m = testing::input_error_of([&] { require_complete_outputs(dir); });
  EXPECT_NE(m.find("a 'cmd' run was killed while putting its results in place (.cmd.commit is "
                   "left): the folder may mix old and new results; re-run cmd into it"),
            std::string::npos)
      << m;
  {
    OutputStage next(dir, "cmd");  // completes the commit and removes the leftovers
    EXPECT_EQ(snapshot(dir),
              (std::map<std::string, std::string>{{".cmd.outputs", "b.csv\n"},
                                                  {next.path().filename().string(), "<dir>"},
                                                  {"b.csv", "new"}}));
  }
  EXPECT_EQ(snapshot(dir),
            (std::map<std::string, std::string>{{".cmd.outputs", "b.csv\n"}, {"b.csv", "new"}}));
  EXPECT_NO_THROW(require_complete_outputs(dir));
}

// A reader of any file inside a `run` folder whose commit was killed half-way (hits/, model/,
// ...) refuses it with one line saying to re-run; the folder's other files (inputs) are read.
TEST(OutputStage, ReadersRefuseTheOutputsOfAnUnfinishedCommitAtAnyDepth) {
  const fs::path dir = fresh_dir("run-readers");
  {
    OutputStage s(dir, "run");
    fs::create_directories(s.path() / "hits" / "all");
    put(s.path() / "hits" / "all" / "hit1.a.band1.csv", "old");
    put(s.path() / "report.md", "old");
    s.commit();
  }
  put(dir / "campaign.toml", "an input beside the outputs");
  EXPECT_NO_THROW(require_committed(dir / "hits" / "all" / "hit1.a.band1.csv"));
  // Killed after the commit point: hits/ was already replaced, report.md not yet.
  fs::create_directories(dir / ".run.commit");
  put(dir / ".run.commit" / ".manifest", "hits\nreport.md\nscatter\n");
  put(dir / ".run.commit" / "report.md", "new");
  for (const fs::path& f : {dir / "hits" / "all" / "hit1.a.band1.csv", dir / "report.md",
                            dir / "scatter" / "mode1.json"}) {  // a new output not there yet
    const std::string m = testing::input_error_of([&] { require_committed(f); });
    EXPECT_NE(m.find(f.string() + ": this is a result of a 'run' run into " + dir.string() +
                     " that was killed while putting its results in place (.run.commit is "
                     "left): the folder may mix old and new results; re-run run into " +
                     dir.string()),
              std::string::npos)
        << m;
  }
  EXPECT_NO_THROW(require_committed(dir / "campaign.toml"));
  EXPECT_NO_THROW(require_committed(fresh_dir("elsewhere") / "x.csv"));
  { OutputStage next(dir, "run"); }  // completes the commit
  EXPECT_NO_THROW(require_committed(dir / "report.md"));
  EXPECT_EQ(testing::read_file(dir / "report.md"), "new");
}

// Killed between recording the new outputs and removing the commit folder: every new output is
// in place, and the next run keeps them (it once removed them all).
TEST(OutputStage, ACommitKilledAfterItsRecordKeepsTheNewOutputs) {
  const fs::path dir = with_old_output("recorded");
  fs::create_directories(dir / ".cmd.commit");  // its manifest is .cmd.outputs now
  { OutputStage next(dir, "cmd"); }
  EXPECT_EQ(snapshot(dir),
            (std::map<std::string, std::string>{{".cmd.outputs", "a.csv\n"}, {"a.csv", "old"}}));
}

TEST(OutputStage, ARunningWritersFilesAreSpared) {
  const fs::path dir = fresh_dir("running");
  OutputStage running(dir, "cmd");
  AtomicFile writing(dir / "x.csv");
  writing.stream() << "in progress";
  put(dir / "y.csv.tmp-0123abcd", "stale");
  OutputStage other(dir, "cmd");
  EXPECT_TRUE(fs::is_directory(running.path()));
  EXPECT_FALSE(fs::exists(dir / "y.csv.tmp-0123abcd"));
  writing.commit();
  EXPECT_EQ(testing::read_file(dir / "x.csv"), "in progress");
}

TEST(AtomicFile, AFailedWriteLeavesNothing) {
  const fs::path dir = fresh_dir("atomic");
  put(dir / "r.txt", "previous");
  AtomicFile f(dir / "r.txt");
  f.stream() << "new";
  f.stream().setstate(std::ios::badbit);  // what a write on a full disk does to the stream
  const std::string m = testing::input_error_of([&] { f.commit(); });
  EXPECT_NE(m.find("r.txt: write failed (disk full?)"), std::string::npos) << m;
  EXPECT_EQ(snapshot(dir), (std::map<std::string, std::string>{{"r.txt", "previous"}}));
}

TEST(AtomicFile, TemporaryNames) {
  EXPECT_TRUE(is_temporary_name("a.csv.tmp-0123abcd"));
  EXPECT_TRUE(is_temporary_name(".fig.png.tmp-0123abcd.png"));
  EXPECT_TRUE(is_temporary_name(".process.stage-89abcdef"));
  EXPECT_FALSE(is_temporary_name("a.csv"));
  EXPECT_FALSE(is_temporary_name("a.tmp-xyz"));
  EXPECT_FALSE(is_temporary_name("process.stage-89abcdef"));
}

// Killed after its manifest became the outputs record but before the empty commit folder was
// removed: every new output is in place, so readers read the folder (it was refused, although
// it held one run's results alone).
TEST(OutputStage, ACommitFolderWithoutItsManifestIsNotRefused) {
  const fs::path dir = fresh_dir("done-not-cleaned");
  {
    OutputStage s(dir, "run");
    put(s.path() / "report.md", "new");
    s.commit();
  }
  fs::create_directories(dir / ".run.commit");
  EXPECT_NO_THROW(require_committed(dir / "report.md"));
  EXPECT_NO_THROW(require_complete_outputs(dir));
  // Through a link to the folder, an unfinished commit is seen all the same.
  put(dir / ".run.commit" / ".manifest", "report.md\n");
  const fs::path link = dir.parent_path() / (dir.filename().string() + "-link");
  fs::remove(link);
  fs::create_directory_symlink(dir, link);
  EXPECT_THROW(require_committed(link / "report.md"), InputError);
  fs::remove(link);
}

}  // namespace
}  // namespace jointlab::data
