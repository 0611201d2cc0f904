// SVG plots and maps, HTML pages for the benchmark and bake reports (report.h).
#include "cli/report.h"

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <fstream>

namespace blvd::cli {
namespace {

// printf-style append, for numbers in the C locale. Never truncates: a long
// label must not cut a tag in half.
void appendf(std::string& out, const char* fmt, ...) __attribute__((format(printf, 2, 3)));
void appendf(std::string& out, const char* fmt, ...) {
  char buf[512];
  va_list ap, again;
  va_start(ap, fmt);
  va_copy(again, ap);
  const int n = std::vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  if (n > 0 && static_cast<size_t>(n) < sizeof buf) {
    out.append(buf, static_cast<size_t>(n));
  } else if (n > 0) {
    const size_t at = out.size();
    out.resize(at + static_cast<size_t>(n) + 1);
    std::vsnprintf(&out[at], static_cast<size_t>(n) + 1, fmt, again);
    out.resize(at + static_cast<size_t>(n));
  }
  va_end(again);
}

// Pixel coordinate: clamped, so that a value far outside a fixed axis still
// prints as a short finite number (the plot area clips it anyway).
double pix(double v) { return std::clamp(v, -1e6, 1e6); }

// Rough text width in pixels at font-size 11 (no font metrics here): used only
// to lay out legend entries.
double textWidth(const std::string& s) { return 6.2 * static_cast<double>(s.size()); }

struct Nice {
  int mantissa = 1;  // 1, 2 or 5
  int exponent = 0;  // power of ten
  double value() const { return mantissa * std::pow(10.0, exponent); }
};

// Heckbert's nicenum: a {1, 2, 5} x 10^n number near x (> 0).
Nice niceNum(double x, bool round) {
  int e = static_cast<int>(std::floor(std::log10(x)));
  const double f = x / std::pow(10.0, e);
  int m;
  if (round)
    m = f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10;
  else
    m = f <= 1 ? 1 : f <= 2 ? 2 : f <= 5 ? 5 : 10;
  if (m == 10) {
    m = 1;
    ++e;
  }
  return {m, e};
}

// k * step, rounded once: an exact integer times or divided by an exact power of ten.
double tickValue(long long k, const Nice& step) {
  const double km = static_cast<double>(k) * step.mantissa;
  if (step.exponent >= 0) return km * std::pow(10.0, step.exponent);
  return km / std::pow(10.0, -step.exponent);
}

void widen(double& lo, double& hi) {
  if (!std::isfinite(lo) || !std::isfinite(hi) || !std::isfinite(hi - lo)) {
    lo = 0;
    hi = 1;
  }
  if (lo > hi) std::swap(lo, hi);
  if (hi == lo) {
    const double pad = lo != 0 ? std::fabs(lo) * 0.1 : 1.0;
    lo -= pad;
    hi += pad;
  }
}

// Legend row(s) below the title: swatch + label, wrapped at `right`.
// Returns the height used.
double legend(std::string& svg, const std::vector<LegendEntry>& entries, double left, double right, double top) {
  double x = left, y = top;
  bool any = false;
  for (const LegendEntry& e : entries) {
    if (e.label.empty()) continue;
    const double w = 22 + textWidth(e.label) + 14;
    if (any && x + w > right) {
      x = left;
      y += 16;
    }
    any = true;
    appendf(svg, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" stroke-width=\"3\"/>", x, y + 6,
            x + 16, y + 6, htmlEscape(e.color).c_str());
    appendf(svg, "<text x=\"%.1f\" y=\"%.1f\">%s</text>\n", x + 22, y + 10, htmlEscape(e.label).c_str());
    x += w;
  }
  return any ? y - top + 18 : 0;
}

void svgOpen(std::string& svg, int w, int h, const std::string& title) {
  appendf(svg,
          "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"chart\" width=\"%d\" height=\"%d\" viewBox=\"0 0 %d %d\" "
          "font-family=\"sans-serif\" font-size=\"11\">\n",
          w, h, w, h);
  appendf(svg, "<rect x=\"0\" y=\"0\" width=\"%d\" height=\"%d\" fill=\"#ffffff\"/>\n", w, h);
  if (!title.empty())
    appendf(svg, "<text class=\"title\" x=\"%.1f\" y=\"18\" text-anchor=\"middle\" font-size=\"14\">%s</text>\n",
            w / 2.0, htmlEscape(title).c_str());
}

}  // namespace

std::string htmlEscape(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string colorRamp(double t) {
  if (std::isnan(t)) return "#808080";
  static constexpr int kStops[5][3] = {{0x44, 0x01, 0x54}, {0x3b, 0x52, 0x8b}, {0x21, 0x91, 0x8c},
                                       {0x5e, 0xc9, 0x62}, {0xfd, 0xe7, 0x25}};
  const double s = std::clamp(t, 0.0, 1.0) * 4.0;
  const int i = std::min(3, static_cast<int>(s));
  const double f = s - i;
  char buf[8];
  int c[3];
  for (int k = 0; k < 3; ++k)
    c[k] = static_cast<int>(std::lround(kStops[i][k] + f * (kStops[i + 1][k] - kStops[i][k])));
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", c[0], c[1], c[2]);
  return buf;
}

std::string seriesColor(size_t i) {
  static const char* const kTab10[10] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                                         "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};
  return kTab10[i % 10];
}

std::vector<double> niceTicks(double lo, double hi, int target) {
  widen(lo, hi);
  target = std::max(2, target);
  const Nice range = niceNum(hi - lo, false);
  const Nice step = niceNum(range.value() / (target - 1), true);
  const double s = step.value();
  // The tolerance keeps 0.3 / 0.1 = 2.9999999999999996 from adding a tick.
  const long long k0 = static_cast<long long>(std::floor(lo / s + 1e-9));
  const long long k1 = static_cast<long long>(std::ceil(hi / s - 1e-9));
  std::vector<double> ticks;
  for (long long k = k0; k <= k1 && ticks.size() < 1000; ++k) ticks.push_back(tickValue(k, step));
  if (ticks.size() < 2) ticks = {lo, hi};  // unreachable for finite, widened input
  return ticks;
}

std::string formatTick(double v, double step) {
  if (!std::isfinite(v)) return "";
  step = std::fabs(step);
  if (std::fabs(v) < step * 1e-6) v = 0;  // never "-0"
  char buf[64];
  if (!(step > 1e-12) || std::fabs(v) >= 1e15) {
    std::snprintf(buf, sizeof buf, "%g", v);
    if (std::string_view(buf) == "-0") return "0";
    return buf;
  }
  // The fewest decimals that write `step` exactly (0.2 -> 1, 0.25 -> 2, 2.5 -> 1).
  int decimals = 0;
  for (double scaled = step; decimals < 12 && std::fabs(scaled - std::round(scaled)) > 1e-9 * scaled; scaled *= 10)
    ++decimals;
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

std::string svgLinePlot(const PlotSpec& spec) {
  const int W = std::max(200, spec.width), H = std::max(120, spec.height);
  std::string svg;
  svgOpen(svg, W, H, spec.title);

  std::vector<LegendEntry> entries;
  for (size_t i = 0; i < spec.series.size(); ++i) {
    const Series& s = spec.series[i];
    entries.push_back({s.name, s.color.empty() ? seriesColor(i) : s.color});
  }
  const double left = 58, right = 16;
  double top = spec.title.empty() ? 10 : 28;
  top += legend(svg, entries, left, W - right, top);
  top += 6;
  const double bottom = spec.x_label.empty() ? 24 : 38;
  const double pw = W - left - right, ph = std::max(20.0, H - top - bottom);

  // Which x a point has: x[i], or i; NaN when it is a gap.
  auto xAt = [&](size_t i) -> double {
    if (spec.x.empty()) return static_cast<double>(i);
    return i < spec.x.size() && std::isfinite(spec.x[i]) ? spec.x[i] : NAN;
  };

  // Data ranges.
  double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
  for (const Series& s : spec.series) {
    for (size_t i = 0; i < s.y.size(); ++i) {
      const double x = xAt(i);
      if (!std::isfinite(x) || !std::isfinite(s.y[i])) continue;
      xlo = std::min(xlo, x);
      xhi = std::max(xhi, x);
      ylo = std::min(ylo, s.y[i]);
      yhi = std::max(yhi, s.y[i]);
    }
  }
  for (const auto& [v, label] : spec.h_lines) {
    if (!std::isfinite(v)) continue;
    ylo = std::min(ylo, v);
    yhi = std::max(yhi, v);
  }
  if (!(xlo <= xhi)) {  // no finite point: the x extent of the data, or [0, 1]
    xlo = 0;
    xhi = 1;
  }
  const bool fix_lo = std::isfinite(spec.y_min), fix_hi = std::isfinite(spec.y_max);
  const bool both_fixed_ok = !(fix_lo && fix_hi) || spec.y_max > spec.y_min;
  if (both_fixed_ok && fix_lo) ylo = spec.y_min;
  if (both_fixed_ok && fix_hi) yhi = spec.y_max;
  if (!(ylo <= yhi)) {  // no data, or one fixed bound on the wrong side of all of it
    if (both_fixed_ok && fix_lo) yhi = ylo;
    else if (both_fixed_ok && fix_hi) ylo = yhi;
  }

  // x is tight (the data's extent, ticks inside it: a route has no natural
  // round end), y is loose (nice bounds around the data) unless fixed.
  const std::vector<double> xt = niceTicks(xlo, xhi, std::max(2, static_cast<int>(pw / 90)));
  const double xa = xhi > xlo ? xlo : xt.front(), xb = xhi > xlo ? xhi : xt.back();
  std::vector<double> yt = niceTicks(ylo, yhi, std::max(2, static_cast<int>(ph / 45)));
  double ya = yt.front(), yb = yt.back();
  if (both_fixed_ok && fix_lo) ya = spec.y_min;
  if (both_fixed_ok && fix_hi) yb = spec.y_max;
  if (!(yb > ya)) {
    widen(ya, yb);
    yt = niceTicks(ya, yb, 3);
  }
  const double xstep = xt.size() > 1 ? xt[1] - xt[0] : 1, ystep = yt.size() > 1 ? yt[1] - yt[0] : 1;

  auto px = [&](double x) { return pix((x - xa) / (xb - xa) * pw); };
  auto py = [&](double y) { return pix(ph - (y - ya) / (yb - ya) * ph); };

  // Grid and tick labels.
  const double eps_y = (yb - ya) * 1e-9, eps_x = (xb - xa) * 1e-9;
  svg += "<g stroke=\"#e4e4e4\" stroke-width=\"1\">\n";
  for (double y : yt)
    if (y >= ya - eps_y && y <= yb + eps_y)
      appendf(svg, "<line x1=\"%.1f\" y1=\"%.2f\" x2=\"%.1f\" y2=\"%.2f\"/>", left, top + py(y), left + pw,
              top + py(y));
  for (double x : xt)
    if (x >= xa - eps_x && x <= xb + eps_x)
      appendf(svg, "<line x1=\"%.2f\" y1=\"%.1f\" x2=\"%.2f\" y2=\"%.1f\"/>", left + px(x), top, left + px(x),
              top + ph);
  svg += "\n</g>\n<g fill=\"#333333\">\n";
  for (double y : yt)
    if (y >= ya - eps_y && y <= yb + eps_y)
      appendf(svg, "<text class=\"ytick\" x=\"%.1f\" y=\"%.2f\" text-anchor=\"end\">%s</text>", left - 5,
              top + py(y) + 4, formatTick(y, ystep).c_str());
  for (double x : xt)
    if (x >= xa - eps_x && x <= xb + eps_x)
      appendf(svg, "<text class=\"xtick\" x=\"%.2f\" y=\"%.1f\" text-anchor=\"middle\">%s</text>", left + px(x),
              top + ph + 14, formatTick(x, xstep).c_str());
  svg += "\n</g>\n";
  appendf(svg, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" stroke=\"#444444\"/>\n", left,
          top, pw, ph);
  if (!spec.x_label.empty())
    appendf(svg, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%s</text>\n", left + pw / 2, top + ph + 30,
            htmlEscape(spec.x_label).c_str());
  if (!spec.y_label.empty())
    appendf(svg, "<text transform=\"translate(13,%.1f) rotate(-90)\" text-anchor=\"middle\">%s</text>\n",
            top + ph / 2, htmlEscape(spec.y_label).c_str());

  // Reference lines, under the data.
  for (const auto& [v, label] : spec.h_lines) {
    if (!std::isfinite(v) || v < ya - eps_y || v > yb + eps_y) continue;
    appendf(svg,
            "<line class=\"hline\" x1=\"%.1f\" y1=\"%.2f\" x2=\"%.1f\" y2=\"%.2f\" stroke=\"#c0392b\" "
            "stroke-dasharray=\"6 4\"/>",
            left, top + py(v), left + pw, top + py(v));
    appendf(svg, "<text x=\"%.1f\" y=\"%.2f\" text-anchor=\"end\" fill=\"#c0392b\">%s</text>\n", left + pw - 4,
            top + py(v) - 4, htmlEscape(label).c_str());
  }

  // Data, clipped to the plot area by a nested viewport.
  appendf(svg, "<svg x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" overflow=\"hidden\">\n", left, top, pw, ph);
  for (size_t si = 0; si < spec.series.size(); ++si) {
    const Series& s = spec.series[si];
    const std::string color = htmlEscape(s.color.empty() ? seriesColor(si) : s.color);
    svg += "<g class=\"series\">";
    if (!s.name.empty()) svg += "<title>" + htmlEscape(s.name) + "</title>";
    size_t i = 0;
    while (i < s.y.size()) {
      // One run of consecutive finite points.
      while (i < s.y.size() && !(std::isfinite(s.y[i]) && std::isfinite(xAt(i)))) ++i;
      const size_t begin = i;
      while (i < s.y.size() && std::isfinite(s.y[i]) && std::isfinite(xAt(i))) ++i;
      if (i - begin == 1) {
        appendf(svg, "<circle cx=\"%.2f\" cy=\"%.2f\" r=\"2.5\" fill=\"%s\"/>", px(xAt(begin)), py(s.y[begin]),
                color.c_str());
      } else if (i - begin > 1) {
        appendf(svg, "<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"1.5\" stroke-linejoin=\"round\" points=\"",
                color.c_str());
        for (size_t k = begin; k < i; ++k)
          appendf(svg, k == begin ? "%.2f,%.2f" : " %.2f,%.2f", px(xAt(k)), py(s.y[k]));
        svg += "\"/>";
      }
    }
    svg += "</g>\n";
  }
  svg += "</svg>\n</svg>\n";
  return svg;
}

std::string svgMap(const MapSpec& spec) {
  const int W = std::max(200, spec.width), H = std::max(200, spec.height);
  std::string svg;
  svgOpen(svg, W, H, spec.title);
  const double margin = 8;
  double top = spec.title.empty() ? margin : 28;
  top += legend(svg, spec.legend, margin, W - margin, top);
  const double bottom = spec.units.empty() ? margin : 30;
  const double aw = W - 2 * margin, ah = std::max(20.0, H - top - bottom);

  double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
  for (const MapLine& l : spec.lines) {
    for (const auto& [x, y] : l.pts) {
      if (!std::isfinite(x) || !std::isfinite(y)) continue;
      xlo = std::min(xlo, x);
      xhi = std::max(xhi, x);
      ylo = std::min(ylo, y);
      yhi = std::max(yhi, y);
    }
  }
  if (!(xlo <= xhi)) {
    appendf(svg, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" fill=\"#888888\">no data</text>\n</svg>\n",
            W / 2.0, top + ah / 2);
    return svg;
  }
  const double dx = xhi - xlo, dy = yhi - ylo;
  double scale = std::min(dx > 0 ? aw / dx : INFINITY, dy > 0 ? ah / dy : INFINITY);
  if (!std::isfinite(scale) || !(scale > 0)) scale = 1;  // a single point
  const double ox = margin + (aw - dx * scale) / 2, oy = top + (ah - dy * scale) / 2;
  auto px = [&](double x) { return pix(ox + (x - xlo) * scale); };
  auto py = [&](double y) { return pix(oy + (yhi - y) * scale); };  // north up

  svg += "<g fill=\"none\" stroke-linecap=\"round\" stroke-linejoin=\"round\">\n";
  for (const MapLine& l : spec.lines) {
    const std::string color = htmlEscape(l.color.empty() ? "#555555" : l.color);
    const double width = l.width > 0 && std::isfinite(l.width) ? l.width : 1.0;
    size_t i = 0;
    auto finite = [&](size_t k) { return std::isfinite(l.pts[k].first) && std::isfinite(l.pts[k].second); };
    while (i < l.pts.size()) {
      while (i < l.pts.size() && !finite(i)) ++i;
      const size_t begin = i;
      while (i < l.pts.size() && finite(i)) ++i;
      if (i - begin == 1) {
        appendf(svg, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.2f\" fill=\"%s\"/>\n", px(l.pts[begin].first),
                py(l.pts[begin].second), std::max(1.0, width / 2), color.c_str());
      } else if (i - begin > 1) {
        appendf(svg, "<polyline stroke=\"%s\" stroke-width=\"%.2f\" points=\"", color.c_str(), width);
        for (size_t k = begin; k < i; ++k)
          appendf(svg, k == begin ? "%.1f,%.1f" : " %.1f,%.1f", px(l.pts[k].first), py(l.pts[k].second));
        svg += "\"/>\n";
      }
    }
  }
  svg += "</g>\n";

  if (!spec.units.empty()) {
    // About a fifth of the drawing width, rounded down to {1, 2, 5} x 10^n units.
    const double want = aw / 5 / scale;
    Nice n = niceNum(want, false);
    if (n.value() > want) n = n.mantissa == 1 ? Nice{5, n.exponent - 1} : Nice{n.mantissa == 5 ? 2 : 1, n.exponent};
    const double len = tickValue(1, n), bar = len * scale, y = H - 12.0;
    appendf(svg,
            "<path d=\"M%.1f %.1fV%.1fH%.1fV%.1f\" fill=\"none\" stroke=\"#222222\" stroke-width=\"1.5\"/>"
            "<text x=\"%.1f\" y=\"%.1f\">%s %s</text>\n",
            margin, y - 5, y, margin + bar, y - 5, margin + bar + 6, y + 3,
            formatTick(len, len).c_str(), htmlEscape(spec.units).c_str());
  }
  svg += "</svg>\n";
  return svg;
}

// ---- HtmlPage ---------------------------------------------------------------

HtmlPage::HtmlPage(std::string title) : title_(std::move(title)) {}

HtmlPage& HtmlPage::h2(std::string_view text) {
  body_ += "<h2>" + htmlEscape(text) + "</h2>\n";
  return *this;
}

HtmlPage& HtmlPage::paragraph(std::string_view text) {
  body_ += "<p>" + htmlEscape(text) + "</p>\n";
  return *this;
}

HtmlPage& HtmlPage::table(const std::vector<std::vector<std::string>>& rows, bool header) {
  if (rows.empty()) return *this;
  body_ += "<table>\n";
  for (size_t r = 0; r < rows.size(); ++r) {
    const bool th = header && r == 0;
    if (th) body_ += "<thead>";
    if (r == (header ? 1u : 0u)) body_ += "<tbody>\n";
    body_ += "<tr>";
    for (const std::string& cell : rows[r])
      body_ += (th ? "<th>" : "<td>") + htmlEscape(cell) + (th ? "</th>" : "</td>");
    body_ += "</tr>";
    if (th) body_ += "</thead>";
    body_ += "\n";
  }
  if (rows.size() > (header ? 1u : 0u)) body_ += "</tbody>\n";
  body_ += "</table>\n";
  return *this;
}

HtmlPage& HtmlPage::raw(std::string_view markup) {
  body_ += markup;
  body_ += "\n";
  return *this;
}

HtmlPage& HtmlPage::imageGrid(const std::vector<Figure>& figures, int columns) {
  appendf(body_, "<div class=\"grid\" style=\"grid-template-columns:repeat(%d,1fr)\">\n", std::max(1, columns));
  for (const Figure& f : figures) {
    const std::string src = htmlEscape(f.src), cap = htmlEscape(f.caption);
    body_ += "<figure><a href=\"" + src + "\"><img src=\"" + src + "\" alt=\"" + cap + "\" loading=\"lazy\"/></a>";
    if (!f.caption.empty()) body_ += "<figcaption>" + cap + "</figcaption>";
    body_ += "</figure>\n";
  }
  body_ += "</div>\n";
  return *this;
}

std::string HtmlPage::str() const {
  // Polyglot markup (void elements closed with "/>"): valid HTML5 and
  // well-formed XML, so inlined SVG and the tests' XML check both work.
  std::string out =
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"/>\n<title>" + htmlEscape(title_) +
      "</title>\n<style>\n"
      "body{font:14px/1.4 sans-serif;margin:1.5em;color:#222;background:#fafafa}\n"
      "table{border-collapse:collapse;margin:.5em 0}\n"
      "th,td{border:1px solid #ccc;padding:2px 8px;text-align:right}\n"
      "th{background:#eee}\n"
      "td:first-child,th:first-child{text-align:left}\n"
      ".grid{display:grid;gap:6px;margin:.5em 0}\n"
      ".grid figure{margin:0}\n"
      ".grid img{width:100%;display:block}\n"
      "figcaption{font-size:12px;color:#555}\n"
      "svg.chart{display:block;margin:.5em 0;max-width:100%;height:auto}\n"
      "</style></head>\n<body>\n<h1>" +
      htmlEscape(title_) + "</h1>\n";
  out += body_;
  out += "</body></html>\n";
  return out;
}

bool HtmlPage::write(const std::string& path, std::string& err) const {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) {
    err = "cannot open " + path + " for writing";
    return false;
  }
  const std::string s = str();
  f.write(s.data(), static_cast<std::streamsize>(s.size()));
  f.close();
  if (!f) {
    err = "cannot write " + path;
    return false;
  }
  return true;
}

}  // namespace blvd::cli
