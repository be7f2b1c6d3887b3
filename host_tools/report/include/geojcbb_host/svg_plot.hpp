// host_tools/report: a small, dependency-free SVG 1.1 chart writer for the
// evaluation's figures.
//   Figure    a grid of x-y panels (paths, landmarks, errors over time),
//   optionally with equal aspect
//             ratio, with a shared legend below the grid (or one per panel).
//   BarChart  one value per category, optionally grouped, with value labels and
//   a settable y range
//             (bars are clipped to it; the labels keep the true values).
// Non-finite points are skipped (a line breaks into segments at a gap), long
// lines are decimated to at most kMaxLinePoints points, all text is
// XML-escaped. Series without a colour take one from the Okabe-Ito palette, one
// per distinct label across the figure, so a strategy keeps its colour in every
// panel. Host only: allocates freely.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace geojcbb::host::svg {

inline constexpr std::size_t kMaxLinePoints = 2000;

enum class Style { kLine, kDashed, kMarkersCross, kMarkersCircle, kMarkersDot };

struct Series {
  std::string label;  ///< legend text; empty: not in the legend
  std::vector<double> x, y;
  Style style = Style::kLine;
  std::string colour;  ///< any SVG colour; empty: from the palette
};

struct Range {
  double lo, hi;
};

struct Panel {
  std::string title, xlabel, ylabel;
  std::vector<Series> series;
  bool equal_aspect = false;  ///< same data units per pixel on x and y
  std::optional<Range> x_range,
      y_range;  ///< fixed ranges; otherwise from the data
};

struct Figure {
  std::string title;
  int cols = 1;
  std::vector<Panel> panels;
  double panel_w = 420,
         panel_h = 320;       ///< one grid cell [px], titles and axis labels included
  bool shared_legend = true;  ///< one legend below the grid; otherwise one per panel
  bool share_x = false;       ///< all panels take the union of their x ranges
};

struct BarChart {
  std::string title, ylabel;
  std::vector<std::string> categories;      ///< along the x axis
  std::vector<std::string> groups;          ///< one bar per group in each category (the legend)
  std::vector<std::vector<double>> values;  ///< values[group][category]; NaN: no bar
  std::optional<Range> y_range;             ///< e.g. {0.9, 1.0} for F1; otherwise from 0 and the data
  int value_decimals = 3;
  double width = 640, height = 360;
};

/// The i-th palette colour (Okabe-Ito, yellow last), cycling.
const std::string& palette(std::size_t i);

/// Ticks at a step of 1, 2 or 5 times a power of ten, about `target` of them,
/// the first <= lo and the last >= hi. A degenerate or inverted range is padded
/// first.
std::vector<double> nice_ticks(double lo, double hi, int target = 6);

/// Data -> pixel transform of a panel's plot area (SVG y grows downwards).
struct Transform {
  double x_lo, x_hi, y_lo, y_hi;    ///< data range shown
  double left, top, width, height;  ///< plot area [px]
  double px(double x) const { return left + (x - x_lo) / (x_hi - x_lo) * width; }
  double py(double y) const { return top + (y_hi - y) / (y_hi - y_lo) * height; }
  double x_per_px() const { return (x_hi - x_lo) / width; }
  double y_per_px() const { return (y_hi - y_lo) / height; }
};

struct PanelLayout {
  Transform t;
  std::vector<double> xticks, yticks;  ///< inside the shown range
};

/// The ranges, ticks and transform of `p` drawn in the plot area (left, top,
/// width, height). Without a fixed range an axis spans its ticks; with
/// equal_aspect the data (padded 5 %) is centred and the tighter axis widened
/// so x_per_px == y_per_px.
PanelLayout layout_panel(const Panel& p, double left, double top, double width, double height);

/// The part of a bar from 0 to `value` inside [y.lo, y.hi], as {bottom, top} in
/// data units (equal when the bar lies wholly outside).
Range clip_bar(double value, const Range& y);

std::string render(const Figure& f);
std::string render(const BarChart& c);
/// Throws std::runtime_error when the file cannot be written.
void write(const Figure& f, const std::string& path);
void write(const BarChart& c, const std::string& path);

}  // namespace geojcbb::host::svg
