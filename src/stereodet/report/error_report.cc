#include "stereodet/report/error_report.h"

#include <fmt/format.h>

#include <cmath>
#include <sstream>

#include "stereodet/report/report_json_internal.h"

namespace stereodet {

namespace {

using nlohmann::json;

using report_internal::Csv;

std::string Points(double v) { return std::isnan(v) ? std::string("-") : fmt::format("{:.2f}", v); }

constexpr ErrorType kTypes[kNumErrorTypes] = {ErrorType::kCls,  ErrorType::kLoc,
                                              ErrorType::kBoth, ErrorType::kDupe,
                                              ErrorType::kBkg,  ErrorType::kMissed};

}  // namespace

json ErrorAnalysisJson(const ErrorAnalysis& a) {
  json count = json::object(), r40 = json::object(), r11 = json::object();
  for (const ErrorType type : kTypes) {
    const int t = static_cast<int>(type);
    count[ErrorTypeName(type)] = a.count[t];
    r40[ErrorTypeName(type)] = a.delta_ap_r40[t];
    r11[ErrorTypeName(type)] = a.delta_ap_r11[t];
  }
  return {{"background_overlap", a.background_overlap},
          {"min_overlap", a.min_overlap},
          {"tp", a.tp},
          {"fp", a.fp},
          {"fn", a.fn},
          {"ap_r40", a.ap_r40},
          {"ap_r11", a.ap_r11},
          {"count", count},
          {"delta_ap_r40", r40},
          {"delta_ap_r11", r11},
          {"special",
           {{"fp_r40", a.delta_fp_r40},
            {"fp_r11", a.delta_fp_r11},
            {"fn_r40", a.delta_fn_r40},
            {"fn_r11", a.delta_fn_r11}}},
          {"cls_incoming", a.cls_incoming},
          {"seconds", a.seconds}};
}

std::string FormatErrorTable(const std::vector<ErrorAnalysis>& analyses) {
  std::ostringstream out;
  if (analyses.empty()) return out.str();
  out << fmt::format(
      "\nError analysis (TIDE; docs/metrics.md): AP_R40 points gained by fixing each error type "
      "alone, every detection taking part; background below overlap {}\n",
      analyses.front().background_overlap);
  out << fmt::format("{:<11}{:<8}{:<9}{:>7} |{:>7}{:>7}{:>7}{:>7}{:>7}{:>7} |{:>7}{:>7} | {}\n",
                     "class", "metric", "diff.", "AP_R40", "cls", "loc", "both", "dupe", "bkg",
                     "missed", "FP", "FN", "count cls/loc/both/dupe/bkg/missed");
  for (const ErrorAnalysis& a : analyses) {
    if (!a.evaluated) continue;
    out << fmt::format("{:<11}{:<8}{:<9}{:>7} |", a.class_name, OverlapKindName(a.kind),
                       DifficultyName(a.difficulty), Points(a.ap_r40));
    for (const ErrorType type : kTypes) {
      out << fmt::format("{:>7}", Points(a.delta_ap_r40[static_cast<int>(type)]));
    }
    out << fmt::format(" |{:>7}{:>7} | {}/{}/{}/{}/{}/{}\n", Points(a.delta_fp_r40),
                       Points(a.delta_fn_r40), a.count[0], a.count[1], a.count[2], a.count[3],
                       a.count[4], a.count[5]);
  }
  return out.str();
}

std::string FormatErrorCsv(const std::vector<ErrorAnalysis>& analyses, const std::string& overlaps,
                           bool header) {
  std::ostringstream out;
  if (header) {
    out << "class,metric,difficulty,overlaps,error,count,delta_ap_r40,delta_ap_r11,ap_r40,ap_r11\n";
  }
  for (const ErrorAnalysis& a : analyses) {
    const std::string cell = fmt::format("{},{},{},{}", a.class_name, OverlapKindName(a.kind),
                                         DifficultyName(a.difficulty), overlaps);
    const std::string ap = fmt::format("{},{}", Csv(a.ap_r40), Csv(a.ap_r11));
    for (const ErrorType type : kTypes) {
      const int t = static_cast<int>(type);
      out << fmt::format("{},{},{},{},{},{}\n", cell, ErrorTypeName(type), a.count[t],
                         Csv(a.delta_ap_r40[t]), Csv(a.delta_ap_r11[t]), ap);
    }
    out << fmt::format("{},fp,,{},{},{}\n", cell, Csv(a.delta_fp_r40), Csv(a.delta_fp_r11), ap);
    out << fmt::format("{},fn,,{},{},{}\n", cell, Csv(a.delta_fn_r40), Csv(a.delta_fn_r11), ap);
  }
  return out.str();
}

}  // namespace stereodet
