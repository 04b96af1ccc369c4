// `stereodet report RESULTS_DIR... [--out DIR] [--labels A,B] [--no-png]`: figures (SVG, PNG) and
// one self-contained HTML page of one or several results folders (docs/report.md). The library call
// is WriteReport(ReportOptions) (report/html_report.h).
#include <fmt/format.h>

#include <memory>
#include <sstream>

#include "stereodet/cli/commands.h"
#include "stereodet/report/html_report.h"

namespace stereodet::cli {

namespace {

struct ReportArgs {
  ReportOptions options;
  std::vector<std::string> results;
  std::string labels;  // comma separated
  bool no_png = false;
};

void RunReport(const ReportArgs& a) {
  ReportOptions options = a.options;
  for (const std::string& r : a.results) options.results.emplace_back(r);
  std::stringstream labels(a.labels);
  for (std::string label; std::getline(labels, label, ',');) options.labels.push_back(label);
  options.png = !a.no_png;
  const ReportResult result = WriteReport(options);
  for (const std::string& note : result.notes) fmt::print("note: {}\n", note);
  fmt::print("report: {} figures ({}), {} files\n", result.num_figures,
             result.png ? "SVG and PNG" : "SVG", result.files.size());
  fmt::print("open {}\n", result.index.string());
}

}  // namespace

void AddReportCommand(CLI::App& app) {
  auto args = std::make_shared<ReportArgs>();
  CLI::App* report = app.add_subcommand("report", CommandDescription("report"));
  report
      ->add_option("results", args->results,
                   "results folders of `stereodet eval --out` (several: overlaid, one colour each)")
      ->required();
  report->add_option("--out", args->options.out,
                     "the report folder (default with one results folder: RESULTS/report; replaced "
                     "whole; a folder of other files is refused)");
  report->add_option("--labels", args->labels,
                     "names in legends and tables, comma separated, one per results folder "
                     "(default: the folders' names)");
  report->add_flag("--no-png", args->no_png, "SVG figures only");
  report->add_option("--png-scale", args->options.png_scale, "PNG pixels per SVG pixel")
      ->capture_default_str();
  report->callback([args] { RunReport(*args); });
}

}  // namespace stereodet::cli
