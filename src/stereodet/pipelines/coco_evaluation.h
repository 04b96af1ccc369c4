// `stereodet eval --coco-gt FILE --coco-det FILE` as one library call: read a COCO ground truth and
// a COCO results file, evaluate them as pycocotools' COCOeval does (eval/coco.h), and write the
// results folder.
//
//   CocoEvaluationOptions options;
//   options.gt = "instances_val2017.json";  options.det = "detections.json";  options.out = "eval";
//   const CocoEvaluationResult result = RunCocoEvaluation(options);
//   std::cout << FormatCocoSummary(result.result);
//
// The results folder (docs/metrics.md, "COCO mode"):
//   results.json     "mode": "coco", provenance as `eval` records it (tool, command line, inputs,
//                    input_hash), the options, the 12 summary numbers by name, the categories and
//                    the arrays' files and shapes;
//   precision.npy    COCOeval.eval['precision'], float64, T x R x K x A x M (numpy's .npy format,
//   recall.npy       ['recall'], T x K x A x M               np.load reads them);
//   scores.npy       ['scores'], T x R x K x A x M.
#ifndef STEREODET_PIPELINES_COCO_EVALUATION_H_
#define STEREODET_PIPELINES_COCO_EVALUATION_H_

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "stereodet/eval/coco.h"

namespace stereodet {

// The names results.json gives the summary numbers, in CocoEvalResult::stats' order (detectron2's
// names): AP, AP50, AP75, APs, APm, APl, AR1, AR10, AR100, ARs, ARm, ARl. AR1 / AR10 / AR100 stand
// for max_dets[0..2], whatever their values.
const std::array<const char*, kNumCocoStats>& CocoStatNames();

struct CocoEvaluationOptions {
  std::filesystem::path gt;   // a COCO ground-truth file (instances_*.json)
  std::filesystem::path det;  // a COCO results file: [{image_id, category_id, bbox, score}, ...]
  CocoEvalOptions eval;
  // The results folder (a StagedFolder of `eval`: only an earlier eval output, with its
  // results.json, is replaced; it must not hold gt or det). Empty: nothing is written.
  std::filesystem::path out;
  // Provenance recorded in results.json.
  std::string tool_version;
  std::string command_line;

  // Throws std::invalid_argument for a missing gt or det, or bad eval options.
  void Check() const;
};

struct CocoEvaluationResult {
  CocoEvalResult result;
  std::string input_hash;   // FNV-1a 64 of the ground truth's bytes then the results' bytes
  double read_seconds = 0;  // reading and parsing both files, s (result.seconds: evaluating)
  std::vector<std::filesystem::path> files;  // with out: the files written, as paths under out
};

// Checks the options, claims `out` (refusing a folder of other files, or one holding an input),
// reads both files, evaluates and writes the results folder, which replaces `out` whole at the
// end. Throws std::invalid_argument for bad options, ParseError for a malformed file or a
// detection on an image the ground truth does not have, std::runtime_error for I/O.
CocoEvaluationResult RunCocoEvaluation(const CocoEvaluationOptions& options);

}  // namespace stereodet

#endif  // STEREODET_PIPELINES_COCO_EVALUATION_H_
