// host_tools/report: the SVG chart writer (svg_plot.hpp). Text widths are estimated (0.6 em per
// character of sans-serif) to size margins, the legend and the label rotation.
#include "geojcbb_host/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <stdexcept>

namespace geojcbb::host::svg {

namespace {

constexpr double kTickFont = 11, kLabelFont = 12, kTitleFont = 13, kFigureTitleFont = 16;
constexpr double kValueFont = 10, kLegendFont = 11, kLegendRow = 18;
constexpr double kLineWidth = 1.6;

bool finite(double v) { return std::isfinite(v); }

// Pixel coordinates: two decimals at most, trailing zeros dropped.
std::string num(double v) {
  v = std::clamp(v, -1e6, 1e6);
  char b[32];
  std::snprintf(b, sizeof b, "%.2f", v);
  std::string s(b);
  while (s.back() == '0') s.pop_back();
  if (s.back() == '.') s.pop_back();
  return s == "-0" ? "0" : s;
}

std::string esc(const std::string& s) {
  std::string o;
  o.reserve(s.size());
  for (const char ch : s) {
    const auto u = static_cast<unsigned char>(ch);
    switch (ch) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      case '\'': o += "&apos;"; break;
      default:
        if (u >= 0x20 || ch == '\t' || ch == '\n' || ch == '\r') o += ch;  // XML 1.0 forbids the rest
    }
  }
  return o;
}

double text_w(const std::string& s, double size) {
  std::size_t n = 0;
  for (const char ch : s) n += (static_cast<unsigned char>(ch) & 0xC0) != 0x80;  // UTF-8 code points
  return 0.6 * size * static_cast<double>(n);
}

// `anchor` is start, middle or end; `rotate` in degrees about (x, y).
void text(std::string& o, double x, double y, const std::string& s, double size, const char* anchor, double rotate = 0,
          const char* extra = "") {
  o += "<text x=\"" + num(x) + "\" y=\"" + num(y) + "\" font-size=\"" + num(size) + "\" text-anchor=\"" + anchor + "\"";
  if (rotate != 0) o += " transform=\"rotate(" + num(rotate) + " " + num(x) + " " + num(y) + ")\"";
  o += extra;
  o += ">" + esc(s) + "</text>\n";
}

std::string svg_open(double w, double h) {
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"" + num(w) + "\" height=\"" + num(h) +
         "\" viewBox=\"0 0 " + num(w) + " " + num(h) + "\" font-family=\"sans-serif\">\n<rect width=\"" + num(w) +
         "\" height=\"" + num(h) + "\" fill=\"white\"/>\n";
}

struct Extent {
  double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool empty() const { return lo > hi; }
};

// An ordered range of positive width: a degenerate one is padded by 10 % of its value (or 1).
Range proper(double lo, double hi) {
  if (!finite(lo) || !finite(hi)) return {0, 1};
  if (hi < lo) std::swap(lo, hi);
  if (hi - lo <= 1e-12 * std::max(std::abs(lo), std::abs(hi))) {
    const double d = lo == 0 ? 1 : 0.1 * std::abs(lo);
    return {lo - d, hi + d};
  }
  return {lo, hi};
}

Range proper(const Extent& e) { return e.empty() ? Range{0, 1} : proper(e.lo, e.hi); }

// The smallest 1, 2 or 5 times a power of ten >= raw.
double nice_round(double raw) {
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double n = raw / mag;
  const double m = n <= 1 + 1e-9 ? 1 : n <= 2 + 1e-9 ? 2 : n <= 5 + 1e-9 ? 5 : 10;
  return m * mag;
}

// About target - 1 intervals: the 1, 2 or 5 times a power of ten nearest to span / (target - 1).
double nice_step(const Range& r, int target) {
  const double raw = (r.hi - r.lo) / std::max(target - 1, 1);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double n = raw / mag;
  return (n < std::sqrt(2.0) ? 1 : n < std::sqrt(10.0) ? 2 : n < std::sqrt(50.0) ? 5 : 10) * mag;
}

std::vector<double> covering_ticks(const Range& r, double step) {
  const double k0 = std::floor(r.lo / step + 1e-9), k1 = std::ceil(r.hi / step - 1e-9);
  std::vector<double> t;
  for (double k = k0; k <= k1; ++k) {
    const double v = k * step;
    t.push_back(std::abs(v) < 1e-9 * step ? 0.0 : v);
  }
  return t;
}

std::vector<double> inside(const std::vector<double>& ticks, const Range& r) {
  const double eps = 1e-9 * (r.hi - r.lo);
  std::vector<double> t;
  for (const double v : ticks)
    if (v >= r.lo - eps && v <= r.hi + eps) t.push_back(v);
  return t;
}

std::string tick_label(double v, double step) {
  const int d = std::clamp(static_cast<int>(std::ceil(-std::log10(step) - 1e-9)), 0, 10);
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", d, v);
  std::string s(b);
  if (s.find_first_not_of("-0.") == std::string::npos && s[0] == '-') s.erase(0, 1);
  return s;
}

double step_of(const std::vector<double>& t, const Range& r) { return t.size() >= 2 ? t[1] - t[0] : (r.hi - r.lo); }

int tick_target(double px, double per_tick) { return std::clamp(static_cast<int>(px / per_tick) + 1, 3, 8); }

Extent x_extent(const Panel& p) {
  Extent e;
  for (const Series& s : p.series)
    for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
      if (finite(s.x[i]) && finite(s.y[i])) e.add(s.x[i]);
  if (p.x_range) {
    e.add(p.x_range->lo);
    e.add(p.x_range->hi);
  }
  return e;
}

// Legend entries: distinct (label, style, colour), in order of first appearance.
struct Entry {
  std::string label, colour;
  Style style;
  bool bar;
};

double entry_w(const Entry& e) { return 28 + text_w(e.label, kLegendFont) + 18; }

std::vector<std::vector<const Entry*>> legend_rows(const std::vector<Entry>& es, double width) {
  std::vector<std::vector<const Entry*>> rows;
  double used = 0;
  for (const Entry& e : es) {
    if (rows.empty() || used + entry_w(e) > width) {
      rows.emplace_back();
      used = 0;
    }
    rows.back().push_back(&e);
    used += entry_w(e);
  }
  return rows;
}

double legend_h(const std::vector<Entry>& es, double width) {
  return es.empty() ? 0 : kLegendRow * static_cast<double>(legend_rows(es, width).size()) + 6;
}

void marker(std::string& o, Style st, double x, double y) {
  if (st == Style::kMarkersCross)
    o += "M" + num(x - 3.5) + "," + num(y - 3.5) + "l7,7m0,-7l-7,7";
  else
    o += "<circle cx=\"" + num(x) + "\" cy=\"" + num(y) + "\" r=\"" + (st == Style::kMarkersDot ? "2.2" : "3.5") +
         "\"/>";
}

std::string marker_group(Style st, const std::string& colour) {
  return st == Style::kMarkersDot ? "<g fill=\"" + esc(colour) + "\">"
                                  : "<g fill=\"none\" stroke=\"" + esc(colour) + "\" stroke-width=\"1.3\">";
}

// Markers and lines: crosses are one path per series, circles one element per point.
void markers(std::string& o, Style st, const std::string& colour, const std::vector<std::pair<double, double>>& pts) {
  if (pts.empty()) return;
  o += marker_group(st, colour);
  if (st == Style::kMarkersCross) o += "<path d=\"";
  for (const auto& [x, y] : pts) marker(o, st, x, y);
  if (st == Style::kMarkersCross) o += "\"/>";
  o += "</g>\n";
}

bool is_line(Style st) { return st == Style::kLine || st == Style::kDashed; }

std::string line_attrs(Style st, const std::string& colour) {
  std::string a = " stroke=\"" + esc(colour) + "\" stroke-width=\"" + num(kLineWidth) + "\"";
  if (st == Style::kDashed) a += " stroke-dasharray=\"6 4\"";
  return a;
}

void draw_legend(std::string& o, const std::vector<Entry>& es, double left, double top, double width) {
  double y = top + kLegendRow / 2 + 3;
  for (const auto& row : legend_rows(es, width)) {
    double w = 0;
    for (const Entry* e : row) w += entry_w(*e);
    double x = left + std::max(0.0, (width - w) / 2);
    for (const Entry* e : row) {
      if (e->bar) {
        o += "<rect x=\"" + num(x + 4) + "\" y=\"" + num(y - 5) + "\" width=\"16\" height=\"10\" fill=\"" +
             esc(e->colour) + "\"/>";
      } else if (is_line(e->style)) {
        o += "<line x1=\"" + num(x) + "\" y1=\"" + num(y) + "\" x2=\"" + num(x + 24) + "\" y2=\"" + num(y) + "\"" +
             line_attrs(e->style, e->colour) + "/>";
      } else {
        markers(o, e->style, e->colour, {{x + 12, y}});
      }
      text(o, x + 28, y + 4, e->label, kLegendFont, "start");
      x += entry_w(*e);
    }
    o += "\n";
    y += kLegendRow;
  }
}

struct Colours {
  std::map<std::string, std::string> by_label;
  std::size_t next = 0;
  std::string operator()(const Series& s) {
    if (!s.colour.empty()) return s.colour;
    if (s.label.empty()) return palette(next++);
    auto it = by_label.find(s.label);
    if (it == by_label.end()) it = by_label.emplace(s.label, palette(next++)).first;
    return it->second;
  }
};

void add_entry(std::vector<Entry>& es, const Series& s, const std::string& colour) {
  if (s.label.empty()) return;
  for (const Entry& e : es)
    if (e.label == s.label && e.style == s.style && e.colour == colour) return;
  es.push_back({s.label, colour, s.style, false});
}

void draw_series(std::string& o, const Series& s, const std::string& colour, const Transform& t) {
  const std::size_t n = std::min(s.x.size(), s.y.size());
  if (!is_line(s.style)) {
    std::vector<std::pair<double, double>> pts;
    for (std::size_t i = 0; i < n; ++i)
      if (finite(s.x[i]) && finite(s.y[i]) && s.x[i] >= t.x_lo && s.x[i] <= t.x_hi && s.y[i] >= t.y_lo &&
          s.y[i] <= t.y_hi)
        pts.emplace_back(t.px(s.x[i]), t.py(s.y[i]));
    markers(o, s.style, colour, pts);
    return;
  }
  std::vector<std::vector<std::size_t>> segs;  // runs of finite points
  std::size_t count = 0;
  bool in_run = false;
  for (std::size_t i = 0; i < n; ++i) {
    const bool ok = finite(s.x[i]) && finite(s.y[i]);
    if (ok && !in_run) segs.emplace_back();
    if (ok) {
      segs.back().push_back(i);
      ++count;
    }
    in_run = ok;
  }
  if (segs.empty()) return;
  const std::size_t k = (count + kMaxLinePoints - 1) / kMaxLinePoints;
  o += "<g fill=\"none\"" + line_attrs(s.style, colour) + " stroke-linejoin=\"round\">\n";
  for (const auto& seg : segs) {
    auto pt = [&](std::size_t i) { return num(t.px(s.x[i])) + "," + num(t.py(s.y[i])); };
    if (seg.size() == 1) {
      o += "<circle cx=\"" + num(t.px(s.x[seg[0]])) + "\" cy=\"" + num(t.py(s.y[seg[0]])) + "\" r=\"" +
           num(kLineWidth) + "\" fill=\"" + esc(colour) + "\" stroke=\"none\"/>\n";
      continue;
    }
    o += "<polyline points=\"";
    for (std::size_t j = 0; j < seg.size(); j += k) o += pt(seg[j]) + " ";
    if ((seg.size() - 1) % k != 0) o += pt(seg.back());
    if (o.back() == ' ') o.pop_back();
    o += "\"/>\n";
  }
  o += "</g>\n";
}

void grid_and_axes(std::string& o, const Transform& t, const std::vector<double>& xt, const std::vector<double>& yt,
                   bool x_labels, const Range& xr_step, const Range& yr_step) {
  const double r = t.left + t.width, b = t.top + t.height;
  std::string grid, ticks;
  for (const double v : xt) {
    const std::string x = num(t.px(v));
    grid += "M" + x + "," + num(t.top) + "V" + num(b);
    ticks += "M" + x + "," + num(b) + "v4";
  }
  for (const double v : yt) {
    const std::string y = num(t.py(v));
    grid += "M" + num(t.left) + "," + y + "H" + num(r);
    ticks += "M" + num(t.left) + "," + y + "h-4";
  }
  if (!grid.empty()) o += "<path d=\"" + grid + "\" stroke=\"#e6e6e6\" stroke-width=\"1\" fill=\"none\"/>\n";
  o += "<rect x=\"" + num(t.left) + "\" y=\"" + num(t.top) + "\" width=\"" + num(t.width) + "\" height=\"" +
       num(t.height) + "\" fill=\"none\" stroke=\"#444\" stroke-width=\"1\"/>\n";
  if (!ticks.empty()) o += "<path d=\"" + ticks + "\" stroke=\"#444\" stroke-width=\"1\" fill=\"none\"/>\n";
  const double xs = step_of(xt, xr_step), ys = step_of(yt, yr_step);
  if (x_labels)
    for (const double v : xt) text(o, t.px(v), b + 16, tick_label(v, xs), kTickFont, "middle");
  for (const double v : yt) text(o, t.left - 6, t.py(v) + 4, tick_label(v, ys), kTickFont, "end");
}

double max_label_w(const std::vector<double>& ticks, const Range& r) {
  double w = 0;
  const double s = step_of(ticks, r);
  for (const double v : ticks) w = std::max(w, text_w(tick_label(v, s), kTickFont));
  return w;
}

void draw_panel(std::string& o, const Panel& p, const std::vector<std::string>& cols, double cx, double cy, double w,
                double h, bool show_xlabel, const std::vector<Entry>* own_legend, int clip_id) {
  const double top = p.title.empty() ? 10 : 28;
  const double ylab = p.ylabel.empty() ? 0 : 20;
  const double lh = own_legend ? legend_h(*own_legend, w - 20) : 0;
  const double bottom = 24 + (p.xlabel.empty() ? 0 : 18) + 6 + lh, right = 16;
  auto layout = [&](double left) {
    return layout_panel(p, cx + left, cy + top, std::max(w - left - right, 10.0), std::max(h - top - bottom, 10.0));
  };
  PanelLayout l = layout(ylab + 48);
  l = layout(ylab + max_label_w(l.yticks, {l.t.y_lo, l.t.y_hi}) + 12);
  const Transform& t = l.t;
  if (!p.title.empty())
    text(o, t.left + t.width / 2, cy + 19, p.title, kTitleFont, "middle", 0, " font-weight=\"bold\"");
  grid_and_axes(o, t, l.xticks, l.yticks, true, {t.x_lo, t.x_hi}, {t.y_lo, t.y_hi});
  if (!p.xlabel.empty() && show_xlabel)
    text(o, t.left + t.width / 2, t.top + t.height + 36, p.xlabel, kLabelFont, "middle");
  if (!p.ylabel.empty()) text(o, cx + 14, t.top + t.height / 2, p.ylabel, kLabelFont, "middle", -90);
  const std::string id = "gjclip" + std::to_string(clip_id);
  o += "<defs><clipPath id=\"" + id + "\"><rect x=\"" + num(t.left) + "\" y=\"" + num(t.top) + "\" width=\"" +
       num(t.width) + "\" height=\"" + num(t.height) + "\"/></clipPath></defs>\n<g clip-path=\"url(#" + id + ")\">\n";
  for (std::size_t i = 0; i < p.series.size(); ++i) draw_series(o, p.series[i], cols[i], t);
  o += "</g>\n";
  if (own_legend) draw_legend(o, *own_legend, cx + 10, cy + h - lh, w - 20);
}

}  // namespace

const std::string& palette(std::size_t i) {
  static const std::vector<std::string> p = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                             "#E69F00", "#56B4E9", "#000000", "#F0E442"};
  return p[i % p.size()];
}

std::vector<double> nice_ticks(double lo, double hi, int target) {
  const Range r = proper(lo, hi);
  return covering_ticks(r, nice_step(r, target));
}

PanelLayout layout_panel(const Panel& p, double left, double top, double width, double height) {
  Extent ex, ey;
  for (const Series& s : p.series)
    for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
      if (finite(s.x[i]) && finite(s.y[i])) {
        ex.add(s.x[i]);
        ey.add(s.y[i]);
      }
  const int xt = tick_target(width, 80), yt = tick_target(height, 40);
  PanelLayout l;
  Range xr, yr;
  if (p.equal_aspect) {
    auto padded = [](const std::optional<Range>& fixed, const Extent& e) {
      if (fixed) return proper(fixed->lo, fixed->hi);
      const Range r = proper(e);
      const double d = 0.05 * (r.hi - r.lo);
      return Range{r.lo - d, r.hi + d};
    };
    xr = padded(p.x_range, ex);
    yr = padded(p.y_range, ey);
    const double s = std::max((xr.hi - xr.lo) / width, (yr.hi - yr.lo) / height);
    const double xc = (xr.lo + xr.hi) / 2, yc = (yr.lo + yr.hi) / 2;
    xr = {xc - s * width / 2, xc + s * width / 2};
    yr = {yc - s * height / 2, yc + s * height / 2};
    // One step on both axes, 70 px apart or closer (at least two ticks on either axis).
    const double step = nice_round(s * std::min(70.0, std::min(width, height) / 5));
    l.xticks = inside(covering_ticks(xr, step), xr);
    l.yticks = inside(covering_ticks(yr, step), yr);
  } else {
    auto axis = [](const std::optional<Range>& fixed, const Extent& e, int target, Range& r,
                   std::vector<double>& ticks) {
      if (fixed) {
        r = proper(fixed->lo, fixed->hi);
        ticks = inside(covering_ticks(r, nice_step(r, target)), r);
      } else {
        const Range d = proper(e);
        ticks = covering_ticks(d, nice_step(d, target));
        r = {ticks.front(), ticks.back()};
      }
    };
    axis(p.x_range, ex, xt, xr, l.xticks);
    axis(p.y_range, ey, yt, yr, l.yticks);
  }
  l.t = {xr.lo, xr.hi, yr.lo, yr.hi, left, top, width, height};
  return l;
}

Range clip_bar(double value, const Range& y) {
  const Range r = proper(y.lo, y.hi);
  const double base = std::clamp(0.0, r.lo, r.hi), v = std::clamp(value, r.lo, r.hi);
  return {std::min(base, v), std::max(base, v)};
}

std::string render(const Figure& f) {
  const int cols = std::max(f.cols, 1);
  const int n = static_cast<int>(f.panels.size());
  const int rows = (n + cols - 1) / cols;
  const double W = cols * f.panel_w;
  const double title_h = f.title.empty() ? 0 : 32;

  std::vector<Panel> panels = f.panels;
  if (f.share_x) {
    Extent e;
    for (const Panel& p : panels) {
      const Extent pe = x_extent(p);
      if (!pe.empty()) {
        e.add(pe.lo);
        e.add(pe.hi);
      }
    }
    const Range r = proper(e);
    const std::vector<double> t = covering_ticks(r, nice_step(r, tick_target(f.panel_w, 80)));
    for (Panel& p : panels) p.x_range = Range{t.front(), t.back()};
  }

  Colours colours;
  std::vector<std::vector<std::string>> cols_of(panels.size());
  std::vector<Entry> shared;
  std::vector<std::vector<Entry>> own(panels.size());
  for (std::size_t i = 0; i < panels.size(); ++i)
    for (const Series& s : panels[i].series) {
      cols_of[i].push_back(colours(s));
      add_entry(f.shared_legend ? shared : own[i], s, cols_of[i].back());
    }
  const double lh = legend_h(shared, W - 20);
  const double H = std::max(title_h + rows * f.panel_h + lh, 20.0);

  std::string o = svg_open(W, H);
  if (!f.title.empty()) text(o, W / 2, 22, f.title, kFigureTitleFont, "middle", 0, " font-weight=\"bold\"");
  for (int i = 0; i < n; ++i) {
    const int r = i / cols, c = i % cols;
    const bool below = i + cols < n;  // a panel below shows the shared x label
    draw_panel(o, panels[i], cols_of[i], c * f.panel_w, title_h + r * f.panel_h, f.panel_w, f.panel_h,
               !(f.share_x && below), f.shared_legend || own[i].empty() ? nullptr : &own[i], i);
  }
  if (!shared.empty()) draw_legend(o, shared, 10, title_h + rows * f.panel_h, W - 20);
  return o + "</svg>\n";
}

std::string render(const BarChart& c) {
  const std::size_t ncat = c.categories.size(), ng = c.values.size();
  const double W = c.width, H = c.height;
  Extent e;
  e.add(0);
  for (const auto& g : c.values)
    for (const double v : g)
      if (finite(v)) e.add(v);
  const int yt = tick_target(H - 100, 50);
  Range yr;
  std::vector<double> ticks;
  if (c.y_range) {
    yr = proper(c.y_range->lo, c.y_range->hi);
    ticks = inside(covering_ticks(yr, nice_step(yr, yt)), yr);
  } else {
    const Range d = proper(e);
    ticks = covering_ticks(d, nice_step(d, yt));
    yr = {ticks.front(), ticks.back()};
  }
  auto value_text = [&](double v) {
    char b[64];
    std::snprintf(b, sizeof b, "%.*f", std::clamp(c.value_decimals, 0, 10), v);
    return std::string(b);
  };

  const double left = (c.ylabel.empty() ? 0 : 20) + max_label_w(ticks, yr) + 12, right = 14;
  const double pw = std::max(W - left - right, 10.0);
  const double slot = pw / static_cast<double>(std::max<std::size_t>(ncat, 1));
  const double bw = 0.8 * slot / static_cast<double>(std::max<std::size_t>(ng, 1));
  double vw = 0, cw = 0;
  for (const auto& g : c.values)
    for (const double v : g)
      if (finite(v)) vw = std::max(vw, text_w(value_text(v), kValueFont));
  for (const std::string& s : c.categories) cw = std::max(cw, text_w(s, kTickFont));
  const bool rot_values = vw > bw + 2, rot_cats = cw > slot - 4;
  const double angle = 35, rad = angle * 3.14159265358979 / 180;

  std::vector<Entry> legend;
  for (std::size_t g = 0; g < ng; ++g) {
    const std::string label = g < c.groups.size() ? c.groups[g] : "";
    if (!label.empty()) legend.push_back({label, palette(g), Style::kLine, true});
  }
  const double lh = legend_h(legend, W - 20);
  const double top = (c.title.empty() ? 10 : 34) + (rot_values ? vw + 6 : 14);
  const double cat_h = rot_cats ? cw * std::sin(rad) + kTickFont * std::cos(rad) + 16 : 22;
  const double bottom = cat_h + 4 + lh;
  const Transform t{0, 1, yr.lo, yr.hi, left, top, pw, std::max(H - top - bottom, 10.0)};

  std::string o = svg_open(W, H);
  if (!c.title.empty()) text(o, W / 2, 22, c.title, kFigureTitleFont, "middle", 0, " font-weight=\"bold\"");
  grid_and_axes(o, t, {}, ticks, false, {0, 1}, yr);
  if (!c.ylabel.empty()) text(o, 14, t.top + t.height / 2, c.ylabel, kLabelFont, "middle", -90);
  if (yr.lo < 0 && yr.hi > 0)
    o += "<line x1=\"" + num(t.left) + "\" y1=\"" + num(t.py(0)) + "\" x2=\"" + num(t.left + t.width) + "\" y2=\"" +
         num(t.py(0)) + "\" stroke=\"#444\" stroke-width=\"1\"/>\n";
  const double b = t.top + t.height;
  for (std::size_t k = 0; k < ncat; ++k) {
    const double sx = t.left + slot * static_cast<double>(k);
    const double cx = sx + slot / 2;
    if (rot_cats)
      text(o, cx, b + 14, c.categories[k], kTickFont, "end", -angle);
    else
      text(o, cx, b + 16, c.categories[k], kTickFont, "middle");
    for (std::size_t g = 0; g < ng; ++g) {
      if (k >= c.values[g].size() || !finite(c.values[g][k])) continue;
      const double v = c.values[g][k];
      const Range bar = clip_bar(v, yr);
      const double x = sx + 0.1 * slot + bw * static_cast<double>(g), xm = x + bw / 2;
      o += "<rect class=\"bar\" x=\"" + num(x) + "\" y=\"" + num(t.py(bar.hi)) + "\" width=\"" + num(bw) +
           "\" height=\"" + num(t.py(bar.lo) - t.py(bar.hi)) + "\" fill=\"" + palette(g) + "\"/>\n";
      const bool down = v < std::clamp(0.0, yr.lo, yr.hi) && bar.lo > yr.lo;  // label below a negative bar
      const double y = down ? t.py(bar.lo) + 3 : t.py(bar.hi) - 3;
      if (rot_values)
        text(o, xm + 0.35 * kValueFont, y, value_text(v), kValueFont, down ? "end" : "start", -90);
      else
        text(o, xm, down ? y + kValueFont : y, value_text(v), kValueFont, "middle");
    }
  }
  if (!legend.empty()) draw_legend(o, legend, 10, H - lh, W - 20);
  return o + "</svg>\n";
}

namespace {
void write_file(const std::string& svg, const std::string& path) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error("svg: cannot open " + path + " for writing");
  out << svg;
  out.close();
  if (!out) throw std::runtime_error("svg: cannot write " + path);
}
}  // namespace

void write(const Figure& f, const std::string& path) { write_file(render(f), path); }
void write(const BarChart& c, const std::string& path) { write_file(render(c), path); }

}  // namespace geojcbb::host::svg
