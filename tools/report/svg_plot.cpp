#include "tools/report/svg_plot.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string_view>

#include "tools/report/axis_ticks.h"
#include "tools/report/decimate.h"

namespace kuavo::report {
namespace {

// Layout, in pixels. The left margin holds ~7-character tick labels and the rotated y label.
constexpr double kMarginLeft_px = 72.0;
constexpr double kMarginRight_px = 16.0;
constexpr double kMarginTop_px = 30.0;
constexpr double kMarginBottom_px = 46.0;
constexpr int kMinWidth_px = 240;
constexpr int kMinHeight_px = 140;
constexpr double kTickLength_px = 4.0;
// Legend column right of the plot area: swatch, gap, text at ~6.5 px per character of the
// 11 px sans-serif font. At most a third of the plot's width (longer names run off the edge).
constexpr double kLegendPad_px = 12.0;
constexpr double kLegendSwatch_px = 18.0;
constexpr double kLegendGap_px = 6.0;
constexpr double kLegendCharWidth_px = 6.5;
constexpr double kLegendRowHeight_px = 16.0;
// Data margin on each side of the range, as a fraction of its span, so lines clear the frame.
constexpr double kRangePadFraction = 0.03;
constexpr double kMinRelativePad = 1e-9;
// Tick density: about one x tick per 100 px and one y tick per 45 px.
constexpr double kXTickSpacing_px = 100.0;
constexpr double kYTickSpacing_px = 45.0;
// Pixel coordinates are written with 2 decimals and kept inside this bound, so a pathological
// input (values near DBL_MAX) still yields finite numbers.
constexpr double kMaxCoordinate_px = 1e6;

// matplotlib's "tab10": distinct from each other and readable on white.
constexpr const char* kPalette[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                                    "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};
constexpr std::size_t kPaletteSize = sizeof kPalette / sizeof kPalette[0];
constexpr const char* kDefaultPolygonFill = "#d9d9d9";

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool empty() const { return !(lo <= hi); }
  double span() const { return hi - lo; }
};

// The plot area in pixels and the data rectangle it shows (x right, y up).
struct Frame {
  double left_px = 0, top_px = 0, width_px = 1, height_px = 1;
  Range x, y;
  bool has_data = false;
  double px(double v) const { return left_px + (v - x.lo) / x.span() * width_px; }
  double py(double v) const { return top_px + height_px - (v - y.lo) / y.span() * height_px; }
};

template <class Line>
std::size_t sample_count(const Line& line) {
  return std::min(line.x.size(), line.y.size());
}
template <class Line>
bool finite_sample(const Line& line, std::size_t i) {
  return std::isfinite(line.x[i]) && std::isfinite(line.y[i]);
}

std::string_view series_color(const Plot& plot, std::size_t i) {
  const std::string& c = plot.series[i].color;
  return c.empty() ? std::string_view(kPalette[i % kPaletteSize]) : std::string_view(c);
}
std::string_view polygon_fill(const Polygon& p) {
  return p.fill.empty() ? std::string_view(kDefaultPolygonFill) : std::string_view(p.fill);
}

// ---- text output -------------------------------------------------------------------------

void put_escaped(std::string& out, std::string_view text) {
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default:
        // XML 1.0 allows no control characters other than tab, newline, carriage return.
        if (static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\n' && c != '\r') {
          out += ' ';
        } else {
          out += c;
        }
    }
  }
}

// A pixel coordinate: 2 decimals, trailing zeros dropped, never NaN or infinite.
void put_number(std::string& out, double v) {
  if (!std::isfinite(v)) v = 0.0;
  v = std::clamp(v, -kMaxCoordinate_px, kMaxCoordinate_px);
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed, 2);
  const char* end = r.ptr;
  while (end[-1] == '0') --end;
  if (end[-1] == '.') --end;
  std::string_view s(buf, static_cast<std::size_t>(end - buf));
  out += (s == "-0") ? std::string_view("0") : s;
}

void put_attr(std::string& out, std::string_view name, double v) {
  out += ' ';
  out += name;
  out += "=\"";
  put_number(out, v);
  out += '"';
}
void put_attr(std::string& out, std::string_view name, std::string_view text) {
  out += ' ';
  out += name;
  out += "=\"";
  put_escaped(out, text);
  out += '"';
}
// The shown data range, exactly (shortest round-trip form): it defines the mapping.
void put_range_attr(std::string& out, std::string_view name, const Range& r) {
  char buf[64];
  char* p = std::to_chars(buf, buf + sizeof buf, r.lo).ptr;
  *p++ = ' ';
  p = std::to_chars(p, buf + sizeof buf, r.hi).ptr;
  put_attr(out, name, std::string_view(buf, static_cast<std::size_t>(p - buf)));
}
void put_point(std::string& out, double x, double y) {
  put_number(out, x);
  out += ',';
  put_number(out, y);
}

void put_text(std::string& out, std::string_view cls, double x, double y, std::string_view anchor,
              std::string_view text, std::string_view extra_attrs = {}) {
  out += "<text";
  put_attr(out, "class", cls);
  put_attr(out, "x", x);
  put_attr(out, "y", y);
  if (!anchor.empty()) put_attr(out, "text-anchor", anchor);
  out += extra_attrs;
  out += '>';
  put_escaped(out, text);
  out += "</text>\n";
}

// ---- layout ------------------------------------------------------------------------------

// Characters, not bytes, of UTF-8 text (for the legend width estimate).
std::size_t utf8_length(std::string_view s) {
  return static_cast<std::size_t>(
      std::count_if(s.begin(), s.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

double legend_width_px(const Plot& plot, double plot_width_px) {
  std::size_t longest = 0;
  bool any = false;
  auto consider = [&](const std::string& name) {
    if (name.empty()) return;
    longest = std::max(longest, utf8_length(name));
    any = true;
  };
  for (const Series& s : plot.series) consider(s.name);
  for (const Polygon& p : plot.polygons) consider(p.name);
  if (!any) return 0.0;
  const double wanted =
      kLegendPad_px + kLegendSwatch_px + kLegendGap_px + kLegendCharWidth_px * static_cast<double>(longest);
  return std::min(wanted, plot_width_px / 3.0);
}

// Widens a data range by the margin; gives an empty or zero-width range a usable extent.
Range padded(const Range& r) {
  if (r.empty()) return {0.0, 1.0};
  double pad = r.span() * kRangePadFraction;
  if (!(pad > 0.0)) pad = std::abs(r.lo) * 0.1;  // a constant: +-10 % of its value
  if (!(pad > 0.0)) pad = 1.0;                   // zero (or too small to pad)
  // Ticks need a span that doubles can still divide: at least 1e-9 of the magnitude.
  pad = std::max(pad, kMinRelativePad * std::max(std::abs(r.lo), std::abs(r.hi)));
  // Keep the span finite (and thus the mapping) even for values near DBL_MAX.
  constexpr double kLimit = std::numeric_limits<double>::max() / 4.0;
  return {std::max(r.lo - pad, -kLimit), std::min(r.hi + pad, kLimit)};
}

Frame make_frame(const Plot& plot, double width_px, double height_px) {
  Frame f;
  f.left_px = kMarginLeft_px;
  f.top_px = kMarginTop_px;
  f.width_px = width_px - kMarginLeft_px - kMarginRight_px - legend_width_px(plot, width_px);
  f.height_px = height_px - kMarginTop_px - kMarginBottom_px;
  Range x, y;
  auto add = [&](const auto& line) {
    for (std::size_t i = 0, n = sample_count(line); i < n; ++i) {
      if (!finite_sample(line, i)) continue;
      x.add(line.x[i]);
      y.add(line.y[i]);
    }
  };
  for (const Polygon& p : plot.polygons) add(p);
  for (const Series& s : plot.series) add(s);
  f.has_data = !x.empty();
  f.x = padded(x);
  f.y = padded(y);
  if (plot.equal_axes) {
    // Both axes get the smaller of the two scales; the other range grows about its centre.
    const double sx = f.width_px / f.x.span(), sy = f.height_px / f.y.span();
    Range& grow = (sx > sy) ? f.x : f.y;
    const double scale = std::min(sx, sy);
    const double half = 0.5 * ((sx > sy) ? f.width_px : f.height_px) / scale;
    const double mid = 0.5 * (grow.lo + grow.hi);
    grow = {mid - half, mid + half};
  }
  return f;
}

// ---- drawing -----------------------------------------------------------------------------

void draw_ticks(const Frame& f, std::string& out) {
  const double bottom = f.top_px + f.height_px, right = f.left_px + f.width_px;
  const AxisTicks xt = nice_ticks(f.x.lo, f.x.hi, static_cast<int>(std::lround(f.width_px / kXTickSpacing_px)));
  const AxisTicks yt = nice_ticks(f.y.lo, f.y.hi, static_cast<int>(std::lround(f.height_px / kYTickSpacing_px)));
  out += "<g stroke=\"#e3e3e3\">\n";
  for (const double v : xt.values) {
    out += "<line class=\"xtick\"";
    put_attr(out, "x1", f.px(v));
    put_attr(out, "y1", f.top_px);
    put_attr(out, "x2", f.px(v));
    put_attr(out, "y2", bottom + kTickLength_px);
    out += "/>\n";
  }
  for (const double v : yt.values) {
    out += "<line class=\"ytick\"";
    put_attr(out, "x1", f.left_px - kTickLength_px);
    put_attr(out, "y1", f.py(v));
    put_attr(out, "x2", right);
    put_attr(out, "y2", f.py(v));
    out += "/>\n";
  }
  out += "</g>\n<g fill=\"#333\">\n";
  for (const double v : xt.values)
    put_text(out, "xtick-label", f.px(v), bottom + 16.0, "middle", format_tick(v, xt.step));
  for (const double v : yt.values) {
    put_text(out, "ytick-label", f.left_px - kTickLength_px - 3.0, f.py(v) + 4.0, "end", format_tick(v, yt.step));
  }
  out += "</g>\n";
}

void draw_polygons(const Plot& plot, const Frame& f, std::string& out) {
  for (const Polygon& p : plot.polygons) {
    out += "<polygon class=\"polygon\"";
    put_attr(out, "fill", polygon_fill(p));
    out += " fill-opacity=\"0.6\" stroke=\"#8c8c8c\" stroke-width=\"1\" points=\"";
    bool first = true;
    for (std::size_t i = 0, n = sample_count(p); i < n; ++i) {
      if (!finite_sample(p, i)) continue;
      if (!first) out += ' ';
      put_point(out, f.px(p.x[i]), f.py(p.y[i]));
      first = false;
    }
    out += "\"/>\n";
  }
}

// Buffers reused across runs and series of one render.
struct RunScratch {
  std::vector<double> px, py;
  std::vector<std::size_t> keep;
};

void draw_run(const Series& s, const Frame& f, std::size_t begin, std::size_t end, RunScratch& w, std::string& out) {
  w.px.clear();
  w.py.clear();
  for (std::size_t i = begin; i < end; ++i) {
    w.px.push_back(f.px(s.x[i]));
    w.py.push_back(f.py(s.y[i]));
  }
  decimate_min_max(w.px, w.py, &w.keep);
  out += "<polyline points=\"";
  for (std::size_t k = 0; k < w.keep.size(); ++k) {
    if (k > 0) out += ' ';
    put_point(out, w.px[w.keep[k]], w.py[w.keep[k]]);
  }
  if (w.keep.size() == 1) {  // a lone sample: a zero-length segment, drawn as a dot by the round cap
    out += ' ';
    put_point(out, w.px[w.keep[0]], w.py[w.keep[0]]);
  }
  out += "\"/>\n";
}

void draw_series(const Plot& plot, const Frame& f, std::string& out) {
  RunScratch scratch;
  for (std::size_t si = 0; si < plot.series.size(); ++si) {
    const Series& s = plot.series[si];
    out += "<g class=\"series\"";
    put_attr(out, "data-name", s.name);
    put_attr(out, "stroke", series_color(plot, si));
    out += " fill=\"none\" stroke-width=\"1.5\" stroke-linejoin=\"round\" stroke-linecap=\"round\"";
    if (s.dashed) out += " stroke-dasharray=\"6 4\"";
    out += ">\n";
    const std::size_t n = sample_count(s);
    std::size_t i = 0;
    while (i < n) {
      while (i < n && !finite_sample(s, i)) ++i;
      const std::size_t begin = i;
      while (i < n && finite_sample(s, i)) ++i;
      if (i > begin) draw_run(s, f, begin, i, scratch, out);
    }
    out += "</g>\n";
  }
}

void draw_legend(const Plot& plot, const Frame& f, std::string& out) {
  const double swatch_x = f.left_px + f.width_px + kLegendPad_px;
  const double text_x = swatch_x + kLegendSwatch_px + kLegendGap_px;
  double row_y = f.top_px + 8.0;
  out += "<g class=\"legend\">\n";
  for (std::size_t si = 0; si < plot.series.size(); ++si) {
    const Series& s = plot.series[si];
    if (s.name.empty()) continue;
    out += "<line";
    put_attr(out, "x1", swatch_x);
    put_attr(out, "y1", row_y);
    put_attr(out, "x2", swatch_x + kLegendSwatch_px);
    put_attr(out, "y2", row_y);
    put_attr(out, "stroke", series_color(plot, si));
    out += " stroke-width=\"2\"";
    if (s.dashed) out += " stroke-dasharray=\"6 4\"";
    out += "/>\n";
    put_text(out, "legend-label", text_x, row_y + 4.0, {}, s.name);
    row_y += kLegendRowHeight_px;
  }
  for (const Polygon& p : plot.polygons) {
    if (p.name.empty()) continue;
    out += "<rect";
    put_attr(out, "x", swatch_x);
    put_attr(out, "y", row_y - 5.0);
    put_attr(out, "width", kLegendSwatch_px);
    put_attr(out, "height", 10.0);
    put_attr(out, "fill", polygon_fill(p));
    out += " fill-opacity=\"0.6\" stroke=\"#8c8c8c\"/>\n";
    put_text(out, "legend-label", text_x, row_y + 4.0, {}, p.name);
    row_y += kLegendRowHeight_px;
  }
  out += "</g>\n";
}

// One plot as a <g>, its top edge at offset_y in the document.
void draw_plot(const Plot& plot, double offset_y, std::string& out) {
  const double width = std::max(plot.width_px, kMinWidth_px), height = std::max(plot.height_px, kMinHeight_px);
  const Frame f = make_frame(plot, width, height);
  out += "<g class=\"plot\"";
  put_range_attr(out, "data-x-range", f.x);
  put_range_attr(out, "data-y-range", f.y);
  if (offset_y != 0.0) {
    out += " transform=\"translate(0,";
    put_number(out, offset_y);
    out += ")\"";
  }
  out += ">\n";
  draw_ticks(f, out);
  draw_polygons(plot, f, out);
  draw_series(plot, f, out);
  out += "<rect class=\"plot-area\"";
  put_attr(out, "x", f.left_px);
  put_attr(out, "y", f.top_px);
  put_attr(out, "width", f.width_px);
  put_attr(out, "height", f.height_px);
  out += " fill=\"none\" stroke=\"#444\"/>\n";
  const double mid_x = f.left_px + 0.5 * f.width_px, mid_y = f.top_px + 0.5 * f.height_px;
  if (!f.has_data) put_text(out, "no-data", mid_x, mid_y, "middle", "no data", " fill=\"#888\" font-size=\"14\"");
  if (!plot.title.empty())
    put_text(out, "title", mid_x, 19.0, "middle", plot.title, " font-size=\"13\" font-weight=\"bold\"");
  if (!plot.x_label.empty()) put_text(out, "x-label", mid_x, f.top_px + f.height_px + 36.0, "middle", plot.x_label);
  if (!plot.y_label.empty()) {
    std::string rotate = " transform=\"rotate(-90 16 ";
    put_number(rotate, mid_y);
    rotate += ")\"";
    put_text(out, "y-label", 16.0, mid_y, "middle", plot.y_label, rotate);
  }
  draw_legend(plot, f, out);
  out += "</g>\n";
}

void open_document(double width, double height, std::string& out) {
  out += "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\"";
  put_attr(out, "width", width);
  put_attr(out, "height", height);
  out += " viewBox=\"0 0 ";
  put_number(out, width);
  out += ' ';
  put_number(out, height);
  out += "\" font-family=\"sans-serif\" font-size=\"11\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
}

}  // namespace

std::string render_svg(const Plot& plot) {
  std::string out;
  open_document(std::max(plot.width_px, kMinWidth_px), std::max(plot.height_px, kMinHeight_px), out);
  draw_plot(plot, 0.0, out);
  out += "</svg>\n";
  return out;
}

std::string render_svg_stack(const std::vector<Plot>& plots) {
  double width = 0.0, height = 0.0;
  for (const Plot& p : plots) {
    width = std::max(width, static_cast<double>(std::max(p.width_px, kMinWidth_px)));
    height += std::max(p.height_px, kMinHeight_px);
  }
  std::string out;
  open_document(width, height, out);
  double offset_y = 0.0;
  for (const Plot& p : plots) {
    draw_plot(p, offset_y, out);
    offset_y += std::max(p.height_px, kMinHeight_px);
  }
  out += "</svg>\n";
  return out;
}

bool write_text_file(const std::string& path, const std::string& text, std::string* error) {
  auto fail = [&](const char* what) {
    if (error != nullptr) *error = path + ": " + what + ": " + std::strerror(errno);
    return false;
  };
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) return fail("cannot open for writing");
  const bool written = std::fwrite(text.data(), 1, text.size(), file) == text.size();
  const int write_errno = errno;
  if (std::fclose(file) != 0) return fail("cannot close");
  if (!written) {
    errno = write_errno;
    return fail("cannot write");
  }
  return true;
}

}  // namespace kuavo::report
