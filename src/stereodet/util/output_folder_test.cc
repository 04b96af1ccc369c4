#include "stereodet/util/output_folder.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>

#include "stereodet/util/atomic_file.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {
namespace fs = std::filesystem;
using State = OutputFolderIdentity::State;

class OutputFolderTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = temp_.path(); }
  size_t CountFiles() const {
    size_t n = 0;
    for (const auto& entry : fs::recursive_directory_iterator(dir_)) n += entry.is_regular_file();
    return n;
  }
  // A folder whose run.json names `tool`.
  fs::path WithRunJson(const std::string& name, const std::string& tool) {
    RunManifest manifest;
    manifest.tool = tool;
    manifest.version = "0";
    WriteRunManifest(dir_ / name, manifest);
    return dir_ / name;
  }
  // The message CheckOutputFolderOwner throws, or "" when it accepts.
  static std::string Refusal(const fs::path& dir, const std::string& command,
                             const std::vector<std::string>& makers) {
    try {
      CheckOutputFolderOwner(dir, command, makers);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  }
  TestTempDir temp_;
  fs::path dir_;
};

// A PID that ran and is gone: a child that exited and was reaped.
pid_t DeadPid() {
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  int status = 0;
  ::waitpid(child, &status, 0);
  return child;
}

TEST_F(OutputFolderTest, AbsentAndEmptyFoldersAreFreeForAnyCommand) {
  EXPECT_EQ(IdentifyOutputFolder(dir_ / "new").state, State::kAbsent);
  fs::create_directories(dir_ / "empty");
  EXPECT_EQ(IdentifyOutputFolder(dir_ / "empty").state, State::kEmpty);
  // Our own temporary files left by a killed run do not make a folder someone's.
  WriteFileAtomically(dir_ / "leftover" / ".000001.tmp-123-0.txt", "half");
  EXPECT_EQ(IdentifyOutputFolder(dir_ / "leftover").state, State::kEmpty);
  // A hidden file of someone else's does.
  WriteFileAtomically(dir_ / "repo" / ".gitignore", "*");
  EXPECT_EQ(IdentifyOutputFolder(dir_ / "repo").state, State::kForeign);
  EXPECT_EQ(Refusal(dir_ / "new", "eval", {kMakerEval}), "");
  EXPECT_EQ(Refusal(dir_ / "empty", "eval", {kMakerEval}), "");
}

TEST_F(OutputFolderTest, EachCommandsMarkerNamesItsMaker) {
  WithRunJson("dets", "detect ssd");
  WriteFileAtomically(dir_ / "dets" / "000001.txt", "");
  EXPECT_EQ(IdentifyOutputFolder(dir_ / "dets").maker, "detect ssd");

  WriteFileAtomically(dir_ / "eval" / "results.json", "{}");
  EXPECT_EQ(IdentifyOutputFolder(dir_ / "eval").maker, kMakerEval);

  WriteFileAtomically(dir_ / "report" / "index.html",
                      "<script type=\"application/json\" id=\"stereodet-figures\">[]</script>");
  EXPECT_EQ(IdentifyOutputFolder(dir_ / "report").maker, kMakerReport);
  WriteFileAtomically(dir_ / "website" / "index.html", "<html>my site</html>");
  EXPECT_EQ(IdentifyOutputFolder(dir_ / "website").state, State::kForeign);

  // stereo: stereo.json and a run.json of "stereo", beside KITTI-named folders it writes.
  WithRunJson("stereo", "stereo");
  WriteFileAtomically(dir_ / "stereo" / "stereo.json", "{}");
  WriteFileAtomically(dir_ / "stereo" / "velodyne" / "000001.bin", "");
  WriteFileAtomically(dir_ / "stereo" / "image_2" / "000001.png", "");
  const OutputFolderIdentity stereo = IdentifyOutputFolder(dir_ / "stereo");
  EXPECT_EQ(stereo.state, State::kMarked);
  EXPECT_EQ(stereo.maker, kMakerStereo);

  // synth: a KITTI data set with its settings file.
  WriteFileAtomically(dir_ / "synth" / "synth_settings.txt", "seed=1\n");
  WriteFileAtomically(dir_ / "synth" / "training" / "image_2" / "000000.png", "");
  EXPECT_EQ(IdentifyOutputFolder(dir_ / "synth").maker, kMakerSynth);
}

TEST_F(OutputFolderTest, ModelFoldersBelongToTheirTrainingOnly) {
  const fs::path model = WithRunJson("ssd-rgb", "train ssd");
  WriteFileAtomically(model / "model.json", R"({"architecture": "ssd"})");
  WriteFileAtomically(model / "model.pt", "weights");
  EXPECT_EQ(IdentifyOutputFolder(model).maker, "train ssd");
  EXPECT_EQ(Refusal(model, "train ssd", {"train ssd"}), "");
  // Another family's training, and every detect, must not replace it.
  EXPECT_NE(Refusal(model, "train rpn", {"train rpn"}), "");
  const std::string refusal = Refusal(model, "detect ssd", DetectionFolderMakers());
  EXPECT_NE(refusal.find("detect ssd: " + model.string() +
                         " is a model folder (model.json, "
                         "model.pt; run.json of 'train ssd')"),
            std::string::npos)
      << refusal;
  EXPECT_NE(refusal.find("detect ssd, detect rpn, detect det3d or run made"), std::string::npos)
      << refusal;

  // Without run.json, model.json's architecture says which training made it.
  WriteFileAtomically(dir_ / "old-model" / "model.json", R"({"architecture": "det3d"})");
  EXPECT_EQ(IdentifyOutputFolder(dir_ / "old-model").maker, "train det3d");
  // Weights with nothing to say who made them are nobody's to replace.
  WriteFileAtomically(dir_ / "weights" / "model.pt", "weights");
  EXPECT_EQ(IdentifyOutputFolder(dir_ / "weights").state, State::kForeign);
  // A detection folder that a training wrote into is a mix: nobody's.
  const fs::path mixed = WithRunJson("mixed", "detect ssd");
  WriteFileAtomically(mixed / "model.json", R"({"architecture": "ssd"})");
  EXPECT_EQ(IdentifyOutputFolder(mixed).state, State::kForeign);
  EXPECT_NE(Refusal(mixed, "detect ssd", DetectionFolderMakers()), "");
  EXPECT_NE(Refusal(mixed, "train ssd", {"train ssd"}), "");
}

TEST_F(OutputFolderTest, KittiDataSetsAreNobodysOutputUnlessSynthOrStereoMadeThem) {
  // A real KITTI download: no marker at all.
  WriteFileAtomically(dir_ / "kitti" / "training" / "image_2" / "000000.png", "");
  WriteFileAtomically(dir_ / "kitti" / "ImageSets" / "val.txt", "000000\n");
  const OutputFolderIdentity kitti = IdentifyOutputFolder(dir_ / "kitti");
  EXPECT_EQ(kitti.state, State::kForeign);
  EXPECT_NE(kitti.description.find("a KITTI data set (it holds training/, ImageSets/)"),
            std::string::npos)
      << kitti.description;
  EXPECT_NE(Refusal(dir_ / "kitti", "synth", {kMakerSynth}), "");
  // Its subset folder too (stereo --out OTHER/training).
  WriteFileAtomically(dir_ / "kitti" / "training" / "calib" / "000000.txt", "");
  EXPECT_NE(Refusal(dir_ / "kitti" / "training", "stereo", {kMakerStereo}), "");
  // A run.json of detect dropped into a data set does not make it a detection folder.
  WithRunJson("kitti/training", "detect ssd");
  EXPECT_EQ(IdentifyOutputFolder(dir_ / "kitti" / "training").state, State::kForeign);
}

TEST_F(OutputFolderTest, MixedAndUnreadableMarkersAreForeign) {
  WithRunJson("both", "detect rpn");
  WriteFileAtomically(dir_ / "both" / "results.json", "{}");
  EXPECT_EQ(IdentifyOutputFolder(dir_ / "both").state, State::kForeign);
  WriteFileAtomically(dir_ / "broken" / "run.json", "{not json");
  const OutputFolderIdentity broken = IdentifyOutputFolder(dir_ / "broken");
  EXPECT_EQ(broken.state, State::kForeign);
  EXPECT_NE(broken.description.find("an unreadable run.json"), std::string::npos);
  WriteFileAtomically(dir_ / "plain_file", "x");
  EXPECT_THROW(IdentifyOutputFolder(dir_ / "plain_file"), std::runtime_error);
}

TEST_F(OutputFolderTest, EveryCommandAgainstEveryOtherCommandsFolder) {
  // Each command's own folder, as it marks it.
  WithRunJson("detect", "detect det3d");
  WriteFileAtomically(dir_ / "eval" / "results.json", "{}");
  WriteFileAtomically(dir_ / "report" / "index.html", "<p id=\"stereodet-figures\"></p>");
  WithRunJson("stereo", "stereo");
  WriteFileAtomically(dir_ / "stereo" / "stereo.json", "{}");
  WriteFileAtomically(dir_ / "synth" / "synth_settings.txt", "seed=1\n");
  WithRunJson("train", "train rpn");
  WriteFileAtomically(dir_ / "train" / "model.pt", "w");
  const std::vector<std::pair<std::string, std::vector<std::string>>> commands = {
      {"detect", DetectionFolderMakers()}, {"eval", {kMakerEval}},   {"report", {kMakerReport}},
      {"stereo", {kMakerStereo}},          {"synth", {kMakerSynth}}, {"train", {"train rpn"}}};
  for (const auto& [command, makers] : commands) {
    for (const auto& [folder, unused] : commands) {
      const std::string refusal = Refusal(dir_ / folder, command, makers);
      if (command == folder) {
        EXPECT_EQ(refusal, "") << command << " into its own folder";
      } else {
        EXPECT_NE(refusal, "") << command << " into the folder of " << folder;
      }
    }
  }
}

// StagedFolder: one run per folder.
TEST_F(OutputFolderTest, StagedFolderReplacesAnEarlierRunWhole) {
  const fs::path out = dir_ / "results";
  {
    StagedFolder run1(out, "eval", {kMakerEval});
    WriteFileAtomically(run1.path() / "results.json", "1");
    WriteFileAtomically(run1.path() / "curves" / "only_in_run1.csv", "x");
    EXPECT_FALSE(fs::exists(out));  // nothing visible before the commit
    run1.Commit();
  }
  EXPECT_EQ(ReadFile(out / "results.json"), "1");
  {
    StagedFolder run2(out / "", "eval", {kMakerEval});  // a trailing separator: the same folder
    WriteFileAtomically(run2.path() / "results.json", "2");
    EXPECT_EQ(ReadFile(out / "results.json"), "1");  // the old run stays whole until the commit
    run2.Commit();
  }
  EXPECT_EQ(ReadFile(out / "results.json"), "2");
  EXPECT_FALSE(fs::exists(out / "curves" / "only_in_run1.csv"));  // no stale file of run 1
  EXPECT_EQ(CountFiles(), 1u);  // no staging or old folder left beside it
}

TEST_F(OutputFolderTest, UncommittedStagedFolderLeavesThePreviousRun) {
  const fs::path out = dir_ / "results";
  WriteFileAtomically(out / "results.json", "old");
  {
    StagedFolder run(out, "eval", {kMakerEval});
    WriteFileAtomically(run.path() / "results.json", "new");
  }  // interrupted: no Commit()
  EXPECT_EQ(ReadFile(out / "results.json"), "old");
  EXPECT_EQ(CountFiles(), 1u);
}

TEST_F(OutputFolderTest, StagedFolderRefusesAFolderOfSomethingElse) {
  WriteFileAtomically(dir_ / "home" / "thesis.tex", "precious");
  try {
    StagedFolder refused(dir_ / "home", "eval", {kMakerEval});
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("is a folder of other files (thesis.tex)"),
              std::string::npos)
        << e.what();
  }
  WriteFileAtomically(dir_ / "plain_file", "x");
  EXPECT_THROW(StagedFolder(dir_ / "plain_file", "eval", {kMakerEval}), std::runtime_error);
  EXPECT_EQ(ReadFile(dir_ / "home" / "thesis.tex"), "precious");
  fs::create_directories(dir_ / "empty");
  StagedFolder ok(dir_ / "empty", "eval", {kMakerEval});  // an empty folder is fine
  ok.Commit();
  EXPECT_TRUE(fs::is_directory(dir_ / "empty"));
}

TEST_F(OutputFolderTest, StagedFolderSaysTheParentMustBeWritable) {
  if (::geteuid() == 0) GTEST_SKIP() << "root writes into read-only folders";
  fs::create_directories(dir_ / "locked");
  fs::permissions(dir_ / "locked", fs::perms::owner_read | fs::perms::owner_exec);
  try {
    StagedFolder refused(dir_ / "locked" / "out", "eval", {kMakerEval});
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("must be writable"), std::string::npos) << e.what();
  }
  fs::permissions(dir_ / "locked", fs::perms::owner_all);
}

TEST_F(OutputFolderTest, StaleTemporariesOfDeadRunsAreRemovedLiveOnesKept) {
  const pid_t dead = DeadPid();
  const std::string live = std::to_string(::getpid());
  const fs::path out = dir_ / "dets";
  WithRunJson("dets", "detect ssd");
  const fs::path stale_staging = dir_ / (".dets.staging-" + std::to_string(dead) + "-0");
  const fs::path stale_old = dir_ / (".dets.old-" + std::to_string(dead) + "-3");
  const fs::path live_staging = dir_ / (".dets.staging-" + live + "-9");
  const fs::path other_staging = dir_ / (".other.staging-" + std::to_string(dead) + "-0");
  const fs::path stale_tmp = out / "sub" / (".000001.tmp-" + std::to_string(dead) + "-0.png");
  const fs::path user_file = out / ".notes.tmp-draft";
  for (const fs::path& p : {stale_staging / "x", stale_old / "x", live_staging / "x",
                            other_staging / "x", stale_tmp, user_file}) {
    WriteFileAtomically(p, "x");
  }
  // Written into a minute ago: a run of another host could still be writing.
  RemoveStaleTemporaries(out / "");
  EXPECT_TRUE(fs::exists(stale_staging));
  EXPECT_TRUE(fs::exists(stale_tmp));
  // Untouched for an hour: stale.
  const fs::file_time_type hour_ago = fs::file_time_type::clock::now() - std::chrono::hours(1);
  for (const fs::path& p :
       {stale_staging, stale_old, live_staging, other_staging, stale_tmp, user_file}) {
    fs::last_write_time(p, hour_ago);
  }
  RemoveStaleTemporaries(out / "");
  EXPECT_FALSE(fs::exists(stale_staging));
  EXPECT_FALSE(fs::exists(stale_old));
  EXPECT_FALSE(fs::exists(stale_tmp));
  EXPECT_TRUE(fs::exists(live_staging));   // this process still runs
  EXPECT_TRUE(fs::exists(other_staging));  // another folder's
  EXPECT_TRUE(fs::exists(user_file));      // not one of our names
  EXPECT_TRUE(fs::exists(out / "run.json"));
}

}  // namespace
}  // namespace stereodet
