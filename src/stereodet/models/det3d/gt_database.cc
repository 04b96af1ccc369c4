#include "stereodet/models/det3d/gt_database.h"

#include <cmath>
#include <numeric>
#include <random>

#include "stereodet/util/check.h"

namespace stereodet {

namespace {

// PointInBox with the box's trigonometry computed once and a cheap circle test first (frames hold
// 10^5 points and more).
class BoxTest {
 public:
  explicit BoxTest(const LidarBox& box)
      : box_(box),
        c_(std::cos(box.yaw)),
        s_(std::sin(box.yaw)),
        radius2_(0.25 * (box.l * box.l + box.w * box.w)) {}
  bool Contains(const VeloPoint& p) const {
    const double dx = p.x - box_.x, dy = p.y - box_.y;
    if (dx * dx + dy * dy > radius2_ * (1 + 1e-9)) return false;
    return std::abs(c_ * dx + s_ * dy) <= box_.l / 2 &&
           std::abs(-s_ * dx + c_ * dy) <= box_.w / 2 && std::abs(p.z - box_.z) <= box_.h / 2;
  }

 private:
  LidarBox box_;
  double c_, s_, radius2_;
};

}  // namespace

void GtDatabaseOptions::Check() const {
  STEREODET_CHECK(box_margin_m >= 0.0 && std::isfinite(box_margin_m))
      << "GT database box margin must be >= 0 m, got " << box_margin_m;
  STEREODET_CHECK(min_points >= 1) << "--gt-min-points must be >= 1, got " << min_points;
}

void GtSamplingOptions::Check() const {
  STEREODET_CHECK(max_per_class >= 0) << "--gt-per-class must be >= 0, got " << max_per_class;
}

int64_t GtDatabase::ObjectCount() const {
  int64_t n = 0;
  for (const auto& objects : objects_by_class) n += static_cast<int64_t>(objects.size());
  return n;
}

int64_t GtDatabase::PointCount() const {
  int64_t n = 0;
  for (const auto& objects : objects_by_class) {
    for (const GtObject& o : objects) n += static_cast<int64_t>(o.points.size());
  }
  return n;
}

LidarBox GrownBox(const LidarBox& box, double margin_m) {
  LidarBox grown = box;
  grown.l += 2 * margin_m;
  grown.w += 2 * margin_m;
  grown.h += 2 * margin_m;
  return grown;
}

GtDatabase BuildGtDatabase(const std::vector<Det3dFrame>& frames, int num_classes,
                           PointSource source, const GtDatabaseOptions& options) {
  options.Check();
  STEREODET_CHECK(num_classes >= 1) << "GT database needs >= 1 class, got " << num_classes;
  GtDatabase database;
  database.source = source;
  database.box_margin_m = options.box_margin_m;
  database.objects_by_class.resize(num_classes);
  for (const Det3dFrame& frame : frames) {
    for (const LidarBox& box : frame.boxes) {
      STEREODET_CHECK(box.label >= 0 && box.label < num_classes)
          << "frame " << frame.id << ": box label " << box.label << " outside the " << num_classes
          << " classes";
      const BoxTest grown(GrownBox(box, options.box_margin_m));
      GtObject object;
      object.box = box;
      object.frame_id = frame.id;
      for (const VeloPoint& p : frame.points) {
        if (grown.Contains(p)) object.points.push_back(p);
      }
      if (static_cast<int>(object.points.size()) < options.min_points) continue;
      object.points.shrink_to_fit();
      database.objects_by_class[box.label].push_back(std::move(object));
    }
  }
  return database;
}

GtSamplingResult SampleGtObjects(const Det3dFrame& frame, const GtDatabase& database,
                                 const GtSamplingOptions& options, uint64_t seed) {
  options.Check();
  const int num_classes = static_cast<int>(database.objects_by_class.size());
  GtSamplingResult result;
  result.pasted_per_class.assign(num_classes, 0);
  const double margin = database.box_margin_m;
  // Occupied footprints: the frame's objects, then each pasted one (all grown).
  std::vector<LidarBox> occupied;
  occupied.reserve(frame.boxes.size());
  for (const LidarBox& b : frame.boxes) occupied.push_back(GrownBox(b, margin));
  std::vector<const GtObject*> pasted;
  std::mt19937_64 rng(seed);
  for (int c = 0; c < num_classes; ++c) {
    const std::vector<GtObject>& pool = database.objects_by_class[c];
    const size_t draws = std::min<size_t>(pool.size(), options.max_per_class);
    // A partial Fisher-Yates shuffle: the first `draws` entries are a uniform draw without
    // replacement (rng() % n, as EpochOrder does: the same on every platform).
    std::vector<size_t> index(pool.size());
    std::iota(index.begin(), index.end(), size_t{0});
    for (size_t k = 0; k < draws; ++k) {
      const size_t j = k + static_cast<size_t>(rng() % (index.size() - k));
      std::swap(index[k], index[j]);
      const GtObject& candidate = pool[index[k]];
      const LidarBox grown = GrownBox(candidate.box, margin);
      bool collides = false;
      for (const LidarBox& o : occupied) {
        if (LidarBevIou(grown, o) > 0.0) {
          collides = true;
          break;
        }
      }
      if (collides) {
        ++result.rejected;
        continue;
      }
      occupied.push_back(grown);
      pasted.push_back(&candidate);
      ++result.pasted_per_class[c];
    }
  }

  Det3dFrame& out = result.frame;
  out.id = frame.id;
  out.calib = frame.calib;
  out.image_width = frame.image_width;
  out.image_height = frame.image_height;
  out.boxes = frame.boxes;
  size_t extra = 0;
  for (const GtObject* o : pasted) extra += o->points.size();
  out.points.reserve(frame.points.size() + extra);
  std::vector<BoxTest> cut;
  for (size_t k = frame.boxes.size(); k < occupied.size(); ++k) cut.emplace_back(occupied[k]);
  for (const VeloPoint& p : frame.points) {
    bool inside = false;
    for (size_t k = 0; k < cut.size() && !inside; ++k) inside = cut[k].Contains(p);
    if (inside) {
      ++result.removed_points;
    } else {
      out.points.push_back(p);
    }
  }
  for (const GtObject* o : pasted) {
    out.points.insert(out.points.end(), o->points.begin(), o->points.end());
    out.boxes.push_back(o->box);
  }
  return result;
}

}  // namespace stereodet
