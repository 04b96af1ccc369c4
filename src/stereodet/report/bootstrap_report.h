// Bootstrap intervals (eval/bootstrap.h) as JSON, text and CSV: what `stereodet eval --bootstrap N`
// adds to results.json and the printed table, and what `stereodet eval compare --bootstrap N`
// writes to bootstrap.csv. Definitions in docs/metrics.md, "Bootstrap intervals".
#ifndef STEREODET_REPORT_BOOTSTRAP_REPORT_H_
#define STEREODET_REPORT_BOOTSTRAP_REPORT_H_

#include <nlohmann/json.hpp>
#include <string>

#include "stereodet/eval/bootstrap.h"

namespace stereodet {

// How the intervals were made: {"resamples", "seed", "confidence", "method": "percentile",
// "resampled": "frames", "seconds"}; results.json's top-level "bootstrap".
nlohmann::json BootstrapSummaryJson(const BootstrapResult& result);

// One cell's intervals: {METRIC: {"estimate", "lower", "upper", "resamples_defined"}} for each of
// BootstrapMetrics(matcher) (BootstrapMetricName keys; NaN as null); each results.json cell's
// "bootstrap".
nlohmann::json BootstrapCellJson(const BootstrapCell& cell, Matcher matcher);
// The same for one breakdown bin: each results.json cell's "breakdown" entry's "bootstrap".
nlohmann::json BootstrapBinJson(const BootstrapBin& bin, Matcher matcher);

// The printed block: a title line (resamples, frames, seed, confidence), a header, then one line
// per evaluated cell: class, kind, difficulty, and per metric (AP_R40, AP_R11, AP_VOC for the
// exact matchers, Brier over labels) "estimate [lower, upper]" (AP 2 decimals, Brier 4), each cell
// followed by one line per breakdown bin ("distance [0, 30)", the same metrics).
std::string FormatBootstrapTable(const BootstrapResult& result);

// `eval compare --bootstrap` as CSV, one row per cell and metric (BootstrapMetrics order), cells
// in result order: class, metric, difficulty, measure, a, a_lower, a_upper, b, b_lower, b_upper,
// a_minus_b, a_minus_b_lower, a_minus_b_upper, resamples, resamples_defined (of the difference),
// confidence, seed. Numbers at full precision (shortest round trip); empty for NaN.
std::string FormatPairedBootstrapCsv(const PairedBootstrapResult& result);
// With breakdowns (eval compare --breakdown): one row per cell, bin and metric, cells in result
// order and bins in BootstrapCell::breakdown's: class, metric, difficulty, axis, lower, upper
// (empty: infinite), measure, then as FormatPairedBootstrapCsv. Only the header when no cell has
// bins.
std::string FormatPairedBootstrapBreakdownCsv(const PairedBootstrapResult& result);
// Every resample's values (the result must have been made with keep_samples): one row per
// resample, evaluated cell and measure (ap_r40, brier_labels, brier_detections, brier_all),
// resample-major:
//   resample,class,metric,difficulty,measure,a,b,a_minus_b
// (full precision, empty for NaN). Resample r's frame counts depend on (frames, seed, r) only,
// so two compares with the same seed on the same frames resampled the same frames in row r.
std::string FormatPairedBootstrapSamplesCsv(const PairedBootstrapResult& result);

// The printed block of the paired difference: title, then per evaluated cell its A - B with its
// interval for AP_R40 and Brier over labels, and whether the interval excludes 0; each cell
// followed by one line per breakdown bin ("distance [0, 30)", the same columns).
std::string FormatPairedBootstrapTable(const PairedBootstrapResult& result);

}  // namespace stereodet

#endif  // STEREODET_REPORT_BOOTSTRAP_REPORT_H_
