// Figures as SVG: a small, fixed vocabulary of 2D plots (lines, markers, error bars, grouped bars)
// with axes, ticks, labels and a legend, written as standalone SVG 1.1 text. The data of every
// series is embedded in the SVG (a <metadata> element holding PlotToJson), so a figure can be
// checked against the numbers it plots and re-plotted elsewhere. PNG files are rasterized from the
// same SVG text (raster.h). See docs/report.md for why the figures are written here.
#ifndef STEREODET_REPORT_SVG_PLOT_H_
#define STEREODET_REPORT_SVG_PLOT_H_

#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace stereodet {

enum class SeriesStyle {
  kLine,         // a polyline through the points (NaN points break it)
  kLineMarkers,  // a polyline and a circle on each point
  kMarkers,      // circles only
  kBars,         // one bar per point: x is the category index (Plot::categories), y the height
};

struct PlotSeries {
  std::string name;  // legend entry; empty: not in the legend
  SeriesStyle style = SeriesStyle::kLine;
  std::vector<double> x, y;  // data units; same length
  // Optional error bars: y_low[i] .. y_high[i] drawn as a vertical whisker at x[i] (both empty, or
  // the length of y; NaN: no whisker at that point).
  std::vector<double> y_low, y_high;
  std::string colour;  // any SVG colour; empty: the palette's colour for this series' index
  bool dashed = false;
  // The line's SVG stroke-dasharray ("1.5,2.5": dotted); empty: solid, or "5,3" when dashed.
  std::string dash_array;
  // kLine / kLineMarkers: draw the line as steps, from (x[i], y[i]) across to (x[i+1], y[i]) and
  // then up or down to (x[i+1], y[i+1]) (a precision-recall curve at every score: precision holds
  // until the next detection). The data is unchanged.
  bool steps = false;
  std::string DashArray() const { return !dash_array.empty() ? dash_array : dashed ? "5,3" : ""; }
};

struct Plot {
  std::string id;                // file stem and element id: letters, digits, '_' and '-' only
  std::string title;             // drawn above the plot area
  std::string x_label, y_label;  // with units, e.g. "recall", "3D centre error (m)"
  // Axis ranges in data units; NaN: from the data (with y from 0 for bars), widened to nice ticks.
  double x_min = std::numeric_limits<double>::quiet_NaN();
  double x_max = std::numeric_limits<double>::quiet_NaN();
  double y_min = std::numeric_limits<double>::quiet_NaN();
  double y_max = std::numeric_limits<double>::quiet_NaN();
  // For bar charts: the x tick labels of categories 0, 1, ...; the x axis then shows these.
  std::vector<std::string> categories;
  std::vector<PlotSeries> series;
  std::string caption;  // one or two sentences with the numbers the figure summarises (HTML only)
  double width_px = 480, height_px = 340;  // the plot's size without the legend
  void Check() const;  // throws std::invalid_argument (bad id, mismatched lengths, bad size)
};

// Where data coordinates land in the SVG: x_px = left + (x - x_min) / (x_max - x_min) * (right -
// left), y_px = bottom - (y - y_min) / (y_max - y_min) * (bottom - top).
struct PlotFrame {
  double x_min = 0, x_max = 1, y_min = 0, y_max = 1;  // the axes' ranges after widening
  double left = 0, right = 0, top = 0, bottom = 0;    // the plot area in SVG pixels
  double XPx(double x) const;
  double YPx(double y) const;
};

// The axis ranges and the plot area RenderSvg uses for `plot`.
PlotFrame LayOutPlot(const Plot& plot);

// The figure as a standalone SVG document (width and height in px, white background). Each series
// is a <g class="series" data-series="NAME" data-index="I"> group of <polyline>, <circle>, <line>
// or <rect> elements; <metadata id="ID-data"> holds PlotToJson(plot). Throws what Check throws.
std::string RenderSvg(const Plot& plot);

// {"id", "title", "x_label", "y_label", "caption", "categories", "series": [{"name", "style", "x",
// "y", ("y_low", "y_high")}]}: the plotted numbers in data units (NaN as null).
nlohmann::json PlotToJson(const Plot& plot);

// Tick values for an axis from `lo` to `hi`: multiples of 1, 2 or 5 x 10^k, about `target` of them,
// covering [lo, hi]. Requires lo < hi.
std::vector<double> NiceTicks(double lo, double hi, int target = 5);

// The series palette: colour-blind-safe (Okabe-Ito, all 8, yellow last: the weakest on white), in
// the order series take them; index i gets colour i mod 8. Reports give each overlaid results
// folder its index, so that a folder has one colour in every figure.
std::string PaletteColour(size_t index);

// Text for SVG / HTML content and attribute values: & < > " ' escaped.
std::string XmlEscape(const std::string& text);

}  // namespace stereodet

#endif  // STEREODET_REPORT_SVG_PLOT_H_
