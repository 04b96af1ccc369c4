// The KITTI object-benchmark layout on disk:
//   ROOT/training/{image_2,image_3,label_2,calib,velodyne}/NNNNNN.{png,txt,bin}
//   ROOT/testing/{image_2,image_3,calib,velodyne}/...
//   ROOT/ImageSets/{train,val,trainval,test}.txt   (one frame id per line)
// plus, for data written by `stereodet synth`, ROOT/training/disp_noc_0/NNNNNN.png (ground-truth
// disparity in KITTI's stereo format) and ROOT/training/planes/NNNNNN.txt (the true ground plane,
// in the layout KITTI tools use: plane_io.h).
#ifndef STEREODET_KITTI_DATASET_H_
#define STEREODET_KITTI_DATASET_H_

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "stereodet/geometry/calibration.h"
#include "stereodet/kitti/object.h"

namespace stereodet {

// Paths of one frame's files. They need not exist; see FindMissingFiles.
struct FramePaths {
  std::string id;                     // "000123"
  std::filesystem::path image_left;   // image_2/ID.png
  std::filesystem::path image_right;  // image_3/ID.png
  std::filesystem::path label;        // label_2/ID.txt
  std::filesystem::path calib;        // calib/ID.txt
  std::filesystem::path velodyne;     // velodyne/ID.bin
  std::filesystem::path disparity;    // disp_noc_0/ID.png (synthetic data only)
  std::filesystem::path planes;       // planes/ID.txt (ground plane; synthetic data, some tools)
};

class KittiDataset {
 public:
  // `root` is the folder holding training/, testing/ and ImageSets/. `subset` is "training" or
  // "testing". Throws std::runtime_error if root/subset is not a folder.
  explicit KittiDataset(std::filesystem::path root, std::string subset = "training");

  const std::filesystem::path& root() const { return root_; }
  const std::string& subset() const { return subset_; }
  std::filesystem::path SubsetDir() const { return root_ / subset_; }

  FramePaths Paths(const std::string& id) const;

  // All ids with a file in image_2/ (or label_2/ when there are no images, or calib/ when there are
  // neither), in numeric order. Names that are not digits, and hidden files, are ignored.
  std::vector<std::string> ListIds() const;

  // Reads a split file (one id per line; blank lines ignored). A relative `split` that names no
  // existing file is looked up as ROOT/ImageSets/SPLIT.txt, so "val" works. Throws ParseError for a
  // line that is not a frame id (digits only).
  std::vector<std::string> ReadSplit(const std::filesystem::path& split) const;

 private:
  std::filesystem::path root_;
  std::string subset_;
};

// Which files a job needs: FindMissingFiles reports those absent.
struct RequiredFiles {
  bool image_left = false, image_right = false, label = false, calib = false, velodyne = false;
};
// "ID: label_2/ID.txt" for each required file that is missing, in id order.
std::vector<std::string> FindMissingFiles(const KittiDataset& dataset,
                                          const std::vector<std::string>& ids,
                                          const RequiredFiles& required);
// Before any work, not halfway through it: throws std::runtime_error when a frame of `ids` lacks a
// file `required` names, with the count, the folder and the first five ("3 required files are
// missing under D/training, e.g.\n  000001: image_3/000001.png\n  ...").
void CheckRequiredFiles(const KittiDataset& dataset, const std::vector<std::string>& ids,
                        const RequiredFiles& required);

// The ids of a split file's text, in file order: one id per line, blanks around it and blank lines
// ignored, and a UTF-8 byte-order mark at the start of the text too. Throws ParseError(source,
// line, "frame id", ...) for a line that is not a frame id (digits only), quoting it escaped and
// shortened.
std::vector<std::string> ParseSplit(std::string_view text, const std::string& source);

// Writes a split file atomically, one id per line.
void WriteSplit(const std::filesystem::path& path, const std::vector<std::string>& ids);

// A frame id from an index: 123 -> "000123".
std::string FrameId(int index);

// Whether `text` is a frame id: one or more digits (so it names a file inside a subset folder,
// never a path such as "../x").
bool IsFrameId(std::string_view text);

}  // namespace stereodet

#endif  // STEREODET_KITTI_DATASET_H_
