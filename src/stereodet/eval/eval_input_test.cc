#include "stereodet/eval/eval_input.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include "stereodet/util/check.h"
#include "stereodet/util/hash.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::Not;

constexpr char kLabel[] =
    "Car 0.00 0 -1.57 100.00 100.00 200.00 200.00 1.5 1.6 3.9 1 1.6 20 -1.57\n";
constexpr char kDetection[] = "Car -1 -1 -1.57 100 100 200 200 1.5 1.6 3.9 1 1.6 20 -1.57 0.9\n";

void Write(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

// gt/000000..000002 with one car each, det/000000 and det/000001.
struct Folders {
  TestTempDir dir;
  fs::path gt = dir / "gt", det = dir / "det";
  Folders() {
    for (const char* id : {"000000", "000001", "000002"}) {
      Write(gt / (std::string(id) + ".txt"), kLabel);
    }
    for (const char* id : {"000000", "000001"}) Write(det / (std::string(id) + ".txt"), kDetection);
  }
  EvalInputOptions Options() const {
    EvalInputOptions o;
    o.gt = gt;
    o.det = det;
    o.num_threads = 2;
    o.missing_as_empty = true;  // 000002 has no detection file on purpose (one of three)
    return o;
  }
};

std::string ErrorOf(const EvalInputOptions& options) {
  try {
    LoadEvalFrames(options);
  } catch (const std::exception& e) {
    return e.what();
  }
  ADD_FAILURE() << "no exception";
  return "";
}

TEST(EvalInputTest, ReadsEveryLabelFileAndNotesFramesWithoutDetections) {
  const Folders f;
  const EvalInput in = LoadEvalFrames(f.Options());
  ASSERT_EQ(in.frames.size(), 3u);
  EXPECT_EQ(in.frames[0].id, "000000");
  EXPECT_EQ(in.frames[2].id, "000002");
  EXPECT_EQ(in.frames[0].labels.size(), 1u);
  EXPECT_EQ(in.frames[1].detections.size(), 1u);
  EXPECT_TRUE(in.frames[2].detections.empty());
  EXPECT_THAT(in.frames_without_detections, ElementsAre("000002"));
  EXPECT_TRUE(in.ignored_files.empty());
  EXPECT_THAT(in.Notices(), ElementsAre("frames without a detection file (no detections): 1"));
}

// Without a split, a folder of detections for part of the labelled frames would read as a weak
// detector: more than 10 % of the frames without a detection file is refused unless
// missing_as_empty or a split says what counts.
TEST(EvalInputTest, WithoutASplitMoreThanATenthOfTheFramesWithoutDetectionsIsRefused) {
  TestTempDir dir;
  const fs::path gt = dir / "gt", det = dir / "det";
  for (int i = 0; i < 20; ++i) {
    const std::string id = "0000" + std::to_string(10 + i);
    Write(gt / (id + ".txt"), kLabel);
    if (i != 3 && i != 7) Write(det / (id + ".txt"), kDetection);  // 2 of 20 missing: 10 %
  }
  EvalInputOptions o;
  o.gt = gt;
  o.det = det;
  EXPECT_EQ(LoadEvalFrames(o).frames_without_detections.size(), 2u);  // not more than 10 %
  fs::remove(det / "000011.txt");                                     // 3 of 20: 15 %
  EXPECT_THAT(ErrorOf(o),
              HasSubstr("--det " + det.string() +
                        " has no detection file for 3 of the 20 labelled "
                        "frames in " +
                        gt.string() +
                        " (first: 000011.txt). Without --split every "
                        "label file is a frame to evaluate, and these would count as frames where "
                        "the detector found nothing; pass --split with the frames that were "
                        "detected, or --missing-as-empty to evaluate them so"));
  o.missing_as_empty = true;
  EXPECT_EQ(LoadEvalFrames(o).frames_without_detections.size(), 3u);
  o.missing_as_empty = false;
  Write(dir / "split.txt", "000010\n000011\n000012\n");  // a split: its frames count, as given
  o.split = (dir / "split.txt").string();
  EXPECT_EQ(LoadEvalFrames(o).frames_without_detections, std::vector<std::string>{"000011"});
  // Every shard of one run decides alike: the count is the whole list's.
  o.split.clear();
  o.shard = Shard{1, 2, /*named=*/true};
  EXPECT_THAT(ErrorOf(o), HasSubstr("3 of the 20 labelled frames"));
}

TEST(EvalInputTest, WarnsAboutDetectionFilesThatTheFoldersRunDidNotWrite) {
  Folders f;
  // No run.json (KITTI's own results): nothing to check, nothing said.
  EvalInput in = LoadEvalFrames(f.Options());
  EXPECT_TRUE(in.det_run.empty());
  EXPECT_TRUE(in.det_not_from_run.empty());

  RunManifest manifest;
  manifest.tool = "detect ssd";
  manifest.version = "0.1.0";
  manifest.command_line = "stereodet detect ssd --out det";
  manifest.frames = {{"000000", HashHex(Fnv1a64(kDetection))},
                     {"000001", HashHex(Fnv1a64(kDetection))}};
  WriteRunManifest(f.det, manifest);
  in = LoadEvalFrames(f.Options());
  EXPECT_EQ(in.det_run, "detect ssd 0.1.0: stereodet detect ssd --out det");
  EXPECT_TRUE(in.det_not_from_run.empty());
  for (const std::string& notice : in.Notices()) EXPECT_THAT(notice, Not(HasSubstr("run.json")));

  // Another run changed one file and added another: both are named, in frame order.
  Write(f.det / "000001.txt", "Car -1 -1 -1.57 100 100 200 200 1.5 1.6 3.9 1 1.6 20 -1.57 0.5\n");
  Write(f.det / "000002.txt", kDetection);
  in = LoadEvalFrames(f.Options());
  EXPECT_THAT(in.det_not_from_run,
              ElementsAre((f.det / "000001.txt").string(), (f.det / "000002.txt").string()));
  EXPECT_THAT(in.Notices().back(),
              HasSubstr("warning: 2 detection file(s) are not from the run in"));
  EXPECT_THAT(in.Notices().back(), HasSubstr("det/000001.txt"));
}

TEST(EvalInputTest, KittiRootAndDevkitDataFolderAreFound) {
  TestTempDir dir;
  Write(dir / "kitti/training/label_2/000007.txt", kLabel);
  Write(dir / "kitti/ImageSets/val.txt", "000007\n");
  Write(dir / "results/data/000007.txt", kDetection);
  EvalInputOptions o;
  o.gt = dir / "kitti";
  o.det = dir / "results";
  o.split = "val";
  const EvalInput in = LoadEvalFrames(o);
  ASSERT_EQ(in.frames.size(), 1u);
  EXPECT_EQ(in.frames[0].detections.size(), 1u);
  EXPECT_EQ(in.label_dir, dir / "kitti/training/label_2");
  EXPECT_EQ(in.det_dir, dir / "results/data");
  EXPECT_TRUE(in.Notices().empty());
}

// The folders are listed with readdir(): a symbolic link to a file counts as that file, and a
// trailing separator in the folder names the files as without one. A frame's name that is no
// regular file (a folder, a link to a folder, to nothing or to itself, a FIFO) used to count as
// "no detections" for its frame without a word: it is an error naming it, in labels and
// detections alike. Other names stay ignored with the notice.
TEST(EvalInputTest, LinksCountAsWhatTheyPointToAndAFrameNameThatIsNoFileIsAnError) {
  Folders f;
  Write(f.dir / "elsewhere" / "label.txt", kLabel);
  fs::create_symlink(f.dir / "elsewhere" / "label.txt", f.gt / "000003.txt");
  fs::create_symlink(f.dir / "elsewhere" / "label.txt", f.gt / "link.txt");
  fs::create_directories(f.gt / "notes.txt");  // not a frame's name: ignored
  EvalInputOptions o = f.Options();
  o.gt = f.gt.string() + "/";
  const EvalInput in = LoadEvalFrames(o);
  ASSERT_EQ(in.frames.size(), 4u);
  EXPECT_EQ(in.frames[3].id, "000003");
  EXPECT_EQ(in.frames[3].labels.size(), 1u);
  EXPECT_THAT(in.ignored_files, ElementsAre((f.gt / "link.txt").string()));
  EXPECT_THAT(in.frames_without_detections, ElementsAre("000002", "000003"));

  const fs::path bad = f.det / "000002.txt";
  auto expect_refused = [&](const char* what) {
    for (const bool with_split : {false, true}) {
      EvalInputOptions options = f.Options();
      if (with_split) {
        Write(f.dir / "split.txt", "000000\n000001\n000002\n");
        options.split = (f.dir / "split.txt").string();
      }
      EXPECT_THAT(ErrorOf(options), HasSubstr(bad.string() + " is not a regular file"))
          << what << (with_split ? " with a split" : "");
    }
    fs::remove_all(bad);
  };
  fs::create_directories(bad);
  expect_refused("a folder");
  fs::create_directory_symlink(f.dir / "elsewhere", bad);
  expect_refused("a link to a folder");
  fs::create_symlink(f.dir / "nowhere.txt", bad);
  expect_refused("a dangling link");
  fs::create_symlink(bad, bad);
  expect_refused("a link to itself");
  ASSERT_EQ(::mkfifo(bad.c_str(), 0600), 0);
  expect_refused("a FIFO");
  fs::remove(f.gt / "000002.txt");
  fs::create_directories(f.gt / "000002.txt");
  EXPECT_THAT(ErrorOf(f.Options()),
              HasSubstr((f.gt / "000002.txt").string() + " is not a regular file"));
}

// The devkit's DIR/data/ beside detection files at DIR's top: which to evaluate is ambiguous.
TEST(EvalInputTest, ADetectionFolderWithFilesAtTheTopAndInDataIsRefused) {
  Folders f;
  Write(f.det / "data" / "000000.txt", kDetection);
  EXPECT_THAT(ErrorOf(f.Options()),
              HasSubstr("--det: " + f.det.string() +
                        " holds detection files both at its top and in data/"));
  for (const char* id : {"000000", "000001"}) fs::remove(f.det / (std::string(id) + ".txt"));
  EXPECT_EQ(LoadEvalFrames(f.Options()).det_dir, f.det / "data");  // only data/: the devkit's
}

TEST(EvalInputTest, StrayFilesAreIgnoredWithOneNotice) {
  Folders f;
  Write(f.det / "009999.txt", kDetection);  // a frame outside the split
  Write(f.det / "README.txt", "how these were made\n");
  Write(f.det / "README.md", "not a .txt: ignored silently\n");
  Write(f.det / ".hidden.txt", "hidden: ignored silently\n");
  Write(f.gt / "notes.txt", "not a frame id\n");
  Write(f.dir / "split.txt", "000000\n000001\n");
  EvalInputOptions o = f.Options();
  o.split = (f.dir / "split.txt").string();
  const EvalInput in = LoadEvalFrames(o);
  ASSERT_EQ(in.frames.size(), 2u);
  EXPECT_THAT(in.ignored_files,
              ElementsAre((f.det / "009999.txt").string(), (f.det / "README.txt").string(),
                          (f.gt / "notes.txt").string()));
  const std::vector<std::string> notices = in.Notices();
  ASSERT_EQ(notices.size(), 1u);
  EXPECT_THAT(notices[0], HasSubstr("ignored 3 .txt file(s)"));
  EXPECT_THAT(notices[0], HasSubstr("first: " + (f.det / "009999.txt").string()));
}

TEST(EvalInputTest, WithoutASplitADetectionFileWithoutALabelFileIsAnError) {
  Folders f;
  Write(f.det / "README.txt", "not a frame: ignored\n");
  EXPECT_EQ(LoadEvalFrames(f.Options()).ignored_files.size(), 1u);
  Write(f.det / "009999.txt", kDetection);
  const std::string error = ErrorOf(f.Options());
  EXPECT_THAT(error, HasSubstr("009999.txt has no label file in"));
  EXPECT_THAT(error, HasSubstr("with --split"));
}

TEST(EvalInputTest, SplitFrameWithoutALabelFileIsAnError) {
  Folders f;
  Write(f.dir / "split.txt", "000000\n000005\n");
  EvalInputOptions o = f.Options();
  o.split = (f.dir / "split.txt").string();
  EXPECT_THAT(ErrorOf(o), HasSubstr("frame 000005 has no label file"));
  Write(f.dir / "split.txt", "000000\nabc\n");
  try {
    LoadEvalFrames(o);
    ADD_FAILURE() << "no ParseError";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.line(), 2);
    EXPECT_EQ(e.field(), "frame id");
  }
}

TEST(EvalInputTest, SplitListingAFrameTwiceIsAnError) {
  Folders f;
  Write(f.dir / "split.txt", "000000\n000001\n000000\n");
  EvalInputOptions o = f.Options();
  o.split = (f.dir / "split.txt").string();
  EXPECT_THAT(ErrorOf(o), HasSubstr("frame 000000 is listed more than once"));
}

TEST(EvalInputTest, HashesTheBytesReadIndependentlyOfThreads) {
  Folders f;
  EvalInputOptions o = f.Options();
  const EvalInput two = LoadEvalFrames(o);
  o.num_threads = 1;
  const EvalInput one = LoadEvalFrames(o);
  EXPECT_EQ(two.input_hash.size(), 16u);
  EXPECT_EQ(one.input_hash, two.input_hash);
  Write(f.det / "000001.txt", std::string(kDetection) + kDetection);  // one more detection
  EXPECT_NE(LoadEvalFrames(o).input_hash, one.input_hash);
}

TEST(EvalInputTest, SplitNameWithAPlainLabelFolderSaysWhereItLookedAndHowToPassAFile) {
  TestTempDir dir;
  Write(dir / "kitti/training/label_2/000007.txt", kLabel);
  Write(dir / "kitti/ImageSets/val.txt", "000007\n");
  Write(dir / "det/000007.txt", kDetection);
  EvalInputOptions o;
  o.gt = dir / "kitti/training/label_2";
  o.det = dir / "det";
  o.split = "val";
  const std::string error = ErrorOf(o);
  EXPECT_THAT(error, HasSubstr("--split val: no such file"));
  EXPECT_THAT(error, HasSubstr("not a KITTI root"));
  const std::string found = (dir / "kitti/ImageSets/val.txt").string();
  EXPECT_THAT(error, HasSubstr("looked for the file 'val' and for ImageSets/val.txt"));
  EXPECT_THAT(error,
              HasSubstr(": found " + found + ". Pass the split file itself: --split " + found));
  // Nothing to find: the message still says how to pass a file.
  o.split = "test";
  const std::string none = ErrorOf(o);
  EXPECT_THAT(none, HasSubstr(": none there"));
  EXPECT_THAT(none, HasSubstr("--split ROOT/ImageSets/test.txt, or the KITTI root: --gt ROOT"));
}

TEST(EvalInputTest, LenientSkipsAndListsBadLinesStrictThrows) {
  Folders f;
  Write(f.det / "000001.txt", std::string(kDetection) + "Car 0 0 1 2 3 4 5 6 7 8 9 10 11 12 nan\n");
  Write(f.gt / "000002.txt", std::string("Car 0 0 x\n") + kLabel);
  try {
    LoadEvalFrames(f.Options());
    ADD_FAILURE() << "strict mode did not throw";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.line(), e.file() == (f.det / "000001.txt").string() ? 2 : 1);
  }
  EvalInputOptions o = f.Options();
  o.lenient = true;
  const EvalInput in = LoadEvalFrames(o);
  ASSERT_EQ(in.skipped_lines.size(), 2u);
  EXPECT_THAT(in.skipped_lines[0], HasSubstr((f.det / "000001.txt").string() + ":2: field score"));
  EXPECT_THAT(in.skipped_lines[1], HasSubstr((f.gt / "000002.txt").string() + ":1: field"));
  EXPECT_EQ(in.frames[1].detections.size(), 1u);
  EXPECT_EQ(in.frames[2].labels.size(), 1u);
  EXPECT_THAT(in.Notices(), ::testing::Contains("skipped bad lines (--lenient): 2"));
}

TEST(EvalInputTest, DetectionsWithFloatsInEveryFieldAreRead) {
  Folders f;
  Write(f.det / "000000.txt",
        "Car -1.0000 -1.0000 -1.5700 100.0000 100.0000 200.0000 200.0000 1.5000 1.6000 3.9000 "
        "1.0000 1.6000 20.0000 -1.5700 0.9000\n");
  const EvalInput in = LoadEvalFrames(f.Options());
  ASSERT_EQ(in.frames[0].detections.size(), 1u);
  EXPECT_EQ(*in.frames[0].detections[0].score, 0.9);
}

TEST(EvalInputTest, LabelLinesAsDetectionsNeedAScore) {
  Folders f;
  // A label line and a detection line in one detection file.
  Write(f.det / "000000.txt", std::string(kLabel) + kDetection);
  EXPECT_THAT(ErrorOf(f.Options()),
              HasSubstr("det/000000.txt:1: field score: missing: the line has 15 fields, expected "
                        "16 (a detection line, score last); a label line: to evaluate labels as "
                        "detections, give them a score (`eval --score 1`)"));
  EvalInputOptions options = f.Options();
  options.score_if_missing = 0.25;
  const EvalInput in = LoadEvalFrames(options);
  ASSERT_EQ(in.frames[0].detections.size(), 2u);
  EXPECT_EQ(*in.frames[0].detections[0].score, 0.25);  // the label line
  EXPECT_EQ(*in.frames[0].detections[1].score, 0.9);   // its own score kept
  EXPECT_EQ(in.frames[0].detections[0].box.right, 200.0);
  // The same through the sources a shard keeps (eval merge's path).
  options.keep_sources = true;
  EvalInput kept = LoadEvalFrames(options);
  const EvalInput merged = EvalInputFromSources(kept.sources, false, 1, false, 0.25);
  ASSERT_EQ(merged.frames.size(), in.frames.size());
  EXPECT_EQ(*merged.frames[0].detections[0].score, 0.25);
  EXPECT_EQ(merged.input_hash, in.input_hash);
  options.score_if_missing = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(ErrorOf(options), HasSubstr("--score must be a finite number"));
}

TEST(EvalInputTest, MissingFoldersAndEmptyOptionsAreErrors) {
  Folders f;
  EvalInputOptions o = f.Options();
  o.det = f.dir / "nowhere";
  EXPECT_THAT(ErrorOf(o), HasSubstr("nowhere is not a folder"));
  o.det.clear();
  EXPECT_THROW(LoadEvalFrames(o), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
