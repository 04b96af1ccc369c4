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
//   scores.npy       ['scores'], T x R x K x A x M;
//   cells.csv, reliability.csv   with eval.score_metrics (docs/metrics.md);
// with bootstrap, results.json's "bootstrap" (each number's estimate and interval); with det_b,
// "compare" (B's 12 numbers, A - B, and with bootstrap the paired intervals of A - B).

// The 12 numbers and their intervals as a table, one line per number:
//   "AP     0.409 [0.371, 0.447]"  (FormatCocoBootstrap), or with B:
//   "AP     A 0.409  B 0.391  A - B 0.018 [0.004, 0.031]"  (FormatCocoCompare; the interval only
// with a paired bootstrap).
#ifndef STEREODET_PIPELINES_COCO_EVALUATION_H_
#define STEREODET_PIPELINES_COCO_EVALUATION_H_

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "stereodet/eval/bootstrap.h"
#include "stereodet/eval/coco.h"
#include "stereodet/eval/coco_bootstrap.h"

namespace stereodet {

// The names results.json gives the summary numbers, in CocoEvalResult::stats' order (detectron2's
// names): AP, AP50, AP75, APs, APm, APl, AR1, AR10, AR100, ARs, ARm, ARl. AR1 / AR10 / AR100 stand
// for max_dets[0..2], whatever their values.
const std::array<const char*, kNumCocoStats>& CocoStatNames();

struct CocoEvaluationOptions {
  std::filesystem::path gt;   // a COCO ground-truth file (instances_*.json)
  std::filesystem::path det;  // a COCO results file: [{image_id, category_id, bbox, score}, ...]
  // A second results file of the same ground truth (`--coco-det-b`): evaluated too, and compared
  // with `det` number by number (A - B), with paired intervals under `bootstrap`. Empty: none.
  std::filesystem::path det_b;
  CocoEvalOptions eval;
  // Bootstrap intervals over images for the 12 numbers (BootstrapCoco; with det_b,
  // PairedBootstrapCoco). Unset: none.
  std::optional<BootstrapOptions> bootstrap;
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
  std::optional<CocoEvalResult> result_b;  // with det_b
  // With bootstrap: the intervals (without det_b) or the paired ones (with it; `paired.a` is
  // `bootstrap`'s content then too).
  std::optional<CocoBootstrapResult> bootstrap;
  std::optional<CocoPairedBootstrapResult> paired;
  std::string input_hash;   // FNV-1a 64 of the ground truth's bytes then the results' bytes; with
                            // `out` only (empty without)
  double read_seconds = 0;  // reading and parsing both files, s (result.seconds: evaluating)
  std::vector<std::filesystem::path> files;  // with out: the files written, as paths under out
};

std::string FormatCocoBootstrap(const CocoBootstrapResult& bootstrap);
std::string FormatCocoCompare(const CocoEvalResult& a, const CocoEvalResult& b,
                              const CocoPairedBootstrapResult* paired);

// Checks the options, claims `out` (refusing a folder of other files, or one holding an input),
// reads both files, evaluates and writes the results folder, which replaces `out` whole at the
// end. Throws std::invalid_argument for bad options, ParseError for a malformed file or a
// detection on an image the ground truth does not have, std::runtime_error for I/O.
CocoEvaluationResult RunCocoEvaluation(const CocoEvaluationOptions& options);

}  // namespace stereodet

#endif  // STEREODET_PIPELINES_COCO_EVALUATION_H_
