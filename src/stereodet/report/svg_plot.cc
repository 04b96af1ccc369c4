#include "stereodet/report/svg_plot.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "stereodet/util/check.h"

namespace stereodet {

namespace {

constexpr double kLeft = 64, kRight = 16, kTop = 30, kBottom = 46;
constexpr double kLegendRow = 17;
constexpr const char* kFont = "DejaVu Sans, Arial, Helvetica, sans-serif";

std::string Colour(const PlotSeries& s, size_t index) {
  return s.colour.empty() ? PaletteColour(index) : s.colour;
}

// Shortest text of a tick value: "0.25", "40", "1e-05".
std::string TickText(double v, double step) {
  if (std::abs(v) < step * 1e-9) v = 0;
  return fmt::format("{:.6g}", v);
}

std::string Px(double v) { return fmt::format("{:.2f}", v); }

// ' stroke-dasharray="..."' for a dashed or dotted series, else nothing.
std::string DashAttribute(const PlotSeries& s) {
  const std::string dash = s.DashArray();
  return dash.empty() ? std::string() : " stroke-dasharray=\"" + XmlEscape(dash) + "\"";
}

// A legend entry's lines: words joined up to `max_chars` a line (DejaVu Sans at 12 px is about 7 px
// a character), so that a long entry wraps instead of running off the figure.
std::vector<std::string> WrapLegend(const std::string& text, size_t max_chars) {
  std::vector<std::string> lines(1);
  size_t begin = 0;
  while (begin < text.size()) {
    size_t end = text.find(' ', begin);
    if (end == std::string::npos) end = text.size();
    const std::string word = text.substr(begin, end - begin);
    if (!lines.back().empty() && lines.back().size() + 1 + word.size() > max_chars) {
      lines.emplace_back();
    }
    if (!lines.back().empty()) lines.back() += ' ';
    lines.back() += word;
    begin = end + 1;
  }
  return lines;
}

constexpr double kLegendLeft = 8, kLegendText = kLegendLeft + 28, kCharPx = 7;

size_t LegendChars(const Plot& plot) {
  return static_cast<size_t>(std::max(10.0, (plot.width_px - kLegendText - 8) / kCharPx));
}

void Extend(double v, double& lo, double& hi) {
  if (!std::isfinite(v)) return;
  lo = std::min(lo, v);
  hi = std::max(hi, v);
}

// Widens [lo, hi] to the outer ticks; a NaN end stays as given otherwise.
void NiceRange(double fixed_lo, double fixed_hi, double data_lo, double data_hi, double& lo,
               double& hi) {
  lo = std::isnan(fixed_lo) ? data_lo : fixed_lo;
  hi = std::isnan(fixed_hi) ? data_hi : fixed_hi;
  if (!std::isfinite(lo) || !std::isfinite(hi)) {
    lo = 0;
    hi = 1;
  }
  if (hi <= lo) {
    const double pad = lo == 0 ? 1 : std::abs(lo) * 0.1;
    lo -= std::isnan(fixed_lo) ? pad : 0;
    hi = lo + (hi - lo > 0 ? hi - lo : 2 * pad);
    if (hi <= lo) hi = lo + 1;
  }
  const std::vector<double> ticks = NiceTicks(lo, hi);
  if (std::isnan(fixed_lo)) lo = std::min(lo, ticks.front());
  if (std::isnan(fixed_hi)) hi = std::max(hi, ticks.back());
}

}  // namespace

void Plot::Check() const {
  STEREODET_CHECK(!id.empty()) << "plot id is empty";
  for (char c : id) {
    STEREODET_CHECK(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')
        << "plot id '" << id << "': only letters, digits, '_' and '-'";
  }
  STEREODET_CHECK(width_px >= 160 && height_px >= 120)
      << "plot '" << id << "': size " << width_px << " x " << height_px << " px is too small";
  for (const PlotSeries& s : series) {
    STEREODET_CHECK(s.x.size() == s.y.size())
        << "plot '" << id << "', series '" << s.name << "': " << s.x.size() << " x values, "
        << s.y.size() << " y values";
    STEREODET_CHECK((s.y_low.empty() && s.y_high.empty()) ||
                    (s.y_low.size() == s.y.size() && s.y_high.size() == s.y.size()))
        << "plot '" << id << "', series '" << s.name << "': error bars need one low and high per y";
  }
}

double PlotFrame::XPx(double x) const {
  return left + (x - x_min) / (x_max - x_min) * (right - left);
}
double PlotFrame::YPx(double y) const {
  return bottom - (y - y_min) / (y_max - y_min) * (bottom - top);
}

std::vector<double> NiceTicks(double lo, double hi, int target) {
  STEREODET_CHECK(lo < hi) << "NiceTicks: range [" << lo << ", " << hi << "] is empty";
  const double raw = (hi - lo) / std::max(1, target);
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  double step = magnitude;
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    step = m * magnitude;
    if (step >= raw) break;
  }
  std::vector<double> ticks;
  const double first = std::floor(lo / step + 1e-9) * step;
  for (int i = 0; i < 1000; ++i) {
    const double t = first + i * step;
    ticks.push_back(std::abs(t) < step * 1e-9 ? 0.0 : t);
    if (t >= hi - step * 1e-9) break;
  }
  return ticks;
}

std::string PaletteColour(size_t index) {
  static constexpr const char* kPalette[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                             "#E69F00", "#56B4E9", "#000000", "#F0E442"};
  return kPalette[index % std::size(kPalette)];
}

std::string XmlEscape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

PlotFrame LayOutPlot(const Plot& plot) {
  const bool bars = !plot.categories.empty();
  double x_lo = INFINITY, x_hi = -INFINITY, y_lo = INFINITY, y_hi = -INFINITY;
  for (const PlotSeries& s : plot.series) {
    for (size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      Extend(s.x[i], x_lo, x_hi);
      Extend(s.y[i], y_lo, y_hi);
      if (!s.y_low.empty()) {
        Extend(s.y_low[i], y_lo, y_hi);
        Extend(s.y_high[i], y_lo, y_hi);
      }
    }
  }
  PlotFrame f;
  if (bars) {
    f.x_min = -0.5;
    f.x_max = static_cast<double>(plot.categories.size()) - 0.5;
    Extend(0.0, y_lo, y_hi);
  } else {
    NiceRange(plot.x_min, plot.x_max, x_lo, x_hi, f.x_min, f.x_max);
  }
  NiceRange(plot.y_min, plot.y_max, y_lo, y_hi, f.y_min, f.y_max);
  f.left = kLeft;
  f.right = plot.width_px - kRight;
  f.top = kTop;
  f.bottom = plot.height_px - kBottom;
  return f;
}

nlohmann::json PlotToJson(const Plot& plot) {
  auto numbers = [](const std::vector<double>& v) {
    nlohmann::json a = nlohmann::json::array();
    for (double x : v) a.push_back(std::isfinite(x) ? nlohmann::json(x) : nlohmann::json());
    return a;
  };
  nlohmann::json series = nlohmann::json::array();
  for (const PlotSeries& s : plot.series) {
    static constexpr const char* kStyles[] = {"line", "line_markers", "markers", "bars"};
    nlohmann::json j = {{"name", s.name},
                        {"style", kStyles[static_cast<int>(s.style)]},
                        {"x", numbers(s.x)},
                        {"y", numbers(s.y)}};
    if (s.steps) j["steps"] = true;
    if (!s.y_low.empty()) {
      j["y_low"] = numbers(s.y_low);
      j["y_high"] = numbers(s.y_high);
    }
    series.push_back(std::move(j));
  }
  return {{"id", plot.id},           {"title", plot.title},     {"x_label", plot.x_label},
          {"y_label", plot.y_label}, {"caption", plot.caption}, {"categories", plot.categories},
          {"series", series}};
}

std::string RenderSvg(const Plot& plot) {
  plot.Check();
  const PlotFrame f = LayOutPlot(plot);
  size_t legend_rows = 0;
  for (const PlotSeries& s : plot.series) {
    legend_rows += s.name.empty() ? 0 : WrapLegend(s.name, LegendChars(plot)).size();
  }
  const double height =
      plot.height_px + (legend_rows > 0 ? static_cast<double>(legend_rows) * kLegendRow + 6 : 0);
  std::string svg = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" id=\"{0}\" class=\"plot\" "
      "width=\"{1}\" height=\"{2}\" viewBox=\"0 0 {1} {2}\" font-family=\"{3}\" "
      "font-size=\"12\">\n",
      plot.id, Px(plot.width_px), Px(height), kFont);
  std::string data = PlotToJson(plot).dump();
  for (size_t p = 0; (p = data.find("]]>", p)) != std::string::npos; p += 12) {
    data.replace(p, 3, "]]]]><![CDATA[>");
  }
  svg += fmt::format("<metadata id=\"{}-data\"><![CDATA[{}]]></metadata>\n", plot.id, data);
  svg += fmt::format("<title>{}</title>\n", XmlEscape(plot.title));
  svg += fmt::format("<rect width=\"{}\" height=\"{}\" fill=\"#ffffff\"/>\n", Px(plot.width_px),
                     Px(height));
  svg += fmt::format(
      "<text x=\"{}\" y=\"18\" text-anchor=\"middle\" font-size=\"13\" "
      "font-weight=\"bold\">{}</text>\n",
      Px((f.left + f.right) / 2), XmlEscape(plot.title));

  // Grid, ticks and tick labels.
  const bool bars = !plot.categories.empty();
  svg += "<g class=\"axes\" stroke=\"#000000\" stroke-width=\"1\">\n";
  const std::vector<double> y_ticks = NiceTicks(f.y_min, f.y_max);
  const double y_step = y_ticks.size() > 1 ? y_ticks[1] - y_ticks[0] : 1;
  for (double t : y_ticks) {
    if (t < f.y_min - 1e-9 * y_step || t > f.y_max + 1e-9 * y_step) continue;
    const double y = f.YPx(t);
    svg += fmt::format("<line x1=\"{0}\" y1=\"{1}\" x2=\"{2}\" y2=\"{1}\" stroke=\"#dddddd\"/>\n",
                       Px(f.left), Px(y), Px(f.right));
    svg += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"end\" stroke=\"none\">{}</text>\n",
                       Px(f.left - 5), Px(y + 4), TickText(t, y_step));
  }
  if (bars) {
    for (size_t i = 0; i < plot.categories.size(); ++i) {
      svg += fmt::format(
          "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" stroke=\"none\">{}</text>\n",
          Px(f.XPx(static_cast<double>(i))), Px(f.bottom + 16), XmlEscape(plot.categories[i]));
    }
  } else {
    const std::vector<double> x_ticks = NiceTicks(f.x_min, f.x_max);
    const double x_step = x_ticks.size() > 1 ? x_ticks[1] - x_ticks[0] : 1;
    for (double t : x_ticks) {
      if (t < f.x_min - 1e-9 * x_step || t > f.x_max + 1e-9 * x_step) continue;
      const double x = f.XPx(t);
      svg += fmt::format("<line x1=\"{0}\" y1=\"{1}\" x2=\"{0}\" y2=\"{2}\" stroke=\"#dddddd\"/>\n",
                         Px(x), Px(f.top), Px(f.bottom));
      svg +=
          fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" stroke=\"none\">{}</text>\n",
                      Px(x), Px(f.bottom + 16), TickText(t, x_step));
    }
  }
  svg += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\"/>\n",
                     Px(f.left), Px(f.top), Px(f.right - f.left), Px(f.bottom - f.top));
  svg += "</g>\n";
  svg += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n",
                     Px((f.left + f.right) / 2), Px(f.bottom + 34), XmlEscape(plot.x_label));
  svg += fmt::format(
      "<text x=\"16\" y=\"{0}\" text-anchor=\"middle\" "
      "transform=\"rotate(-90 16 {0})\">{1}</text>\n",
      Px((f.top + f.bottom) / 2), XmlEscape(plot.y_label));

  // The series, clipped to the plot area.
  svg += fmt::format(
      "<clipPath id=\"{}-area\"><rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"/>"
      "</clipPath>\n",
      plot.id, Px(f.left - 4), Px(f.top - 4), Px(f.right - f.left + 8), Px(f.bottom - f.top + 8));
  size_t num_bar_series = 0;
  for (const PlotSeries& s : plot.series) num_bar_series += s.style == SeriesStyle::kBars ? 1 : 0;
  size_t bar_index = 0;
  for (size_t si = 0; si < plot.series.size(); ++si) {
    const PlotSeries& s = plot.series[si];
    const std::string colour = Colour(s, si);
    svg += fmt::format(
        "<g class=\"series\" data-series=\"{}\" data-index=\"{}\" clip-path=\"url(#{}-area)\">\n",
        XmlEscape(s.name), si, plot.id);
    // A bar series' bars sit side by side in their category's slot; whiskers go on the bar.
    const double slot = (f.XPx(1) - f.XPx(0)) * 0.8;
    const double bar_w = slot / static_cast<double>(std::max<size_t>(1, num_bar_series));
    const size_t this_bar = bar_index;
    auto bar_centre = [&](double x) {
      return f.XPx(x) - slot / 2 + bar_w * (static_cast<double>(this_bar) + 0.46);
    };
    if (s.style == SeriesStyle::kBars) {
      const double w = bar_w;
      for (size_t i = 0; i < s.x.size(); ++i) {
        if (!std::isfinite(s.y[i])) continue;
        const double x0 = f.XPx(s.x[i]) - slot / 2 + w * static_cast<double>(bar_index);
        const double y0 = f.YPx(std::max(0.0, s.y[i])), y1 = f.YPx(std::min(0.0, s.y[i]));
        svg += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"{}\"/>\n",
                           Px(x0), Px(y0), Px(w * 0.92), Px(y1 - y0), colour);
      }
      ++bar_index;
    }
    if (s.style == SeriesStyle::kLine || s.style == SeriesStyle::kLineMarkers) {
      std::string points;
      auto flush = [&] {
        if (!points.empty()) {
          svg += fmt::format(
              "<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"1.8\"{} "
              "points=\"{}\"/>\n",
              colour, DashAttribute(s), points);
        }
        points.clear();
      };
      for (size_t i = 0; i < s.x.size(); ++i) {
        if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
          flush();
          continue;
        }
        if (!points.empty()) {
          // A step: across at the previous point's y first.
          if (s.steps) points += ' ' + Px(f.XPx(s.x[i])) + "," + Px(f.YPx(s.y[i - 1]));
          points += ' ';
        }
        points += Px(f.XPx(s.x[i])) + "," + Px(f.YPx(s.y[i]));
      }
      flush();
    }
    if (s.style == SeriesStyle::kLineMarkers || s.style == SeriesStyle::kMarkers) {
      for (size_t i = 0; i < s.x.size(); ++i) {
        if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
        svg += fmt::format("<circle cx=\"{}\" cy=\"{}\" r=\"2.6\" fill=\"{}\"/>\n",
                           Px(f.XPx(s.x[i])), Px(f.YPx(s.y[i])), colour);
      }
    }
    if (!s.y_low.empty()) {
      for (size_t i = 0; i < s.x.size(); ++i) {
        if (!std::isfinite(s.x[i]) || !std::isfinite(s.y_low[i]) || !std::isfinite(s.y_high[i])) {
          continue;
        }
        // On a bar the whisker is dark (the bar's own colour would hide it).
        const bool bars = s.style == SeriesStyle::kBars;
        svg += fmt::format(
            "<line class=\"whisker\" x1=\"{0}\" y1=\"{1}\" x2=\"{0}\" y2=\"{2}\" "
            "stroke=\"{3}\" stroke-width=\"{4}\"/>\n",
            Px(bars ? bar_centre(s.x[i]) : f.XPx(s.x[i])), Px(f.YPx(s.y_low[i])),
            Px(f.YPx(s.y_high[i])), bars ? std::string("#222222") : colour, bars ? "1.6" : "1.2");
      }
    }
    svg += "</g>\n";
  }

  // The legend, below the plot, one row per named series (more where its name wraps).
  double y = plot.height_px + 4;
  for (size_t si = 0; si < plot.series.size(); ++si) {
    const PlotSeries& s = plot.series[si];
    if (s.name.empty()) continue;
    const std::string colour = Colour(s, si);
    const double mid = y + kLegendRow / 2;
    svg += "<g class=\"legend\">";
    if (s.style == SeriesStyle::kBars) {
      svg += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"18\" height=\"10\" fill=\"{}\"/>",
                         Px(kLegendLeft), Px(mid - 5), colour);
    } else {
      if (s.style != SeriesStyle::kMarkers) {
        svg += fmt::format(
            "<line x1=\"{0}\" y1=\"{1}\" x2=\"{2}\" y2=\"{1}\" stroke=\"{3}\" "
            "stroke-width=\"1.8\"{4}/>",
            Px(kLegendLeft), Px(mid), Px(kLegendLeft + 22), colour, DashAttribute(s));
      }
      if (s.style != SeriesStyle::kLine) {
        svg += fmt::format("<circle cx=\"{}\" cy=\"{}\" r=\"2.6\" fill=\"{}\"/>",
                           Px(kLegendLeft + 11), Px(mid), colour);
      }
    }
    for (const std::string& line : WrapLegend(s.name, LegendChars(plot))) {
      svg += fmt::format("<text x=\"{}\" y=\"{}\">{}</text>", Px(kLegendText),
                         Px(y + kLegendRow / 2 + 4), XmlEscape(line));
      y += kLegendRow;
    }
    svg += "</g>\n";
  }
  svg += "</svg>\n";
  return svg;
}

}  // namespace stereodet
