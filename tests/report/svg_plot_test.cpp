// SVG plot writer: well-formed output, the data-to-pixel mapping, 1-2-5 ticks, gaps at
// non-finite samples, min/max-preserving decimation, equal axes, escaped legend names.
#include "tools/report/svg_plot.h"

#include <gtest/gtest.h>
#include <tinyxml2.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <string_view>

#include "tools/report/decimate.h"

namespace kuavo::report {
namespace {

using tinyxml2::XMLDocument;
using tinyxml2::XMLElement;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
// Coordinates are written with 2 decimals.
constexpr double kPixelTolerance = 0.006;

// ---- a strict, tiny XML checker ----------------------------------------------------------
// tinyxml2 is lenient about a raw '<' in an attribute or a bare '&'; this is not. It checks that
// tags balance, there is one root, and every '&' starts a predefined or numeric entity.
bool entities_ok(std::string_view s) {
  for (std::size_t i = s.find('&'); i != std::string_view::npos; i = s.find('&', i + 1)) {
    const std::string_view rest = s.substr(i);
    const bool known = rest.starts_with("&amp;") || rest.starts_with("&lt;") || rest.starts_with("&gt;") ||
                       rest.starts_with("&quot;") || rest.starts_with("&apos;") || rest.starts_with("&#");
    if (!known) return false;
  }
  return true;
}

std::string xml_problem(const std::string& xml) {
  std::vector<std::string> open;
  int roots = 0;
  std::size_t i = 0;
  auto is_name = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == ':' || c == '_' || c == '.';
  };
  while (i < xml.size()) {
    const std::size_t lt = xml.find('<', i);
    const std::string_view text(xml.data() + i, (lt == std::string::npos ? xml.size() : lt) - i);
    if (!entities_ok(text)) return "bad '&' in text near offset " + std::to_string(i);
    if (open.empty() && text.find_first_not_of(" \t\r\n") != std::string_view::npos) return "text outside the root";
    if (lt == std::string::npos) break;
    if (xml.compare(lt, 2, "<?") == 0) {
      const std::size_t end = xml.find("?>", lt);
      if (end == std::string::npos) return "unterminated <?";
      i = end + 2;
      continue;
    }
    if (xml.compare(lt, 2, "</") == 0) {
      const std::size_t end = xml.find('>', lt);
      if (end == std::string::npos) return "unterminated end tag";
      const std::string name = xml.substr(lt + 2, end - lt - 2);
      if (open.empty() || open.back() != name) return "end tag </" + name + "> does not match";
      open.pop_back();
      i = end + 1;
      continue;
    }
    std::size_t p = lt + 1;
    while (p < xml.size() && is_name(xml[p])) ++p;
    const std::string name = xml.substr(lt + 1, p - lt - 1);
    if (name.empty()) return "'<' not starting a tag at offset " + std::to_string(lt);
    for (;;) {
      while (p < xml.size() && std::isspace(static_cast<unsigned char>(xml[p]))) ++p;
      if (p >= xml.size()) return "unterminated tag <" + name;
      if (xml.compare(p, 2, "/>") == 0) {
        p += 2;
        if (open.empty()) ++roots;
        break;
      }
      if (xml[p] == '>') {
        ++p;
        if (open.empty()) ++roots;
        open.push_back(name);
        break;
      }
      const std::size_t attr = p;
      while (p < xml.size() && is_name(xml[p])) ++p;
      if (p == attr || xml.compare(p, 2, "=\"") != 0) return "bad attribute in <" + name + ">";
      const std::size_t close = xml.find('"', p + 2);
      if (close == std::string::npos) return "unterminated attribute";
      const std::string_view value(xml.data() + p + 2, close - p - 2);
      if (value.find('<') != std::string_view::npos || !entities_ok(value))
        return "unescaped attribute value in <" + name + ">";
      p = close + 1;
    }
    i = p;
  }
  if (!open.empty()) return "unclosed <" + open.back() + ">";
  if (roots != 1) return "expected one root element, found " + std::to_string(roots);
  return "";
}

TEST(report_xml_checker, RejectsWhatItShould) {
  EXPECT_EQ(xml_problem("<a><b/></a>"), "");
  EXPECT_NE(xml_problem("<a><b></a>"), "");
  EXPECT_NE(xml_problem("<a x=\"1<2\"/>"), "");
  EXPECT_NE(xml_problem("<a>x & y</a>"), "");
  EXPECT_NE(xml_problem("<a/><b/>"), "");
  EXPECT_EQ(xml_problem("<?xml version=\"1.0\"?>\n<a>x &amp; y &lt; z</a>\n"), "");
}

// ---- reading the SVG back ----------------------------------------------------------------

struct Svg {
  XMLDocument doc;
  explicit Svg(const std::string& text) {
    const std::string problem = xml_problem(text);
    EXPECT_EQ(problem, "") << text.substr(0, 2000);
    EXPECT_EQ(doc.Parse(text.c_str(), text.size()), tinyxml2::XML_SUCCESS) << doc.ErrorStr();
  }
  const XMLElement* root() const { return doc.RootElement(); }
};

bool has_class(const XMLElement* e, std::string_view cls) {
  const char* c = e->Attribute("class");
  return c != nullptr && cls == c;
}

void collect(const XMLElement* e, std::string_view tag, std::string_view cls, std::vector<const XMLElement*>& out) {
  for (const XMLElement* c = e->FirstChildElement(); c != nullptr; c = c->NextSiblingElement()) {
    if (tag == c->Name() && (cls.empty() || has_class(c, cls))) out.push_back(c);
    collect(c, tag, cls, out);
  }
}
std::vector<const XMLElement*> find_all(const XMLElement* e, std::string_view tag, std::string_view cls = {}) {
  std::vector<const XMLElement*> out;
  if (e != nullptr) collect(e, tag, cls, out);
  return out;
}

struct Point {
  double x, y;
};
std::vector<Point> points_of(const XMLElement* e) {
  std::vector<Point> pts;
  std::istringstream in(e->Attribute("points"));
  std::string token;
  while (in >> token) {
    const std::size_t comma = token.find(',');
    EXPECT_NE(comma, std::string::npos) << token;
    pts.push_back(
        {std::strtod(token.substr(0, comma).c_str(), nullptr), std::strtod(token.substr(comma + 1).c_str(), nullptr)});
  }
  return pts;
}

// The mapping as the SVG states it: the plot-area rectangle shows [x0, x1] x [y0, y1], y up.
// The expected pixel positions below are computed from this, not by the library.
struct Mapping {
  double left, top, width, height, x0, x1, y0, y1;
  double px(double x) const { return left + (x - x0) / (x1 - x0) * width; }
  double py(double y) const { return top + height - (y - y0) / (y1 - y0) * height; }
};
Mapping mapping_of(const XMLElement* plot) {
  Mapping m{};
  const auto areas = find_all(plot, "rect", "plot-area");
  EXPECT_EQ(areas.size(), 1u);
  if (areas.empty()) return m;
  m.left = areas[0]->DoubleAttribute("x");
  m.top = areas[0]->DoubleAttribute("y");
  m.width = areas[0]->DoubleAttribute("width");
  m.height = areas[0]->DoubleAttribute("height");
  std::istringstream(plot->Attribute("data-x-range")) >> m.x0 >> m.x1;
  std::istringstream(plot->Attribute("data-y-range")) >> m.y0 >> m.y1;
  return m;
}

const XMLElement* only_plot(const Svg& svg) {
  const auto plots = find_all(svg.root(), "g", "plot");
  EXPECT_EQ(plots.size(), 1u);
  return plots.empty() ? nullptr : plots[0];
}

std::vector<double> label_values(const XMLElement* plot, std::string_view cls) {
  std::vector<double> v;
  for (const XMLElement* e : find_all(plot, "text", cls)) v.push_back(std::strtod(e->GetText(), nullptr));
  return v;
}

Series line(std::string name, std::vector<double> x, std::vector<double> y) {
  Series s;
  s.name = std::move(name);
  s.x = std::move(x);
  s.y = std::move(y);
  return s;
}

// ---- tests -------------------------------------------------------------------------------

TEST(report_svg_plot, TypicalPlotAndStackAreWellFormed) {
  Plot p;
  p.title = "Joint <q3> tracking & \"error\"";
  p.x_label = "t [s]";
  p.y_label = "q [rad]";
  p.series = {line("ref", {0, 1, 2, 3}, {0, 0.5, 0.2, 0.9}), line("meas", {0, 1, 2, 3}, {0.1, 0.4, 0.3, 0.8})};
  p.series[1].dashed = true;
  p.polygons.push_back({"support", {0, 3, 3, 0}, {0, 0, 1, 1}, ""});
  const std::string one = render_svg(p);
  Svg svg(one);
  ASSERT_NE(svg.root(), nullptr);
  EXPECT_STREQ(svg.root()->Name(), "svg");
  EXPECT_STREQ(svg.root()->Attribute("xmlns"), "http://www.w3.org/2000/svg");
  EXPECT_EQ(svg.root()->IntAttribute("width"), 900);
  EXPECT_EQ(svg.root()->IntAttribute("height"), 360);
  EXPECT_EQ(find_all(svg.root(), "text", "title").size(), 1u);
  EXPECT_STREQ(find_all(svg.root(), "text", "title")[0]->GetText(), p.title.c_str());
  EXPECT_EQ(find_all(svg.root(), "text", "x-label").size(), 1u);
  EXPECT_EQ(find_all(svg.root(), "text", "y-label").size(), 1u);
  EXPECT_EQ(find_all(svg.root(), "polygon", "polygon").size(), 1u);

  Plot small = p;
  small.height_px = 200;
  small.width_px = 600;
  Plot tall = p;
  tall.height_px = 300;
  Svg stack(render_svg_stack({p, small, tall}));
  ASSERT_NE(stack.root(), nullptr);
  EXPECT_EQ(stack.root()->IntAttribute("width"), 900);
  EXPECT_EQ(stack.root()->IntAttribute("height"), 860);
  const auto plots = find_all(stack.root(), "g", "plot");
  ASSERT_EQ(plots.size(), 3u);
  EXPECT_EQ(plots[0]->Attribute("transform"), nullptr);
  EXPECT_STREQ(plots[1]->Attribute("transform"), "translate(0,360)");
  EXPECT_STREQ(plots[2]->Attribute("transform"), "translate(0,560)");
  Svg empty_stack(render_svg_stack({}));
  EXPECT_NE(empty_stack.root(), nullptr);
}

TEST(report_svg_plot, KnownPointsLandOnTheStatedMapping) {
  std::vector<double> x, y;
  for (int i = 0; i <= 10; ++i) x.push_back(i), y.push_back(3.0 * i - 2.0);
  Plot p;
  p.series = {line("y = 3x - 2", x, y)};
  Svg svg(render_svg(p));
  const XMLElement* plot = only_plot(svg);
  ASSERT_NE(plot, nullptr);
  const Mapping m = mapping_of(plot);
  // The area lies inside the document and the range holds the data with a small margin.
  EXPECT_GT(m.left, 0.0);
  EXPECT_LE(m.left + m.width, 900.0);
  EXPECT_GT(m.top, 0.0);
  EXPECT_LE(m.top + m.height, 360.0);
  EXPECT_GT(m.width, 600.0);
  EXPECT_GT(m.height, 200.0);
  EXPECT_LT(m.x0, 0.0);
  EXPECT_GT(m.x0, -1.0);  // margin under 10 % of the span
  EXPECT_GT(m.x1, 10.0);
  EXPECT_LT(m.x1, 11.0);
  EXPECT_LT(m.y0, -2.0);
  EXPECT_GT(m.y0, -5.0);
  EXPECT_GT(m.y1, 28.0);
  EXPECT_LT(m.y1, 31.0);

  const auto lines = find_all(plot, "polyline");
  ASSERT_EQ(lines.size(), 1u);
  const std::vector<Point> pts = points_of(lines[0]);
  ASSERT_EQ(pts.size(), x.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    EXPECT_NEAR(pts[i].x, m.px(x[i]), kPixelTolerance) << i;
    EXPECT_NEAR(pts[i].y, m.py(y[i]), kPixelTolerance) << i;
  }
  // Without the stated range: the first sample sits near the bottom-left corner, the last near
  // the top-right (SVG y grows downwards), inside the margin band.
  EXPECT_GT(pts.front().x, m.left);
  EXPECT_LT(pts.front().x, m.left + 0.1 * m.width);
  EXPECT_LT(pts.front().y, m.top + m.height);
  EXPECT_GT(pts.front().y, m.top + 0.9 * m.height);
  EXPECT_LT(pts.back().x, m.left + m.width);
  EXPECT_GT(pts.back().x, m.left + 0.9 * m.width);
  EXPECT_GT(pts.back().y, m.top);
  EXPECT_LT(pts.back().y, m.top + 0.1 * m.height);
  // A straight line with equal x steps stays straight with equal pixel steps.
  const double dx = pts[1].x - pts[0].x, dy = pts[1].y - pts[0].y;
  EXPECT_GT(dx, 0.0);
  EXPECT_LT(dy, 0.0);
  for (std::size_t i = 1; i + 1 < pts.size(); ++i) {
    EXPECT_NEAR(pts[i + 1].x - pts[i].x, dx, 2 * kPixelTolerance);
    EXPECT_NEAR(pts[i + 1].y - pts[i].y, dy, 2 * kPixelTolerance);
  }
  // The visible axis agrees with the stated range: each tick line sits where its label's value maps.
  const auto xticks = find_all(plot, "line", "xtick");
  const auto yticks = find_all(plot, "line", "ytick");
  const auto xvals = label_values(plot, "xtick-label");
  const auto yvals = label_values(plot, "ytick-label");
  ASSERT_EQ(xticks.size(), xvals.size());
  ASSERT_EQ(yticks.size(), yvals.size());
  ASSERT_GE(xvals.size(), 3u);
  ASSERT_GE(yvals.size(), 3u);
  for (std::size_t i = 0; i < xvals.size(); ++i)
    EXPECT_NEAR(xticks[i]->DoubleAttribute("x1"), m.px(xvals[i]), kPixelTolerance);
  for (std::size_t i = 0; i < yvals.size(); ++i)
    EXPECT_NEAR(yticks[i]->DoubleAttribute("y1"), m.py(yvals[i]), kPixelTolerance);
}

// Checks one axis's ticks: evenly spaced by 1, 2 or 5 x 10^k, multiples of the step, inside the
// range and covering it (less than a step left over at either end).
void expect_nice_ticks(const std::vector<double>& v, double lo, double hi, const std::string& what) {
  SCOPED_TRACE(what);
  ASSERT_GE(v.size(), 3u);
  EXPECT_LE(v.size(), 15u);
  const double step = v[1] - v[0];
  ASSERT_GT(step, 0.0);
  const double magnitude = std::pow(10.0, std::floor(std::log10(step) + 1e-9));
  const double mantissa = step / magnitude;
  EXPECT_TRUE(std::abs(mantissa - 1) < 1e-6 || std::abs(mantissa - 2) < 1e-6 || std::abs(mantissa - 5) < 1e-6)
      << "step " << step;
  for (std::size_t i = 0; i < v.size(); ++i) {
    EXPECT_NEAR(v[i] / step, std::round(v[i] / step), 1e-6) << v[i];
    if (i > 0) {
      EXPECT_NEAR(v[i] - v[i - 1], step, 1e-6 * step) << i;
    }
  }
  const double slack = 1e-9 * step;
  EXPECT_GE(v.front(), lo - slack);
  EXPECT_LT(v.front() - lo, step);
  EXPECT_LE(v.back(), hi + slack);
  EXPECT_LT(hi - v.back(), step);
}

TEST(report_svg_plot, TicksAreOneTwoFiveMultiplesCoveringTheRange) {
  const std::pair<double, double> ranges[] = {{0, 0.0137}, {-3.2, 47},         {1000, 1003}, {-1e-3, 5e-4},
                                              {5, 5},      {-2.5e5, 1.2e6},    {1e-7, 3e-7}, {1e6, 1e6 + 3},
                                              {0, 30},     {1e6, 1e6 + 1e-12}, {0, 0},       {-1e-300, -1e-300}};
  for (const auto& [lo, hi] : ranges) {
    Plot p;
    p.series = {line("s", {lo, hi}, {lo, hi})};
    Svg svg(render_svg(p));
    const XMLElement* plot = only_plot(svg);
    ASSERT_NE(plot, nullptr);
    const Mapping m = mapping_of(plot);
    EXPECT_LE(m.y0, lo);
    EXPECT_GE(m.y1, hi);
    const std::string what = "range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    expect_nice_ticks(label_values(plot, "ytick-label"), m.y0, m.y1, what + " y");
    expect_nice_ticks(label_values(plot, "xtick-label"), m.x0, m.x1, what + " x");
  }
}

std::string lowercase(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

TEST(report_svg_plot, NonFiniteSamplesSplitTheLineAndNeverReachTheOutput) {
  Plot p;
  p.series = {line("y gaps", {0, 1, 2, 3, 4, 5, 6, 7, 8, 9}, {0, 1, kNaN, 3, 4, kInf, 6, 7, 8, -kInf}),
              line("x gaps", {0, 1, kNaN, 3, kInf, 5, 6}, {1, 1, 1, 1, 1, 1, 1})};
  const std::string text = render_svg(p);
  const std::string lower = lowercase(text);
  EXPECT_EQ(lower.find("nan"), std::string::npos);
  EXPECT_EQ(lower.find("inf"), std::string::npos);
  Svg svg(text);
  const XMLElement* plot = only_plot(svg);
  ASSERT_NE(plot, nullptr);
  const Mapping m = mapping_of(plot);
  EXPECT_TRUE(std::isfinite(m.y0) && std::isfinite(m.y1));
  EXPECT_LT(m.y1, 9.0);  // the range ignores the infinities
  const auto series = find_all(plot, "g", "series");
  ASSERT_EQ(series.size(), 2u);
  const auto runs = find_all(series[0], "polyline");
  ASSERT_EQ(runs.size(), 3u);
  EXPECT_EQ(points_of(runs[0]).size(), 2u);
  EXPECT_EQ(points_of(runs[1]).size(), 2u);
  EXPECT_EQ(points_of(runs[2]).size(), 3u);
  EXPECT_NEAR(points_of(runs[1])[0].x, m.px(3), kPixelTolerance);
  EXPECT_NEAR(points_of(runs[2])[0].x, m.px(6), kPixelTolerance);
  // Runs 0-1, 3 (a lone sample, drawn as a dot), 5-6.
  const auto x_runs = find_all(series[1], "polyline");
  ASSERT_EQ(x_runs.size(), 3u);
  const auto lone = points_of(x_runs[1]);
  ASSERT_EQ(lone.size(), 2u);
  EXPECT_NEAR(lone[0].x, m.px(3), kPixelTolerance);
  EXPECT_EQ(lone[0].x, lone[1].x);
  EXPECT_EQ(lone[0].y, lone[1].y);

  Plot all_bad;
  all_bad.series = {line("bad", {kNaN, 1, kInf}, {0, kNaN, 1})};
  const std::string bad_text = render_svg(all_bad);
  EXPECT_EQ(lowercase(bad_text).find("nan"), std::string::npos);
  EXPECT_EQ(lowercase(bad_text).find("inf"), std::string::npos);
  Svg bad(bad_text);
  EXPECT_EQ(find_all(bad.root(), "text", "no-data").size(), 1u);
  EXPECT_EQ(find_all(bad.root(), "polyline").size(), 0u);
}

TEST(report_svg_plot, EmptyPlotHasAxesAndANoDataNote) {
  for (const Plot& p : {Plot{}, Plot{"empty", "t [s]", "x [m]", {line("nothing", {}, {})}, {}, false, 900, 360}}) {
    Svg svg(render_svg(p));
    ASSERT_NE(svg.root(), nullptr);
    const auto notes = find_all(svg.root(), "text", "no-data");
    ASSERT_EQ(notes.size(), 1u);
    EXPECT_STREQ(notes[0]->GetText(), "no data");
    EXPECT_EQ(find_all(svg.root(), "rect", "plot-area").size(), 1u);
    EXPECT_GE(find_all(svg.root(), "line", "xtick").size(), 2u);
    EXPECT_GE(find_all(svg.root(), "line", "ytick").size(), 2u);
  }
  Plot with_data;
  with_data.series = {line("one", {0, 1}, {0, 1})};
  Svg svg(render_svg(with_data));
  EXPECT_EQ(find_all(svg.root(), "text", "no-data").size(), 0u);
}

TEST(report_svg_plot, DecimationKeepsSpikesAndBoundsThePointCount) {
  constexpr std::size_t kSamples = 100000;
  constexpr std::size_t kUpSpike = 31337, kDownSpike = 77777;
  std::vector<double> x(kSamples), y(kSamples);
  for (std::size_t i = 0; i < kSamples; ++i) {
    x[i] = 0.0003 * static_cast<double>(i);
    // A slow wave plus a deterministic jitter.
    y[i] = std::sin(2.0 * std::numbers::pi * 0.5 * x[i]) + 0.01 * (static_cast<double>((i * 7919) % 13) - 6.0) / 6.0;
  }
  y[kUpSpike] = 50.0;
  y[kDownSpike] = -40.0;
  Plot p;
  p.series = {line("spiky", x, y)};
  const std::string text = render_svg(p);
  Svg svg(text);
  const XMLElement* plot = only_plot(svg);
  ASSERT_NE(plot, nullptr);
  const Mapping m = mapping_of(plot);
  const auto lines = find_all(plot, "polyline");
  ASSERT_EQ(lines.size(), 1u);
  const auto pts = points_of(lines[0]);
  EXPECT_LE(pts.size(), 4 * static_cast<std::size_t>(std::ceil(m.width)) + 4);
  EXPECT_GE(pts.size(), static_cast<std::size_t>(m.width) / 2);  // still one or more per column
  const auto [top, bottom] =
      std::minmax_element(pts.begin(), pts.end(), [](const Point& a, const Point& b) { return a.y < b.y; });
  EXPECT_NEAR(top->y, m.py(50.0), kPixelTolerance);
  EXPECT_NEAR(top->x, m.px(x[kUpSpike]), kPixelTolerance);
  EXPECT_NEAR(bottom->y, m.py(-40.0), kPixelTolerance);
  EXPECT_NEAR(bottom->x, m.px(x[kDownSpike]), kPixelTolerance);
  // Drawn left to right: decimation keeps the sample order.
  for (std::size_t i = 1; i < pts.size(); ++i) ASSERT_GE(pts[i].x, pts[i - 1].x) << i;

  // The report's case: 30 s at 500 Hz.
  std::vector<double> t(15000), q(15000);
  for (std::size_t i = 0; i < t.size(); ++i) {
    t[i] = static_cast<double>(i) / 500.0;
    q[i] = 0.3 * std::sin(2.0 * std::numbers::pi * 1.3 * t[i]) + 0.002 * static_cast<double>((i * 104729) % 17);
  }
  Plot joint;
  joint.series = {line("q_ref", t, q)};
  EXPECT_LT(render_svg(joint).size(), 200u * 1024u);
}

TEST(report_decimate, KeepsOrderAndColumnExtremesOfAPathThatDoublesBack) {
  // Columns: 0 0 0 | 1 1 | 0 0 | 2: a path going right, back left, then right again.
  const std::vector<double> px = {0.1, 0.5, 0.9, 1.2, 1.8, 0.7, 0.2, 2.5};
  const std::vector<double> py = {5.0, 1.0, 3.0, 4.0, 4.5, 9.0, 2.0, 0.0};
  std::vector<std::size_t> keep;
  decimate_min_max(px, py, &keep);
  EXPECT_EQ(keep, (std::vector<std::size_t>{0, 1, 2, 3, 4, 5, 6, 7}));  // nothing to drop yet
  std::vector<double> long_x, long_y;
  for (int i = 0; i < 1000; ++i) long_x.push_back(0.001 * i), long_y.push_back(i == 500 ? -7.0 : (i % 3));
  decimate_min_max(long_x, long_y, &keep);
  EXPECT_EQ(keep, (std::vector<std::size_t>{0, 2, 500, 999}));  // first, highest (first of ties), lowest, last
}

TEST(report_svg_plot, EqualAxesGiveEqualPixelsPerUnit) {
  struct Case {
    std::vector<double> px, py;  // polygon
  };
  const Case cases[] = {{{0, 2, 2, 0}, {0, 0, 1, 1}},         // wide and short: y widened
                        {{0, 1, 1, 0}, {0, 0, 10, 10}},       // tall: x widened
                        {{-50, 50, 50, -50}, {0, 0, 1, 1}}};  // very wide
  for (const Case& c : cases) {
    for (const bool equal : {true, false}) {
      Plot p;
      p.equal_axes = equal;
      p.polygons.push_back({"support", c.px, c.py, ""});
      p.series = {line("unit steps", {0, 1, 1}, {0, 0, 1})};
      Svg svg(render_svg(p));
      const XMLElement* plot = only_plot(svg);
      ASSERT_NE(plot, nullptr);
      const Mapping m = mapping_of(plot);
      const auto pts = points_of(find_all(plot, "polyline").at(0));
      ASSERT_EQ(pts.size(), 3u);
      const double px_per_unit_x = pts[1].x - pts[0].x;
      const double px_per_unit_y = pts[1].y - pts[2].y;
      EXPECT_GT(px_per_unit_x, 0.0);
      EXPECT_GT(px_per_unit_y, 0.0);
      if (equal) {
        EXPECT_NEAR(px_per_unit_x, px_per_unit_y, 2 * kPixelTolerance);
        EXPECT_NEAR(m.width / (m.x1 - m.x0), m.height / (m.y1 - m.y0), 1e-9 * m.width / (m.x1 - m.x0));
      } else {
        // The default fills the area instead, so this case would catch equal_axes being ignored.
        EXPECT_GT(std::abs(px_per_unit_x / px_per_unit_y - 1.0), 0.1);
      }
      // Everything is still inside the area.
      for (const Point& q : points_of(find_all(plot, "polygon").at(0))) {
        EXPECT_GE(q.x, m.left);
        EXPECT_LE(q.x, m.left + m.width);
        EXPECT_GE(q.y, m.top);
        EXPECT_LE(q.y, m.top + m.height);
      }
    }
  }
}

TEST(report_svg_plot, LegendListsEveryNameEscaped) {
  Plot p;
  p.series = {line("a<b", {0, 1}, {0, 1}),      line("x & y", {0, 1}, {1, 0}), line("say \"hi\"", {0, 1}, {0.5, 0.5}),
              line("it's", {0, 1}, {0.2, 0.2}), line("", {0, 1}, {0.3, 0.3}),  line("plain", {0, 1}, {0.7, 0.7})};
  p.polygons.push_back({"support <polygon>", {0, 1, 1}, {0, 0, 1}, ""});
  const std::string text = render_svg(p);
  Svg svg(text);
  const auto labels = find_all(svg.root(), "text", "legend-label");
  std::vector<std::string> names;
  for (const XMLElement* e : labels) names.push_back(e->GetText());
  EXPECT_EQ(names, (std::vector<std::string>{"a<b", "x & y", "say \"hi\"", "it's", "plain", "support <polygon>"}));
  EXPECT_NE(text.find(">a&lt;b<"), std::string::npos);
  EXPECT_NE(text.find(">x &amp; y<"), std::string::npos);
  EXPECT_NE(text.find("say &quot;hi&quot;"), std::string::npos);
  EXPECT_EQ(text.find("a<b"), std::string::npos);
  EXPECT_EQ(text.find("x & y"), std::string::npos);
  // The series groups carry the same names.
  const auto series = find_all(svg.root(), "g", "series");
  ASSERT_EQ(series.size(), 6u);
  EXPECT_STREQ(series[0]->Attribute("data-name"), "a<b");
}

TEST(report_svg_plot, ColoursAndDashes) {
  Plot p;
  p.series = {line("auto 0", {0, 1}, {0, 1}), line("auto 1", {0, 1}, {1, 0}), line("red", {0, 1}, {0, 0})};
  p.series[2].color = "#ff0000";
  p.series[2].dashed = true;
  p.polygons.push_back({"", {0, 1, 1}, {0, 0, 1}, ""});
  p.polygons.push_back({"", {0, 1, 1}, {0, 0, 1}, "lightblue"});
  Svg svg(render_svg(p));
  const auto series = find_all(svg.root(), "g", "series");
  ASSERT_EQ(series.size(), 3u);
  EXPECT_STRNE(series[0]->Attribute("stroke"), series[1]->Attribute("stroke"));
  EXPECT_STREQ(series[2]->Attribute("stroke"), "#ff0000");
  EXPECT_EQ(series[0]->Attribute("stroke-dasharray"), nullptr);
  EXPECT_NE(series[2]->Attribute("stroke-dasharray"), nullptr);
  const auto polygons = find_all(svg.root(), "polygon", "polygon");
  ASSERT_EQ(polygons.size(), 2u);
  EXPECT_STRNE(polygons[0]->Attribute("fill"), "");
  EXPECT_STREQ(polygons[1]->Attribute("fill"), "lightblue");
}

TEST(report_write_text_file, WritesAndReportsFailure) {
  const std::filesystem::path path = std::filesystem::path(KUAVO_BINARY_DIR) / "report_write_text_file_test.svg";
  std::string error;
  ASSERT_TRUE(write_text_file(path.string(), "<svg/>\n", &error)) << error;
  std::ifstream in(path);
  std::stringstream back;
  back << in.rdbuf();
  EXPECT_EQ(back.str(), "<svg/>\n");
  std::filesystem::remove(path);

  const std::string bad = "/nonexistent-kuavo-dir/plot.svg";
  EXPECT_FALSE(write_text_file(bad, "x", &error));
  EXPECT_NE(error.find(bad), std::string::npos) << error;
  EXPECT_FALSE(write_text_file(bad, "x", nullptr));
}

}  // namespace
}  // namespace kuavo::report
