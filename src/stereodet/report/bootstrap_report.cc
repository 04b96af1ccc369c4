#include "stereodet/report/bootstrap_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <string_view>
#include <vector>

#include "stereodet/report/eval_report.h"
#include "stereodet/report/report_json_internal.h"
#include "stereodet/util/check.h"

namespace stereodet {

namespace {

using nlohmann::json;

// The metrics shown in the text tables: the APs and the Brier score over labels.
std::vector<BootstrapMetric> TableMetrics(Matcher matcher) {
  std::vector<BootstrapMetric> out = {BootstrapMetric::kApR40, BootstrapMetric::kApR11};
  if (matcher != Matcher::kKitti) out.push_back(BootstrapMetric::kApVoc);
  out.push_back(BootstrapMetric::kBrierLabels);
  return out;
}

int Decimals(BootstrapMetric m) {
  return m == BootstrapMetric::kApR40 || m == BootstrapMetric::kApR11 ||
                 m == BootstrapMetric::kApVoc
             ? 2
             : 4;
}

std::string Title(BootstrapMetric m) {
  switch (m) {
    case BootstrapMetric::kApR40:
      return "AP_R40";
    case BootstrapMetric::kApR11:
      return "AP_R11";
    case BootstrapMetric::kApVoc:
      return "AP_VOC";
    case BootstrapMetric::kBrierLabels:
      return "Brier_L";
    case BootstrapMetric::kBrierDetections:
      return "Brier_D";
    case BootstrapMetric::kBrierAll:
      return "Brier_A";
  }
  return "?";
}

std::string WithInterval(const BootstrapInterval& i, int decimals) {
  return fmt::format("{} [{}, {}]", FormatNumber(i.estimate, decimals),
                     FormatNumber(i.lower, decimals), FormatNumber(i.upper, decimals));
}

using report_internal::Csv;
// A bin edge: empty for an infinite one (breakdown.csv's convention).
std::string Edge(double v) { return std::isinf(v) ? std::string() : Csv(v); }

std::string PercentText(double confidence) { return fmt::format("{:g}%", confidence * 100); }

// `text` without the blanks at the end of its lines (the last column's padding).
std::string WithoutTrailingBlanks(const std::string& text) {
  std::istringstream in(text);
  std::string out, line;
  while (std::getline(in, line)) {
    line.erase(line.find_last_not_of(' ') + 1);
    out += line + "\n";
  }
  return out;
}

}  // namespace

json BootstrapSummaryJson(const BootstrapResult& result) {
  return json{{"resamples", result.num_resamples},
              {"seed", result.seed},
              {"confidence", result.confidence},
              {"method", BootstrapMethodName(result.method)},
              {"resampled", "frames"},
              {"seconds", result.seconds}};
}

namespace {

json IntervalsJson(const std::array<BootstrapInterval, kNumBootstrapMetrics>& intervals,
                   Matcher matcher) {
  json j = json::object();
  for (const BootstrapMetric m : BootstrapMetrics(matcher)) {
    const BootstrapInterval& i = intervals[static_cast<int>(m)];
    j[BootstrapMetricName(m)] = {{"estimate", i.estimate},
                                 {"lower", i.lower},
                                 {"upper", i.upper},
                                 {"resamples_defined", i.num_defined}};
  }
  return j;
}

}  // namespace

json BootstrapCellJson(const BootstrapCell& cell, Matcher matcher) {
  return IntervalsJson(cell.intervals, matcher);
}

json BootstrapBinJson(const BootstrapBin& bin, Matcher matcher) {
  return IntervalsJson(bin.intervals, matcher);
}

// The tables' kind column: its longest name ("let-bev"), at least 4 wide ("kind").
size_t KindWidth(const std::vector<BootstrapCell>& cells) {
  size_t width = 4;
  for (const BootstrapCell& cell : cells) {
    width = std::max(width, std::string_view(OverlapKindName(cell.metric)).size());
  }
  return width;
}

std::string FormatBootstrapTable(const BootstrapResult& result) {
  std::ostringstream out;
  out << fmt::format("bootstrap: {} resamples of the {} frames (seed {}), {} {} intervals\n",
                     result.num_resamples, result.num_frames, result.seed,
                     PercentText(result.confidence), BootstrapMethodTitle(result.method));
  const std::vector<BootstrapMetric> metrics = TableMetrics(result.matcher);
  const size_t kind_width = KindWidth(result.cells);
  out << fmt::format("{:<12} {:<{}} {:<8} |", "class", "kind", kind_width, "diff.");
  for (const BootstrapMetric m : metrics) out << fmt::format(" {:<26}", Title(m));
  out << "\n";
  for (const BootstrapCell& cell : result.cells) {
    if (!cell.evaluated) continue;
    out << fmt::format("{:<12} {:<{}} {:<8} |", cell.class_name, OverlapKindName(cell.metric),
                       kind_width, DifficultyName(cell.difficulty));
    for (const BootstrapMetric m : metrics) {
      out << fmt::format(" {:<26}", WithInterval(cell.Get(m), Decimals(m)));
    }
    out << "\n";
    for (const BootstrapBin& bin : cell.breakdown) {
      out << fmt::format(
          "{:>{}} |",
          std::string(BreakdownAxisName(bin.axis)) + " " + BreakdownBinName(bin.lower, bin.upper),
          22 + kind_width);
      for (const BootstrapMetric m : metrics) {
        out << fmt::format(" {:<26}", WithInterval(bin.Get(m), Decimals(m)));
      }
      out << "\n";
    }
  }
  return WithoutTrailingBlanks(out.str());
}

// The columns both paired CSVs end with: measure, A, B and A - B with their bounds, the counts,
// confidence and seed.
std::string PairedColumns(BootstrapMetric m, const BootstrapInterval& a, const BootstrapInterval& b,
                          const BootstrapInterval& x, const BootstrapResult& d) {
  return fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{}", BootstrapMetricName(m),
                     Csv(a.estimate), Csv(a.lower), Csv(a.upper), Csv(b.estimate), Csv(b.lower),
                     Csv(b.upper), Csv(x.estimate), Csv(x.lower), Csv(x.upper), d.num_resamples,
                     x.num_defined, d.confidence, d.seed);
}

std::string FormatPairedBootstrapCsv(const PairedBootstrapResult& result) {
  std::ostringstream out;
  out << "class,metric,difficulty,measure,a,a_lower,a_upper,b,b_lower,b_upper,a_minus_b,"
         "a_minus_b_lower,a_minus_b_upper,resamples,resamples_defined,confidence,seed\n";
  const BootstrapResult& d = result.difference;
  for (size_t c = 0; c < d.cells.size(); ++c) {
    const BootstrapCell& cell = d.cells[c];
    for (const BootstrapMetric m : BootstrapMetrics(d.matcher)) {
      const BootstrapInterval& a = result.a.cells[c].Get(m);
      const BootstrapInterval& b = result.b.cells[c].Get(m);
      const BootstrapInterval& x = cell.Get(m);
      out << fmt::format("{},{},{},{}\n", cell.class_name, OverlapKindName(cell.metric),
                         DifficultyName(cell.difficulty), PairedColumns(m, a, b, x, d));
    }
  }
  return out.str();
}

std::string FormatPairedBootstrapBreakdownCsv(const PairedBootstrapResult& result) {
  std::ostringstream out;
  out << "class,metric,difficulty,axis,lower,upper,measure,a,a_lower,a_upper,b,b_lower,b_upper,"
         "a_minus_b,a_minus_b_lower,a_minus_b_upper,resamples,resamples_defined,confidence,seed\n";
  const BootstrapResult& d = result.difference;
  for (size_t c = 0; c < d.cells.size(); ++c) {
    const BootstrapCell& cell = d.cells[c];
    const BootstrapCell& ca = result.a.cells[c];
    const BootstrapCell& cb = result.b.cells[c];
    for (size_t k = 0; k < cell.breakdown.size(); ++k) {
      const BootstrapBin& bin = cell.breakdown[k];
      for (const BootstrapMetric m : BootstrapMetrics(d.matcher)) {
        // B's bin where B has the cell's bins (a cell evaluated in A alone has none there).
        const BootstrapInterval none;
        const BootstrapInterval& a = k < ca.breakdown.size() ? ca.breakdown[k].Get(m) : none;
        const BootstrapInterval& b =
            cb.breakdown.size() == cell.breakdown.size() ? cb.breakdown[k].Get(m) : none;
        const BootstrapInterval& x = bin.Get(m);
        out << fmt::format("{},{},{},{},{},{},{}\n", cell.class_name, OverlapKindName(cell.metric),
                           DifficultyName(cell.difficulty), BreakdownAxisName(bin.axis),
                           Edge(bin.lower), Edge(bin.upper), PairedColumns(m, a, b, x, d));
      }
    }
  }
  return out.str();
}

std::string FormatPairedBootstrapSamplesCsv(const PairedBootstrapResult& result) {
  const BootstrapResult& d = result.difference;
  std::string out = "resample,class,metric,difficulty,measure,a,b,a_minus_b\n";
  // AP_R40 and the three Brier terms: what the experiment's claims are decided by (a claim that
  // two Brier terms rank A and B oppositely needs both terms' resamples).
  const std::array<BootstrapMetric, 4> measures = {
      BootstrapMetric::kApR40, BootstrapMetric::kBrierLabels, BootstrapMetric::kBrierDetections,
      BootstrapMetric::kBrierAll};
  for (int r = 0; r < d.num_resamples; ++r) {
    for (size_t c = 0; c < d.cells.size(); ++c) {
      const BootstrapCell& cell = d.cells[c];
      if (!cell.evaluated) continue;
      for (const BootstrapMetric m : measures) {
        const BootstrapInterval& a = result.a.cells[c].Get(m);
        const BootstrapInterval& b = result.b.cells[c].Get(m);
        const BootstrapInterval& x = cell.Get(m);
        STEREODET_CHECK(x.samples.size() == static_cast<size_t>(d.num_resamples))
            << "paired bootstrap samples: made without keep_samples";
        out += fmt::format("{},{},{},{},{},{},{},{}\n", r, cell.class_name,
                           OverlapKindName(cell.metric), DifficultyName(cell.difficulty),
                           BootstrapMetricName(m), Csv(a.samples[r]), Csv(b.samples[r]),
                           Csv(x.samples[r]));
      }
    }
  }
  return out;
}

std::string FormatPairedBootstrapTable(const PairedBootstrapResult& result) {
  const BootstrapResult& d = result.difference;
  std::ostringstream out;
  out << fmt::format(
      "paired bootstrap A - B: {} resamples of the {} frames (seed {}), {} {} intervals\n",
      d.num_resamples, d.num_frames, d.seed, PercentText(d.confidence),
      BootstrapMethodTitle(d.method));
  const std::vector<BootstrapMetric> metrics = {BootstrapMetric::kApR40,
                                                BootstrapMetric::kBrierLabels};
  const size_t kind_width = KindWidth(d.cells);
  out << fmt::format("{:<12} {:<{}} {:<8} |", "class", "kind", kind_width, "diff.");
  for (const BootstrapMetric m : metrics) out << fmt::format(" {:<32}", Title(m) + " A - B");
  out << "\n";
  for (const BootstrapCell& cell : d.cells) {
    if (!cell.evaluated) continue;
    out << fmt::format("{:<12} {:<{}} {:<8} |", cell.class_name, OverlapKindName(cell.metric),
                       kind_width, DifficultyName(cell.difficulty));
    for (const BootstrapMetric m : metrics) {
      const BootstrapInterval& i = cell.Get(m);
      const bool excludes_zero = i.num_defined > 0 && (i.lower > 0 || i.upper < 0);
      out << fmt::format(" {:<32}", WithInterval(i, Decimals(m)) + (excludes_zero ? " *" : ""));
    }
    out << "\n";
    for (const BootstrapBin& bin : cell.breakdown) {
      out << fmt::format(
          "{:>{}} |",
          std::string(BreakdownAxisName(bin.axis)) + " " + BreakdownBinName(bin.lower, bin.upper),
          22 + kind_width);
      for (const BootstrapMetric m : metrics) {
        const BootstrapInterval& i = bin.Get(m);
        const bool excludes_zero = i.num_defined > 0 && (i.lower > 0 || i.upper < 0);
        out << fmt::format(" {:<32}", WithInterval(i, Decimals(m)) + (excludes_zero ? " *" : ""));
      }
      out << "\n";
    }
  }
  out << "* the interval excludes 0\n";
  return WithoutTrailingBlanks(out.str());
}

}  // namespace stereodet
