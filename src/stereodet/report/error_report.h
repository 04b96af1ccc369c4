// TIDE-style error analysis (eval/error_analysis.h) as JSON, text and CSV: what
// `stereodet eval --errors` adds to results.json, the printed table and OUT/errors.csv.
// Definitions in docs/metrics.md, "Error analysis (TIDE)".
#ifndef STEREODET_REPORT_ERROR_REPORT_H_
#define STEREODET_REPORT_ERROR_REPORT_H_

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "stereodet/eval/error_analysis.h"

namespace stereodet {

// One cell's analysis, each results.json cell's "errors": {"background_overlap", "min_overlap",
// "tp", "fp", "fn" (the association at score -inf), "ap_r40", "ap_r11" (the cell as is), "count":
// {TYPE: n}, "delta_ap_r40": {TYPE: dAP}, "delta_ap_r11": {TYPE: dAP}, "special": {"fp_r40",
// "fp_r11", "fn_r40", "fn_r11"}, "cls_incoming", "seconds"}; TYPE ErrorTypeName's (cls, loc, both,
// dupe, bkg, missed). NaN (a cell that is not evaluated) as null.
nlohmann::json ErrorAnalysisJson(const ErrorAnalysis& analysis);

// The printed block: a title line, a header, then one line per evaluated cell: class, kind,
// difficulty, AP_R40 as is, dAP_R40 of each type in ErrorType order, of the special errors FP and
// FN, and the counts of each type (2 decimals for dAP). Cells in the order given.
std::string FormatErrorTable(const std::vector<ErrorAnalysis>& analyses);

// OUT/errors.csv: one row per cell (in the order given) and error (the six types, then fp and fn
// for the special errors): class, metric, difficulty, overlaps (`overlaps`, the run's tag),
// error, count (empty for fp / fn), delta_ap_r40, delta_ap_r11, ap_r40, ap_r11. Numbers at full
// precision (shortest round trip); empty for NaN. `header`: start with the header line.
std::string FormatErrorCsv(const std::vector<ErrorAnalysis>& analyses, const std::string& overlaps,
                           bool header = true);

}  // namespace stereodet

#endif  // STEREODET_REPORT_ERROR_REPORT_H_
