#pragma once
// A small SVG plot for the study report: axes with ticks, labels with units, a legend, lines,
// points and bars. Self-contained SVG text, no scripts, no network.

#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace hattr::report::detail {

struct Series {
  std::string label;
  std::string colour;  ///< CSS colour
  std::vector<std::pair<double, double>> points;
  double width = 1.5;
  bool dashed = false;
  bool markers = false;
  /// Half-widths of error bars at each point (empty: none; NaN: none at that point).
  std::vector<double> errors;
};

struct Bar {
  std::string label;   ///< category under the bar
  std::string colour;
  double value;
  double error = std::numeric_limits<double>::quiet_NaN();  ///< error bar's half-width (NaN: none)
};

class SvgPlot {
 public:
  SvgPlot(std::string title, std::string x_label, std::string y_label, int width = 560, int height = 340);
  void add(Series series) { series_.push_back(std::move(series)); }
  /// Same scale on both axes (for trajectories drawn on the paper).
  void equalAspect() { equal_aspect_ = true; }
  /// x takes integer values only (trial numbers): ticks at integers.
  void integerX() { integer_x_ = true; }
  /// A fixed y range (a probability from 0 to 1) instead of the data's.
  void yRange(double lo, double hi) { y_range_ = {lo, hi}; }
  /// A fixed x range instead of the data's.
  void xRange(double lo, double hi) { x_range_ = {lo, hi}; }
  /// Ticks at these values with these labels instead of evenly spaced numbers (a DET curve's
  /// probabilities on a normal-deviate axis).
  using Ticks = std::vector<std::pair<double, std::string>>;
  void labelledTicks(Ticks x, Ticks y) {
    x_ticks_ = std::move(x);
    y_ticks_ = std::move(y);
  }
  /// Bars instead of lines (categories along x).
  void bars(std::vector<Bar> bars) { bars_ = std::move(bars); }
  [[nodiscard]] std::string svg() const;

 private:
  /// The plot area in pixels and the data range it shows (svg_plot.cpp).
  struct Area;
  [[nodiscard]] Area layout() const;
  [[nodiscard]] std::string openingSvg() const;
  [[nodiscard]] std::string axesSvg(const Area& area) const;
  [[nodiscard]] std::string barsSvg(const Area& area) const;
  [[nodiscard]] std::string seriesSvg(const Area& area) const;
  [[nodiscard]] std::string legendSvg(const Area& area) const;

  std::string title_, x_label_, y_label_;
  int width_, height_;
  bool equal_aspect_ = false;
  bool integer_x_ = false;
  std::optional<std::pair<double, double>> y_range_;
  std::optional<std::pair<double, double>> x_range_;
  Ticks x_ticks_, y_ticks_;
  std::vector<Series> series_;
  std::vector<Bar> bars_;
};

/// Escapes text for XML/HTML.
std::string escape(const std::string& text);

}  // namespace hattr::report::detail
