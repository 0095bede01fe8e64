// SVG line plots for the `kuavo demo` report (joint tracking, CoM, ZMP): offline, no dependencies.
// Everything here allocates; none of it belongs in the real-time path.
//
// Output contract (the tests read it, so other tools may too):
//  - each plot is a <g class="plot" data-x-range="x0 x1" data-y-range="y0 y1"> whose
//    <rect class="plot-area"> is the pixel rectangle that shows exactly [x0, x1] x [y0, y1]
//    (x to the right, y up);
//  - ticks are <line class="xtick"|"ytick"> with <text class="xtick-label"|"ytick-label">;
//  - each series is a <g class="series" data-name="..."> of <polyline>s (one per finite run);
//    polygons are <polygon class="polygon">; the legend is <g class="legend"> with
//    <text class="legend-label">; an empty plot carries <text class="no-data">.
#pragma once

#include <string>
#include <vector>

namespace kuavo::report {

// One line. x and y pair up index by index (extra samples of the longer one are ignored). A
// sample with a non-finite x or y is not drawn and breaks the line there.
struct Series {
  std::string name;  // legend text; "" keeps the series out of the legend
  std::vector<double> x, y;
  std::string color;  // any SVG colour; "" = automatic palette (by series index)
  bool dashed = false;
};

// A closed, filled outline (e.g. a support polygon), drawn under the series. Non-finite
// vertices are skipped.
struct Polygon {
  std::string name;  // legend text; "" keeps it out of the legend
  std::vector<double> x, y;
  std::string fill;  // "" = light grey
};

struct Plot {
  std::string title, x_label, y_label;
  std::vector<Series> series;
  std::vector<Polygon> polygons;
  // Same pixels per unit on x and y (top-down CoM/ZMP against the support polygon): the axis
  // with room to spare is widened about its centre.
  bool equal_axes = false;
  int width_px = 900, height_px = 360;  // raised to at least 240 x 140
};

// One plot as a standalone SVG document. The axis ranges span every finite sample of the series
// and polygons plus a small margin; ticks are 1-2-5 multiples of a power of ten; non-finite
// numbers never reach the output. A plot without finite data shows axes and a "no data" note.
// Long series are decimated per pixel column keeping each column's first, lowest, highest and
// last sample, so a one-sample spike still shows and a 30 s, 500 Hz series takes 25-35 KB.
std::string render_svg(const Plot& plot);

// Several plots stacked top to bottom in one SVG document (as wide as the widest plot).
std::string render_svg_stack(const std::vector<Plot>& plots);

// Writes text to path (replacing it). On failure returns false and, when error is not null,
// a message naming the path and the reason.
bool write_text_file(const std::string& path, const std::string& text, std::string* error);

}  // namespace kuavo::report
