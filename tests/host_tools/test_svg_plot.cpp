// The SVG chart writer: standalone, tag-balanced documents with escaped text; NaN gaps break lines;
// long lines are decimated; equal-aspect panels; nice ticks; bars clipped to the y range; write()
// reports an unwritable path.
//
// GCC 12 at -O1 with the sanitizers reports -Wmaybe-uninitialized inside libstdc++'s <regex>
// (std::function members of the regex automaton, in the library, not in our code; host-release at -O3
// does not report it).
// It is not our code and it is reported where the templates are emitted, at the end of this file,
// so the exemption covers the whole file, and only this file.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <regex>
#include <sstream>
#include <stdexcept>

#include "geojcbb_host/svg_plot.hpp"

using namespace geojcbb::host::svg;

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r\n"), b = s.find_last_not_of(" \t\r\n");
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

// Every element opened is closed, in order; comments and declarations are skipped.
bool tags_balanced(const std::string& s) {
  std::vector<std::string> open;
  for (std::size_t i = s.find('<'); i != std::string::npos; i = s.find('<', i + 1)) {
    const std::size_t end = s.find('>', i);
    if (end == std::string::npos) return false;
    const std::string tag = s.substr(i + 1, end - i - 1);
    if (tag.empty() || tag[0] == '?' || tag[0] == '!') continue;
    if (tag[0] == '/') {
      if (open.empty() || open.back() != tag.substr(1)) return false;
      open.pop_back();
    } else if (tag.back() != '/') {
      open.push_back(tag.substr(0, tag.find_first_of(" \t\r\n")));
    }
  }
  return open.empty();
}

std::size_t count(const std::string& s, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t i = s.find(what); i != std::string::npos; i = s.find(what, i + 1)) ++n;
  return n;
}

Series line(const std::string& label, std::vector<double> x, std::vector<double> y, Style st = Style::kLine) {
  return {label, std::move(x), std::move(y), st, ""};
}

Figure one_panel(Series s) {
  Figure f;
  f.panels.push_back({"", "x [m]", "y [m]", {std::move(s)}, false, std::nullopt, std::nullopt});
  return f;
}

BarChart bars() {
  BarChart c;
  c.title = "F1";
  c.ylabel = "F1";
  c.categories = {"JCBB", "GeoJCBB"};
  c.groups = {"env1", "env2"};
  c.values = {{0.95, 1.2}, {0.5, kNaN}};
  c.y_range = Range{0.9, 1.0};
  return c;
}

}  // namespace

TEST_CASE("SVG output is a standalone, tag-balanced document") {
  Figure f;
  f.title = "path fitting";
  f.cols = 2;
  for (int k = 0; k < 3; ++k) {
    Panel p;
    p.title = "strategy " + std::to_string(k);
    p.equal_aspect = true;
    p.series = {line("true path", {0, 10, 10, 0}, {0, 0, 5, 5}),
                line("estimate", {0, 10, 9}, {0, 1, 5}, Style::kDashed),
                line("true landmarks", {2, 8}, {1, 4}, Style::kMarkersCross),
                line("estimated landmarks", {2.1, 8.2}, {1.1, 3.9}, Style::kMarkersCircle),
                line("spurious", {5}, {2}, Style::kMarkersDot),
                line("empty", {}, {})};
    f.panels.push_back(p);
  }
  for (const bool shared : {true, false}) {
    f.shared_legend = shared;
    const std::string s = trim(render(f));
    CHECK(s.rfind("<svg", 0) == 0);
    CHECK(s.size() >= 6);
    CHECK(s.substr(s.size() - 6) == "</svg>");
    CHECK(s.find("xmlns=\"http://www.w3.org/2000/svg\"") != std::string::npos);
    CHECK(tags_balanced(s));
  }
  const std::string b = trim(render(bars()));
  CHECK(b.rfind("<svg", 0) == 0);
  CHECK(b.substr(b.size() - 6) == "</svg>");
  CHECK(tags_balanced(b));
  CHECK(tags_balanced(render(Figure{})));
  CHECK(tags_balanced(render(BarChart{})));
  CHECK_FALSE(tags_balanced("<svg><g></svg>"));
}

TEST_CASE("SVG text is XML-escaped") {
  const std::string nasty = "a<b & c \"q\" 'p'";
  Figure f = one_panel(line(nasty, {0, 1}, {0, 1}));
  f.title = nasty;
  f.panels[0].title = nasty;
  f.panels[0].xlabel = nasty;
  f.panels[0].series[0].colour = "red\"/><script>";
  const std::string s = render(f);
  CHECK(s.find("a&lt;b &amp; c &quot;q&quot; &apos;p&apos;") != std::string::npos);
  CHECK(s.find("a<b") == std::string::npos);
  CHECK(s.find("<script") == std::string::npos);
  CHECK(tags_balanced(s));
  BarChart c = bars();
  c.categories[0] = nasty;
  c.title = nasty;
  const std::string b = render(c);
  CHECK(b.find("a<b") == std::string::npos);
  CHECK(tags_balanced(b));
}

TEST_CASE("SVG non-finite points are skipped and break a line") {
  const double inf = std::numeric_limits<double>::infinity();
  const std::string s = render(one_panel(line("err", {0, 1, 2, 3, 4, 5, 6}, {0, 1, kNaN, 3, 4, 5, 6})));
  CHECK(count(s, "<polyline") == 2);
  CHECK(s.find("nan") == std::string::npos);
  CHECK(count(render(one_panel(line("err", {0, 1, inf, 3, 4}, {0, 1, 2, 3, 4}))), "<polyline") == 2);
  CHECK(count(render(one_panel(line("err", {0, 1, 2}, {kNaN, kNaN, kNaN}))), "<polyline") == 0);
  // A lone finite point between gaps is still drawn (as a dot), not as an invisible polyline.
  const std::string lone = render(one_panel(line("err", {0, 1, 2, 3, 4}, {0, 1, kNaN, 3, kNaN})));
  CHECK(count(lone, "<polyline") == 1);
  CHECK(tags_balanced(lone));
}

TEST_CASE("SVG long lines are decimated, keeping the last point") {
  std::vector<double> x, y;
  for (int i = 0; i < 10000; ++i) {
    x.push_back(0.01 * i);
    y.push_back(std::sin(0.001 * i));
  }
  y.back() = 1000;  // a last point far above the others: it must survive the decimation
  const std::string s = render(one_panel(line("long", x, y)));
  CHECK(count(s, "<polyline") == 1);
  const auto a = s.find("<polyline points=\""), b = s.find('"', a + 18);
  std::vector<double> py;
  std::istringstream in(s.substr(a + 18, b - a - 18));
  for (std::string p; in >> p;) py.push_back(std::stod(p.substr(p.find(',') + 1)));
  CHECK(py.size() <= kMaxLinePoints + 1);
  CHECK(py.size() >= kMaxLinePoints / 2);
  CHECK(py.back() < *std::min_element(py.begin(), py.end() - 1) - 100);
  CHECK(s.size() < 80000);
}

TEST_CASE("SVG equal-aspect panel has the same units per pixel on x and y") {
  Panel p;
  p.equal_aspect = true;
  p.series = {line("path", {-20, 180}, {3, 40})};
  for (const auto& [w, h] : {std::pair{400.0, 300.0}, std::pair{200.0, 500.0}, std::pair{333.0, 333.0}}) {
    const PanelLayout l = layout_panel(p, 50, 30, w, h);
    CHECK(l.t.x_per_px() == doctest::Approx(l.t.y_per_px()));
    CHECK(l.t.px(l.t.x_lo) == doctest::Approx(50));
    CHECK(l.t.px(l.t.x_hi) == doctest::Approx(50 + w));
    CHECK(l.t.py(l.t.y_hi) == doctest::Approx(30));
    CHECK(l.t.py(l.t.y_lo) == doctest::Approx(30 + h));
    CHECK(l.t.x_lo <= -20);  // the data stays inside
    CHECK(l.t.x_hi >= 180);
    CHECK(l.t.y_lo <= 3);
    CHECK(l.t.y_hi >= 40);
    REQUIRE(l.xticks.size() >= 2);
    REQUIRE(l.yticks.size() >= 2);
    CHECK(l.xticks[1] - l.xticks[0] == doctest::Approx(l.yticks[1] - l.yticks[0]));
  }
  p.equal_aspect = false;
  const PanelLayout l = layout_panel(p, 0, 0, 400, 300);
  CHECK(l.t.x_per_px() != doctest::Approx(l.t.y_per_px()));
}

TEST_CASE("SVG nice ticks cover the range with a 1, 2 or 5 step") {
  const std::vector<double> t = nice_ticks(0, 97);
  REQUIRE(t.size() == 6);
  for (int i = 0; i < 6; ++i) CHECK(t[i] == doctest::Approx(20.0 * i));
  for (const auto& range : std::vector<std::pair<double, double>>{{0, 97},
                                                                  {0, 1},
                                                                  {-3.2, 7.9},
                                                                  {0.9, 1.0},
                                                                  {1e-4, 3e-4},
                                                                  {-250, -3},
                                                                  {1234, 98765},
                                                                  {0.001, 0.0237},
                                                                  {5, 5},
                                                                  {0, 0}}) {
    const double lo = range.first;  // named, not bound: CAPTURE's lambda needs a variable
    const double hi = range.second;
    CAPTURE(lo);
    CAPTURE(hi);
    const std::vector<double> k = nice_ticks(lo, hi);
    REQUIRE(k.size() >= 3);
    CHECK(k.size() <= 10);
    const double step = k[1] - k[0];
    const double tol = 1e-9 * step;
    CHECK(k.front() <= lo + tol);
    CHECK(k.back() >= hi - tol);
    if (lo == hi) CHECK(k.front() < lo);
    const double m = step / std::pow(10.0, std::floor(std::log10(step) + 1e-9));
    CHECK((m == doctest::Approx(1) || m == doctest::Approx(2) || m == doctest::Approx(5)));
    for (std::size_t i = 1; i < k.size(); ++i) CHECK(k[i] - k[i - 1] == doctest::Approx(step));
  }
}

TEST_CASE("SVG an all-equal data range gives a padded axis") {
  Panel p;
  p.series = {line("flat", {0, 1, 2}, {2.5, 2.5, 2.5}), line("", {}, {})};
  const PanelLayout l = layout_panel(p, 0, 0, 400, 300);
  CHECK(l.t.y_lo < 2.5);
  CHECK(l.t.y_hi > 2.5);
  CHECK(l.yticks.size() >= 3);
  Panel empty;
  const PanelLayout e = layout_panel(empty, 0, 0, 400, 300);
  CHECK(e.t.x_lo < e.t.x_hi);
  CHECK(e.t.y_lo < e.t.y_hi);
  p.equal_aspect = true;
  p.series = {line("point", {7}, {7}, Style::kMarkersDot)};
  const PanelLayout q = layout_panel(p, 0, 0, 400, 300);
  CHECK(q.t.x_lo < 7);
  CHECK(q.t.x_hi > 7);
  CHECK(q.t.x_per_px() == doctest::Approx(q.t.y_per_px()));
}

TEST_CASE("SVG bars are clipped to the y range") {
  const Range r{0.9, 1.0};
  CHECK(clip_bar(0.95, r).lo == doctest::Approx(0.9));
  CHECK(clip_bar(0.95, r).hi == doctest::Approx(0.95));
  CHECK(clip_bar(1.2, r).hi == doctest::Approx(1.0));
  CHECK(clip_bar(0.5, r).lo == doctest::Approx(clip_bar(0.5, r).hi));
  CHECK(clip_bar(-2, Range{-1, 3}).lo == doctest::Approx(-1));
  CHECK(clip_bar(-2, Range{-1, 3}).hi == doctest::Approx(0));

  const std::string s = render(bars());
  std::vector<double> h;
  const std::regex re("class=\"bar\"[^>]*height=\"([-0-9.]+)\"");
  for (auto it = std::sregex_iterator(s.begin(), s.end(), re); it != std::sregex_iterator(); ++it)
    h.push_back(std::stod((*it)[1]));
  REQUIRE(h.size() == 3);  // by category, then group: 0.95, 0.5, 1.2 (the NaN value has no bar)
  CHECK(h[0] == doctest::Approx(h[2] / 2).epsilon(0.02));  // 0.95 is half of the clipped 1.2
  CHECK(h[2] > 100);
  CHECK(h[1] == doctest::Approx(0));              // 0.5 lies below the range
  CHECK(s.find(">1.200<") != std::string::npos);  // the labels keep the true values
  CHECK(s.find(">0.500<") != std::string::npos);
}

TEST_CASE("SVG write() saves the document and throws on an unwritable path") {
  const Figure f = one_panel(line("a", {0, 1}, {0, 1}));
  const auto path = std::filesystem::temp_directory_path() / "geojcbb_test_svg_plot.svg";
  write(f, path.string());
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  CHECK(ss.str() == render(f));
  std::filesystem::remove(path);
  CHECK_THROWS_AS(write(f, "/nonexistent_geojcbb_dir/x.svg"), std::runtime_error);
  CHECK_THROWS_AS(write(bars(), "/nonexistent_geojcbb_dir/x.svg"), std::runtime_error);
}
