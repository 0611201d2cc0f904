// Small writers for the benchmark and bake reports: SVG line plots, an SVG
// street map, and a self-contained HTML page. No dependencies beyond the
// standard library; nothing here throws on bad data (NaN, empty input) — it
// draws what it can. Output is well-formed XML (the HTML page too, so that
// SVG can be inlined), with every caller-supplied string escaped.
//
// Numbers are formatted with snprintf, so the process must be in the "C"
// numeric locale (the CLI never calls setlocale).
#pragma once
#include <cmath>
#include <cstddef>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace blvd::cli {

// Escapes & < > " ' for use in HTML/XML text and attribute values.
std::string htmlEscape(std::string_view s);

// Viridis-like ramp: t in [0, 1] (clamped) to "#rrggbb", linear between the
// five viridis stops #440154, #3b528b, #21918c, #5ec962, #fde725 (dark
// violet -> yellow, monotonic in lightness). NaN gives "#808080".
std::string colorRamp(double t);

// Categorical colour i (cycling through 10, the "tab10" palette): the default
// of a Series without a colour.
std::string seriesColor(size_t i);

// "Nice numbers for graph labels" (Heckbert, Graphics Gems I, 1990), loose
// labelling: ticks k * step for consecutive integers k, step = {1, 2, 5} x 10^n,
// the first <= lo and the last >= hi, about `target` of them (>= 2).
// Each tick is computed as (k * mantissa) / 10^-n (or * 10^n) so that it is
// the double closest to its decimal value (0.3, not 0.30000000000000004).
// A degenerate or non-finite range is widened first: lo == hi by 10 % of |lo|
// (1 when lo == 0); non-finite bounds give [0, 1].
std::vector<double> niceTicks(double lo, double hi, int target = 6);

// Tick label with the fewest decimals that write `step` exactly (step 0.25:
// "0.75"; step 50: "100"; at most 12), never "-0".
std::string formatTick(double v, double step);

// ---- line plot ------------------------------------------------------------

struct Series {
  std::string name;        // legend text; no legend entry when empty
  std::vector<double> y;   // NaN/inf values are gaps
  std::string color;       // any SVG colour; empty = seriesColor(index)
};

struct PlotSpec {
  std::string title, x_label, y_label;
  std::vector<double> x;   // optional: x[i] for y[i]; empty = the index i.
                           // Points with i >= x.size() or non-finite x are gaps.
  std::vector<Series> series;
  double y_min = NAN, y_max = NAN;  // fixed axis bounds when finite (each
                                    // independently); else nice bounds of the data
  std::vector<std::pair<double, std::string>> h_lines;  // dashed reference lines (a budget, a target) with labels
  int width = 720, height = 300;    // pixels; values < 200 x 120 are raised to that
};

// A standalone SVG (no XML declaration, so it can also be inlined in HTML):
// title, legend, framed plot area with grid lines at nice ticks (x spans the
// data exactly, y is widened to nice bounds unless fixed), axis labels,
// one <polyline> per run of consecutive finite points (one coordinate pair per
// value) and a <circle> for a run of one point. Data outside fixed y bounds is
// clipped by the plot area (a nested <svg>, no ids, so many plots can share a page).
std::string svgLinePlot(const PlotSpec& spec);

// ---- map ------------------------------------------------------------------

struct MapLine {
  std::vector<std::pair<double, double>> pts;  // (x east, y north); non-finite points are gaps
  std::string color;                           // empty = "#555555"
  double width = 1.0;                          // stroke width in pixels (<= 0 means 1)
};

struct LegendEntry {
  std::string label;
  std::string color;
};

struct MapSpec {
  std::string title;
  std::vector<MapLine> lines;
  std::vector<LegendEntry> legend;
  std::string units = "m";          // of the coordinates, for the scale bar; empty = no scale bar
  int width = 720, height = 720;    // pixels; values < 200 x 200 are raised to that
};

// Top-down SVG map: the bounding box of all finite points fitted into the
// drawing area with one scale for x and y (no distortion), north up (y grows
// up the page), a legend row under the title and a scale bar of a nice length.
std::string svgMap(const MapSpec& spec);

// ---- HTML page ------------------------------------------------------------

struct Figure {
  std::string src;      // image path, relative to the page
  std::string caption;  // plain text; may be empty
};

// A self-contained page (inline CSS, no scripts, images by relative link),
// built top to bottom. Text arguments are plain text and are escaped; raw()
// inserts markup as is (an SVG from svgLinePlot()/svgMap()).
class HtmlPage {
 public:
  explicit HtmlPage(std::string title);  // <title> and the <h1>

  HtmlPage& h2(std::string_view text);
  HtmlPage& paragraph(std::string_view text);
  // rows[0] is the header row when `header` is set; ragged rows are allowed.
  HtmlPage& table(const std::vector<std::vector<std::string>>& rows, bool header = true);
  HtmlPage& raw(std::string_view markup);
  // Images in `columns` equal columns (e.g. 3 for full | blvd | difference),
  // each linking to the full-size file.
  HtmlPage& imageGrid(const std::vector<Figure>& figures, int columns);

  std::string str() const;
  // Writes str() to `path`. False with `err` set when the file cannot be written.
  bool write(const std::string& path, std::string& err) const;

 private:
  std::string title_;
  std::string body_;
};

}  // namespace blvd::cli
