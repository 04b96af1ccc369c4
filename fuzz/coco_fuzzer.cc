// libFuzzer target for the COCO readers (ParseCocoGroundTruth, ParseCocoDetections: eval
// --coco-gt / --coco-det) and the evaluation of what they read (EvaluateCoco).
//
// The first byte chooses the file: even, the rest is a ground truth, evaluated with one detection
// per annotation (its own box); odd, the rest is a results file, read against a fixed ground truth
// and evaluated with it. Any input must either parse or throw ParseError, and what parses must
// evaluate without throwing, with every precision and recall -1 or in [0, 1] and every summary
// number -1 or in [0, 1].
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "stereodet/eval/coco.h"
#include "stereodet/util/check.h"

namespace {

void Fail(const char* what) {
  std::fprintf(stderr, "coco_fuzzer: %s\n", what);
  std::abort();
}

bool IsProbability(double v) { return v == -1 || (v >= 0 && v <= 1); }

void CheckEvaluation(const stereodet::CocoGroundTruth& gt,
                     const std::vector<stereodet::CocoDetection>& dets) {
  stereodet::CocoEvalOptions options;
  options.num_threads = 1;
  const stereodet::CocoEvalResult r = stereodet::EvaluateCoco(gt, dets, options);
  for (const double v : r.precision) {
    if (!IsProbability(v)) Fail("a precision outside [0, 1]");
  }
  for (const double v : r.recall) {
    if (!IsProbability(v)) Fail("a recall outside [0, 1]");
  }
  for (const double v : r.stats) {
    if (!IsProbability(v)) Fail("a summary number outside [0, 1]");
  }
  if (r.num_gt + r.num_gt_skipped != static_cast<int64_t>(gt.annotations.size())) {
    Fail("ground truths lost");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace stereodet;
  if (size == 0) return 0;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  if (data[0] % 2 == 0) {
    CocoGroundTruth gt;
    try {
      gt = ParseCocoGroundTruth(text, "gt.json");
    } catch (const ParseError&) {
      return 0;
    }
    for (size_t i = 1; i < gt.image_ids.size(); ++i) {
      if (gt.image_ids[i] <= gt.image_ids[i - 1]) Fail("image ids not sorted and unique");
    }
    std::vector<CocoDetection> dets;
    for (const CocoAnnotation& a : gt.annotations) {
      dets.push_back({a.image_id, a.category_id, a.bbox, 1.0});
    }
    // Detections must be on the ground truth's images, as ParseCocoDetections ensures.
    std::erase_if(dets, [&](const CocoDetection& d) {
      return !std::binary_search(gt.image_ids.begin(), gt.image_ids.end(), d.image_id);
    });
    CheckEvaluation(gt, dets);
  } else {
    CocoGroundTruth gt;
    gt.source = "gt.json";
    gt.image_ids = {1, 2, 3};
    gt.categories = {{1, "a"}, {2, "b"}};
    CocoAnnotation a;
    a.id = 1;
    a.image_id = 1;
    a.category_id = 1;
    a.bbox = {10, 10, 40, 30};
    a.area = 1200;
    gt.annotations.push_back(a);
    a.id = 2;
    a.image_id = 2;
    a.category_id = 2;
    a.bbox = {0, 0, 200, 150};
    a.area = 20000;
    a.iscrowd = true;
    gt.annotations.push_back(a);
    std::vector<CocoDetection> dets;
    try {
      dets = ParseCocoDetections(text, "det.json", gt);
    } catch (const ParseError&) {
      return 0;
    }
    CheckEvaluation(gt, dets);
  }
  return 0;
}
