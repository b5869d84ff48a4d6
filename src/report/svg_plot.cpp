#include "svg_plot_internal.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string_view>
#include <tuple>

#include <fmt/format.h>

namespace hattr::report::detail {
namespace {

/// "Nice" tick positions covering [lo, hi].
std::vector<double> ticks(double lo, double hi, bool integers = false) {
  const double span = hi - lo;
  const double raw = span / 5.0;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double norm = raw / magnitude;
  double step = (norm < 1.5 ? 1.0 : norm < 3.0 ? 2.0 : norm < 7.0 ? 5.0 : 10.0) * magnitude;
  if (integers) step = std::max(1.0, std::round(step));
  std::vector<double> out;
  for (double t = std::ceil(lo / step) * step; t <= hi + step * 1e-9; t += step) out.push_back(std::abs(t) < step * 1e-9 ? 0.0 : t);
  return out;
}

std::string number(double v) { return fmt::format("{:.4g}", v); }

constexpr std::string_view kClipIdPlaceholder = "@clip@";

/// An error bar: a vertical line from y_low to y_high with short caps, at x (pixels).
std::string whisker(double x, double y_low, double y_high, const std::string& colour = "#222") {
  return fmt::format("<path d=\"M{0:.1f},{1:.1f}V{2:.1f}M{3:.1f},{1:.1f}H{4:.1f}M{3:.1f},{2:.1f}H{4:.1f}\" "
                     "stroke=\"{5}\" stroke-width=\"1.2\" fill=\"none\"/>\n",
                     x, y_low, y_high, x - 4, x + 4, colour);
}

/// Replaces the clip-path id placeholder with one made from the figure itself (FNV-1a of the
/// SVG): unique among a page's figures, and the same figure gets the same id on every run.
std::string withClipId(std::string svg) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  for (const char c : svg) hash = (hash ^ static_cast<unsigned char>(c)) * 0x100000001b3ULL;
  const std::string id = fmt::format("plot-{:016x}", hash);
  for (auto at = svg.find(kClipIdPlaceholder); at != std::string::npos; at = svg.find(kClipIdPlaceholder, at)) {
    svg.replace(at, kClipIdPlaceholder.size(), id);
  }
  return svg;
}

}  // namespace

std::string escape(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

SvgPlot::SvgPlot(std::string title, std::string x_label, std::string y_label, int width, int height)
    : title_(std::move(title)), x_label_(std::move(x_label)), y_label_(std::move(y_label)), width_(width), height_(height) {}

/// The plot area inside the margins [px], the data range it shows and the scale between them.
struct SvgPlot::Area {
  double left, top, pw, ph;  ///< left and top edges, width and height of the plot area [px]
  double x0, x1, y0, y1;     ///< the data range shown
  double sx, sy;             ///< pixels per data unit along x and y
  /// A data point's position in pixels.
  [[nodiscard]] double xPixel(double x) const { return left + (x - x0) * sx; }
  [[nodiscard]] double yPixel(double y) const { return top + ph - (y - y0) * sy; }
};

/// Where the plot area lies and which data range it shows (the series', the bars', or yRange).
SvgPlot::Area SvgPlot::layout() const {
  // Plot area inside margins for the title, labels and legend.
  const double left = 70, right = bars_.empty() ? 190 : 20, top = 34, bottom = 50;
  const double pw = width_ - left - right, ph = height_ - top - bottom;

  // Data ranges (bars: categories 0..n-1 and values from 0).
  // (Error bars count: a whisker is never cut by the frame.)
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
  for (const auto& s : series_) {
    for (std::size_t i = 0; i < s.points.size(); ++i) {
      const auto [x, y] = s.points[i];
      if (!std::isfinite(x) || !std::isfinite(y)) continue;
      const double e = i < s.errors.size() && std::isfinite(s.errors[i]) ? s.errors[i] : 0.0;
      x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y - e), y1 = std::max(y1, y + e);
    }
  }
  if (!bars_.empty()) {
    x0 = -0.5, x1 = static_cast<double>(bars_.size()) - 0.5, y0 = std::min(0.0, y0), y1 = std::max(y1, 0.0);
    for (const auto& b : bars_) {
      const double e = std::isfinite(b.error) ? b.error : 0.0;
      y0 = std::min(y0, b.value - e), y1 = std::max(y1, b.value + e);
    }
  }
  if (!std::isfinite(x0)) x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  if (y_range_) std::tie(y0, y1) = *y_range_;
  if (x_range_) std::tie(x0, x1) = *x_range_;
  if (x1 - x0 < 1e-12) x0 -= 0.5, x1 += 0.5;
  if (y1 - y0 < 1e-12) y0 -= 0.5, y1 += 0.5;
  const double pad = 0.05 * (y1 - y0);
  y0 -= bars_.empty() ? pad : 0.0;
  y1 += pad;
  double sx = pw / (x1 - x0), sy = ph / (y1 - y0);
  if (equal_aspect_) {
    const double s = std::min(sx, sy);
    x1 = x0 + pw / s, y1 = y0 + ph / s, sx = sy = s;
  }
  return {left, top, pw, ph, x0, x1, y0, y1, sx, sy};
}

/// The SVG's opening tag, its white background and the title.
std::string SvgPlot::openingSvg() const {
  // The title from the left edge, smaller when it would not fit (about 0.6 em per character).
  const double title_chars = static_cast<double>(
      std::count_if(title_.begin(), title_.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
  const double title_size = std::clamp((width_ - 20.0) / (0.6 * std::max(1.0, title_chars)), 8.0, 13.0);
  return fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" viewBox=\"0 0 {} {}\" "
      "font-family=\"sans-serif\" font-size=\"11\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      "<text x=\"10\" y=\"18\" font-size=\"{:.1f}\" font-weight=\"bold\">{}</text>\n",
      width_, height_, width_, height_, title_size, escape(title_));
}

/// Axes, ticks and grid, the plot area's frame and the axis labels.
std::string SvgPlot::axesSvg(const Area& area) const {
  const double left = area.left, top = area.top, pw = area.pw, ph = area.ph;
  const auto X = [&area](double x) { return area.xPixel(x); };
  const auto Y = [&area](double y) { return area.yPixel(y); };
  std::string out;
  // Evenly spaced numbers, or the labelled ticks given (those within the range).
  const auto tickList = [](const Ticks& given, const std::vector<double>& even, double lo, double hi) {
    Ticks shown;
    if (given.empty()) {
      for (const double t : even) shown.emplace_back(t, number(t));
    }
    for (const auto& t : given) {
      if (t.first >= lo && t.first <= hi) shown.push_back(t);
    }
    return shown;
  };
  for (const auto& [t, label] : tickList(y_ticks_, ticks(area.y0, area.y1), area.y0, area.y1)) {
    out += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#e4e4e4\"/>"
                       "<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"end\">{}</text>\n",
                       left, Y(t), left + pw, Y(t), left - 6, Y(t) + 4, escape(label));
  }
  if (bars_.empty()) {
    for (const auto& [t, label] : tickList(x_ticks_, ticks(area.x0, area.x1, integer_x_), area.x0, area.x1)) {
      out += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#e4e4e4\"/>"
                         "<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{}</text>\n",
                         X(t), top, X(t), top + ph, X(t), top + ph + 16, escape(label));
    }
  }
  out += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#555\"/>\n", left, top, pw, ph);
  out += fmt::format("<text x=\"{:.1f}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n", left + pw / 2, height_ - 10,
                     escape(x_label_));
  out += fmt::format("<text transform=\"translate(16,{:.1f}) rotate(-90)\" text-anchor=\"middle\">{}</text>\n",
                     top + ph / 2, escape(y_label_));
  return out;
}

/// Bars, each with its category under it, its value over it and its error bar ("" without bars).
std::string SvgPlot::barsSvg(const Area& area) const {
  const double top = area.top, ph = area.ph, sx = area.sx;
  const auto X = [&area](double x) { return area.xPixel(x); };
  const auto Y = [&area](double y) { return area.yPixel(y); };
  std::string out;
  for (std::size_t i = 0; i < bars_.size(); ++i) {
    const double x = static_cast<double>(i);
    const double y_top = Y(std::max(bars_[i].value, 0.0)), y_base = Y(std::min(bars_[i].value, 0.0));
    out += fmt::format("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"{}\"/>"
                       "<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{}</text>"
                       "<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\" font-size=\"10\">{}</text>\n",
                       X(x - 0.3), y_top, 0.6 * sx, std::max(1.0, y_base - y_top), bars_[i].colour, X(x), top + ph + 16,
                       escape(bars_[i].label), X(x) + (std::isfinite(bars_[i].error) ? 0.17 * sx : 0.0), y_top - 4,
                       number(bars_[i].value));
    if (std::isfinite(bars_[i].error)) out += whisker(X(x), Y(bars_[i].value - bars_[i].error), Y(bars_[i].value + bars_[i].error));
  }
  return out;
}

/// The series: lines, error bars and markers, inside a clip path.
std::string SvgPlot::seriesSvg(const Area& area) const {
  const double left = area.left, top = area.top, pw = area.pw, ph = area.ph;
  const auto X = [&area](double x) { return area.xPixel(x); };
  const auto Y = [&area](double y) { return area.yPixel(y); };
  // Lines and markers, clipped to the plot area widened by a marker's radius (a marker on the
  // frame stays whole). The clip path's id is set by svg() from the figure's content: pages hold
  // many figures inline, and a shared id would clip every figure with the first one's rectangle.
  constexpr double kMarkerRoom = 3.0;
  std::string out = fmt::format("<clipPath id=\"{}\"><rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"/></clipPath>"
                                "<g clip-path=\"url(#{})\">\n",
                                kClipIdPlaceholder, left - kMarkerRoom, top - kMarkerRoom, pw + 2 * kMarkerRoom,
                                ph + 2 * kMarkerRoom, kClipIdPlaceholder);
  for (const auto& s : series_) {
    // One polyline per run of finite points: a non-finite point breaks the line (a pen lift).
    std::string points;
    const auto flush = [&] {
      if (!points.empty()) {
        out += fmt::format("<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"{}\"{} points=\"{}\"/>\n", s.colour,
                           s.width, s.dashed ? " stroke-dasharray=\"5,3\"" : "", points);
      }
      points.clear();
    };
    for (const auto& [x, y] : s.points) {
      if (std::isfinite(x) && std::isfinite(y)) {
        points += fmt::format("{:.1f},{:.1f} ", X(x), Y(y));
      } else {
        flush();
      }
    }
    flush();
    for (std::size_t i = 0; i < s.errors.size() && i < s.points.size(); ++i) {
      const auto [x, y] = s.points[i];
      if (std::isfinite(x) && std::isfinite(y) && std::isfinite(s.errors[i])) {
        out += whisker(X(x), Y(y - s.errors[i]), Y(y + s.errors[i]), s.colour);
      }
    }
    if (s.markers) {
      for (const auto& [x, y] : s.points) {
        if (std::isfinite(x) && std::isfinite(y)) {
          out += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"2.5\" fill=\"{}\"/>", X(x), Y(y), s.colour);
        }
      }
      out += "\n";
    }
  }
  out += "</g>\n";
  return out;
}

/// Legend, one entry per distinct label, right of the plot area.
std::string SvgPlot::legendSvg(const Area& area) const {
  const double left = area.left, top = area.top, pw = area.pw;
  std::string out;
  std::vector<std::string> seen;
  double ly = top + 8;
  for (const auto& s : series_) {
    if (s.label.empty() || std::find(seen.begin(), seen.end(), s.label) != seen.end()) continue;
    seen.push_back(s.label);
    out += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"{}\" stroke-width=\"3\"{}/>"
                       "<text x=\"{:.1f}\" y=\"{:.1f}\">{}</text>\n",
                       left + pw + 12, ly, left + pw + 32, ly, s.colour, s.dashed ? " stroke-dasharray=\"5,3\"" : "",
                       left + pw + 38, ly + 4, escape(s.label));
    ly += 16;
  }
  return out;
}

std::string SvgPlot::svg() const {
  const Area area = layout();
  std::string out = openingSvg();
  // Axes, ticks and grid.
  out += axesSvg(area);
  // Bars.
  out += barsSvg(area);
  // Lines and markers, in a clip path whose id is made from the figure itself (withClipId).
  out += seriesSvg(area);
  // Legend, one entry per distinct label.
  out += legendSvg(area);
  out += "</svg>\n";
  return withClipId(out);
}

}  // namespace hattr::report::detail
