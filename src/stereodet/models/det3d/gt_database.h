// Ground-truth database cut-and-paste augmentation of the 3D detector (SECOND, Yan et al. 2018;
// kept by SA-SSD): the objects of the training frames, each with the points inside its slightly
// enlarged box, are collected once; at training time a few of them are pasted into a frame, at the
// place they were cut from, unless their box collides in BEV with a box already there. The database
// is built from the frames of the model's own input, so a stereo model pastes stereo objects only
// and a LiDAR model LiDAR objects only (`GtDatabase::source`). Torch-free.
#ifndef STEREODET_MODELS_DET3D_GT_DATABASE_H_
#define STEREODET_MODELS_DET3D_GT_DATABASE_H_

#include <cstdint>
#include <string>
#include <vector>

#include "stereodet/models/det3d/det3d_boxes.h"
#include "stereodet/models/det3d/det3d_data.h"

namespace stereodet {

struct GtDatabaseOptions {
  // Each box is grown by this on every side (length, width and height each by twice this) to cut
  // its points: stereo points of an object smear past its surface, and LiDAR returns sit on it.
  double box_margin_m = 0.2;
  // Objects with fewer points inside their grown box are left out (--gt-min-points).
  int min_points = 5;
  void Check() const;  // throws std::invalid_argument
};

// One object of the database: its box (velodyne frame of the frame it came from, label = class
// index) and the points inside the grown box, in that frame's velodyne coordinates.
struct GtObject {
  LidarBox box;
  std::vector<VeloPoint> points;
  std::string frame_id;
};

struct GtDatabase {
  PointSource source = PointSource::kLidar;  // the points the objects were cut from
  double box_margin_m = 0.2;                 // as built (GtDatabaseOptions::box_margin_m)
  std::vector<std::vector<GtObject>> objects_by_class;  // [class index][object], frame order
  int64_t ObjectCount() const;
  int64_t PointCount() const;
};

// The box grown by `margin_m` on every side (centre and heading kept).
LidarBox GrownBox(const LidarBox& box, double margin_m);

// The database of `frames` (their points as loaded, their boxes of the model's classes, labels in
// [0, num_classes)): objects in frame order, then box order. A point inside two grown boxes goes
// to both objects. Requires: frames' points are of `source`.
GtDatabase BuildGtDatabase(const std::vector<Det3dFrame>& frames, int num_classes,
                           PointSource source, const GtDatabaseOptions& options);

struct GtSamplingOptions {
  // Per class and frame, this many distinct objects of the class are drawn from the database
  // (all of them when it holds fewer) and each is pasted unless it collides (--gt-per-class).
  int max_per_class = 10;
  bool enabled = true;  // --no-gt-sampling (--no-augment turns it off as well)
  void Check() const;   // throws std::invalid_argument
};

struct GtSamplingResult {
  Det3dFrame frame;                   // the frame with the pasted objects (their boxes appended)
  std::vector<int> pasted_per_class;  // [class index]
  int rejected = 0;                   // drawn objects that collided
  int64_t removed_points = 0;         // frame points inside the pasted objects' grown boxes
};

// Pastes database objects into a copy of `frame`, seeded (same seed, same frame, same result):
// per class in class order, a random draw without replacement of up to max_per_class objects,
// visited in draw order; an object whose grown box has BEV IoU > 0 with the grown box of an object
// of the frame or of one pasted before is rejected (so no object's points are cut by another). Then
// the frame's points inside any pasted grown box are removed (so an object's points never mix with
// what stood there) and the pasted objects' points appended in paste order; the pasted boxes (not
// grown) are appended to frame.boxes.
GtSamplingResult SampleGtObjects(const Det3dFrame& frame, const GtDatabase& database,
                                 const GtSamplingOptions& options, uint64_t seed);

}  // namespace stereodet

#endif  // STEREODET_MODELS_DET3D_GT_DATABASE_H_
