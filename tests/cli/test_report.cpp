// SVG plots, SVG map, HTML page (sdk/cli/report.h). The generated files are
// also written to <build>/tests/cli/report/ for a human to look at.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "cli/report.h"

namespace blvd::cli {
namespace {

// ---- a tiny XML well-formedness checker -------------------------------------
// Elements nest and close in order, one root, attributes quoted and unique,
// no '<' in text or attribute values, every '&' starts a known or numeric
// entity. Comments, <?...?> and <!DOCTYPE ...> are skipped. Returns "" when
// well-formed, else what is wrong and where.

bool isNameStart(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_' || c == ':'; }
bool isNameChar(char c) {
  return isNameStart(c) || std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '.';
}

std::string checkEntities(std::string_view t, size_t at) {
  for (size_t j = 0; j < t.size(); ++j) {
    if (t[j] == '<') return "'<' in text or attribute at " + std::to_string(at + j);
    if (t[j] != '&') continue;
    const size_t e = t.find(';', j);
    if (e == std::string_view::npos) return "unterminated entity at " + std::to_string(at + j);
    const std::string_view name = t.substr(j + 1, e - j - 1);
    bool ok = name == "amp" || name == "lt" || name == "gt" || name == "quot" || name == "apos";
    if (!ok && name.size() > 1 && name[0] == '#') {
      const bool hex = name[1] == 'x';
      ok = name.size() > (hex ? 2u : 1u);
      for (size_t k = hex ? 2 : 1; k < name.size(); ++k) {
        const auto c = static_cast<unsigned char>(name[k]);
        ok = ok && (hex ? std::isxdigit(c) : std::isdigit(c));
      }
    }
    if (!ok) return "bad entity '&" + std::string(name) + ";' at " + std::to_string(at + j);
    j = e;
  }
  return "";
}

std::string xmlCheck(std::string_view s) {
  std::vector<std::string> stack;
  int roots = 0;
  size_t i = 0;
  auto skipWs = [&] {
    while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
  };
  while (i < s.size()) {
    if (s[i] != '<') {
      const size_t j = std::min(s.find('<', i), s.size());
      const std::string_view text = s.substr(i, j - i);
      if (stack.empty() && text.find_first_not_of(" \t\r\n") != std::string_view::npos)
        return "text outside the root at " + std::to_string(i);
      if (auto e = checkEntities(text, i); !e.empty()) return e;
      i = j;
      continue;
    }
    if (s.substr(i, 4) == "<!--") {
      const size_t e = s.find("-->", i + 4);
      if (e == std::string_view::npos) return "unterminated comment";
      i = e + 3;
      continue;
    }
    if (s.substr(i, 2) == "<?" || s.substr(i, 9) == "<!DOCTYPE") {
      if (roots > 0 || !stack.empty()) return "declaration inside the document at " + std::to_string(i);
      const size_t e = s.find('>', i);
      if (e == std::string_view::npos) return "unterminated declaration";
      i = e + 1;
      continue;
    }
    if (s.substr(i, 2) == "</") {
      size_t j = i + 2;
      while (j < s.size() && isNameChar(s[j])) ++j;
      const std::string name(s.substr(i + 2, j - i - 2));
      i = j;
      skipWs();
      if (i >= s.size() || s[i] != '>') return "bad end tag </" + name + " at " + std::to_string(j);
      ++i;
      if (stack.empty() || stack.back() != name)
        return "</" + name + "> closes <" + (stack.empty() ? std::string("nothing") : stack.back()) + "> at " +
               std::to_string(i);
      stack.pop_back();
      continue;
    }
    // Start tag.
    const size_t tag_at = i;
    ++i;
    if (i >= s.size() || !isNameStart(s[i])) return "bad tag start at " + std::to_string(tag_at);
    size_t j = i;
    while (j < s.size() && isNameChar(s[j])) ++j;
    const std::string name(s.substr(i, j - i));
    i = j;
    if (stack.empty() && roots > 0) return "second root <" + name + "> at " + std::to_string(tag_at);
    std::set<std::string> attrs;
    for (;;) {
      const size_t before = i;
      skipWs();
      if (i >= s.size()) return "unterminated tag <" + name;
      if (s.substr(i, 2) == "/>") {
        i += 2;
        if (stack.empty()) ++roots;
        break;
      }
      if (s[i] == '>') {
        ++i;
        if (stack.empty()) ++roots;
        stack.push_back(name);
        break;
      }
      if (i == before) return "no space before attribute in <" + name + " at " + std::to_string(i);
      size_t k = i;
      if (!isNameStart(s[k])) return "bad attribute in <" + name + " at " + std::to_string(i);
      while (k < s.size() && isNameChar(s[k])) ++k;
      const std::string attr(s.substr(i, k - i));
      if (!attrs.insert(attr).second) return "duplicate attribute " + attr + " in <" + name;
      i = k;
      skipWs();
      if (i >= s.size() || s[i] != '=') return "attribute " + attr + " without value in <" + name;
      ++i;
      skipWs();
      if (i >= s.size() || (s[i] != '"' && s[i] != '\'')) return "unquoted attribute " + attr + " in <" + name;
      const char q = s[i];
      const size_t e = s.find(q, i + 1);
      if (e == std::string_view::npos) return "unterminated attribute " + attr;
      if (auto err = checkEntities(s.substr(i + 1, e - i - 1), i + 1); !err.empty()) return err;
      i = e + 1;
    }
  }
  if (!stack.empty()) return "<" + stack.back() + "> never closed";
  if (roots != 1) return "no root element";
  return "";
}

TEST(XmlCheck, TheCheckerItselfCatchesMistakes) {
  EXPECT_EQ(xmlCheck("<a x=\"1\"><b/>t &amp; &#39; &#x27;</a>"), "");
  EXPECT_EQ(xmlCheck("<!DOCTYPE html>\n<a><!-- <b> --></a>\n"), "");
  EXPECT_NE(xmlCheck("<a><b></a></b>"), "");
  EXPECT_NE(xmlCheck("<a>"), "");
  EXPECT_NE(xmlCheck("<a>x < y</a>"), "");
  EXPECT_NE(xmlCheck("<a>AT&T</a>"), "");
  EXPECT_NE(xmlCheck("<a x=1/>"), "");
  EXPECT_NE(xmlCheck("<a x=\"1\" x=\"2\"/>"), "");
  EXPECT_NE(xmlCheck("<a x=\"1\"y=\"2\"/>"), "");
  EXPECT_NE(xmlCheck("<a/><b/>"), "");
  EXPECT_NE(xmlCheck("<a t=\"\"\"/>"), "");
}

// ---- helpers ------------------------------------------------------------------

size_t count(std::string_view s, std::string_view what) {
  size_t n = 0;
  for (size_t p = s.find(what); p != std::string_view::npos; p = s.find(what, p + what.size())) ++n;
  return n;
}

struct Point {
  double x, y;
};

// The points of every <polyline>, in order.
std::vector<std::vector<Point>> polylines(const std::string& svg) {
  std::vector<std::vector<Point>> out;
  for (size_t p = svg.find("<polyline"); p != std::string::npos; p = svg.find("<polyline", p + 1)) {
    const size_t a = svg.find("points=\"", p) + 8, b = svg.find('"', a);
    std::vector<Point> pts;
    const std::string list = svg.substr(a, b - a);
    const char* c = list.c_str();
    char* end = nullptr;
    for (;;) {
      const double x = std::strtod(c, &end);
      if (end == c || *end != ',') break;
      c = end + 1;
      const double y = std::strtod(c, &end);
      pts.push_back({x, y});
      c = end;
    }
    out.push_back(pts);
  }
  return out;
}

// The text of every <text class="cls">.
std::vector<std::string> texts(const std::string& svg, const std::string& cls) {
  std::vector<std::string> out;
  const std::string key = "class=\"" + cls + "\"";
  for (size_t p = svg.find(key); p != std::string::npos; p = svg.find(key, p + 1)) {
    const size_t a = svg.find('>', p) + 1, b = svg.find("</text>", a);
    out.push_back(svg.substr(a, b - a));
  }
  return out;
}

// A value is a "round" tick when it is an integer multiple of step = {1, 2, 5} x 10^n.
bool isNiceStep(double step) {
  const double e = std::floor(std::log10(step) + 1e-9);
  const double m = step / std::pow(10.0, e);
  return std::fabs(m - 1) < 1e-9 || std::fabs(m - 2) < 1e-9 || std::fabs(m - 5) < 1e-9;
}

bool noNonFinite(const std::string& svg) {
  return svg.find("nan") == std::string::npos && svg.find("inf") == std::string::npos;
}

std::string outDir() {
  const std::string dir = std::string(BLVD_BINARY_DIR) + "/tests/cli/report";
  ::mkdir((std::string(BLVD_BINARY_DIR) + "/tests").c_str(), 0755);
  ::mkdir((std::string(BLVD_BINARY_DIR) + "/tests/cli").c_str(), 0755);
  ::mkdir(dir.c_str(), 0755);
  return dir;
}

void save(const std::string& name, const std::string& content) {
  std::ofstream(outDir() + "/" + name, std::ios::binary) << content;
}

// ---- escaping and colours -----------------------------------------------------

TEST(Report, HtmlEscape) {
  EXPECT_EQ(htmlEscape("<a & \"b\" 'c'>"), "&lt;a &amp; &quot;b&quot; &#39;c&#39;&gt;");
  EXPECT_EQ(htmlEscape(""), "");
  EXPECT_EQ(htmlEscape("plain 123 é"), "plain 123 é");
  EXPECT_EQ(htmlEscape("&amp;"), "&amp;amp;");
}

TEST(Report, ColorRamp) {
  EXPECT_EQ(colorRamp(0.0), "#440154");
  EXPECT_EQ(colorRamp(0.25), "#3b528b");
  EXPECT_EQ(colorRamp(0.5), "#21918c");
  EXPECT_EQ(colorRamp(0.75), "#5ec962");
  EXPECT_EQ(colorRamp(1.0), "#fde725");
  EXPECT_EQ(colorRamp(-3.0), "#440154");
  EXPECT_EQ(colorRamp(7.0), "#fde725");
  EXPECT_EQ(colorRamp(INFINITY), "#fde725");
  EXPECT_EQ(colorRamp(NAN), "#808080");
  // Halfway between the first two stops: the rounded channel means.
  EXPECT_EQ(colorRamp(0.125), "#402a70");
  // Lightness grows along the ramp.
  double prev = -1;
  for (int i = 0; i <= 20; ++i) {
    const std::string c = colorRamp(i / 20.0);
    ASSERT_EQ(c.size(), 7u);
    const long v = std::strtol(c.c_str() + 1, nullptr, 16);
    const double y = 0.2126 * ((v >> 16) & 255) + 0.7152 * ((v >> 8) & 255) + 0.0722 * (v & 255);
    EXPECT_GT(y, prev) << c;
    prev = y;
  }
}

// ---- ticks --------------------------------------------------------------------

TEST(Report, NiceTicksAreRoundAndCoverTheRange) {
  const double ranges[][2] = {{0, 0.93},   {0.81, 0.97}, {0, 199},      {-3.7, 12.2}, {1e-4, 3e-4},
                              {12345, 12400}, {0.3, 0.7}, {-250, -10},  {0, 1},       {16.9, 17.4}};
  for (const auto& r : ranges) {
    const std::vector<double> t = niceTicks(r[0], r[1], 6);
    ASSERT_GE(t.size(), 2u) << r[0] << ".." << r[1];
    EXPECT_LE(t.size(), 13u) << r[0] << ".." << r[1];
    const double step = t[1] - t[0];
    EXPECT_TRUE(isNiceStep(step)) << step;
    EXPECT_LE(t.front(), r[0] + 1e-12);
    EXPECT_GE(t.back(), r[1] - 1e-12);
    EXPECT_GT(t.front(), r[0] - step);  // loose, but by less than a step
    EXPECT_LT(t.back(), r[1] + step);
    for (size_t i = 0; i < t.size(); ++i) {
      EXPECT_NEAR(t[i] - t[0], i * step, step * 1e-9);
      // Exactly the double of its decimal label: 0.3, not 0.30000000000000004.
      const std::string label = formatTick(t[i], step);
      EXPECT_EQ(std::strtod(label.c_str(), nullptr), t[i]) << label;
      EXPECT_NEAR(std::remainder(t[i], step), 0.0, step * 1e-9);
    }
  }
  const auto t = niceTicks(0, 1, 6);
  EXPECT_EQ(t, (std::vector<double>{0, 0.2, 0.4, 0.6, 0.8, 1.0}));
  EXPECT_EQ(niceTicks(0, 199, 8), (std::vector<double>{0, 20, 40, 60, 80, 100, 120, 140, 160, 180, 200}));
  // Degenerate and non-finite ranges are widened, never empty.
  EXPECT_EQ(niceTicks(5, 5, 5), (std::vector<double>{4.4, 4.6, 4.8, 5, 5.2, 5.4, 5.6}));  // from [4.5, 5.5]
  EXPECT_EQ(niceTicks(0, 0, 3), (std::vector<double>{-1, 0, 1}));
  EXPECT_EQ(niceTicks(NAN, 1, 6), t);
  EXPECT_EQ(niceTicks(1, 0, 6), t);  // swapped
}

TEST(Report, FormatTick) {
  EXPECT_EQ(formatTick(0.1 + 0.2, 0.1), "0.3");
  EXPECT_EQ(formatTick(-1e-17, 0.1), "0.0");
  EXPECT_EQ(formatTick(-0.0, 5), "0");
  EXPECT_EQ(formatTick(100, 50), "100");
  EXPECT_EQ(formatTick(0.25, 0.05), "0.25");
  EXPECT_EQ(formatTick(-7.5, 2.5), "-7.5");
  EXPECT_EQ(formatTick(2e-4, 5e-5), "0.00020");
  EXPECT_EQ(formatTick(0.75, 0.25), "0.75");
  EXPECT_EQ(formatTick(1e-7, 1e-7), "0.0000001");
  EXPECT_EQ(formatTick(NAN, 1), "");
}

// ---- line plot ----------------------------------------------------------------

PlotSpec ssimPlot() {
  PlotSpec p;
  p.title = "SSIM along the route";
  p.x_label = "frame";
  p.y_label = "SSIM";
  Series s{"blvd", {}, ""};
  for (int i = 0; i < 50; ++i) s.y.push_back(0.9 + 0.05 * std::sin(i * 0.3));
  p.series.push_back(s);
  p.h_lines.push_back({0.9, "target 0.90"});
  return p;
}

TEST(LinePlot, OnePointPerValueAndWellFormed) {
  const PlotSpec p = ssimPlot();
  const std::string svg = svgLinePlot(p);
  save("plot_ssim.svg", svg);
  EXPECT_EQ(xmlCheck(svg), "");
  EXPECT_TRUE(noNonFinite(svg));
  const auto lines = polylines(svg);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0].size(), 50u);
  // x increases monotonically, y inside the plot area (nested viewport, origin 0).
  for (size_t i = 1; i < lines[0].size(); ++i) EXPECT_GT(lines[0][i].x, lines[0][i - 1].x);
  for (const Point& q : lines[0]) {
    EXPECT_GE(q.y, 0.0);
    EXPECT_GE(q.x, 0.0);
  }
  // Larger value, higher on the page (smaller y).
  const auto& l = lines[0];
  EXPECT_LT(l[5].y, l[0].y);  // sin rises from 0 at i = 0 to ~1 at i = 5
  EXPECT_EQ(count(svg, "class=\"hline\""), 1u);
  EXPECT_NE(svg.find(">target 0.90</text>"), std::string::npos);
  EXPECT_NE(svg.find("<title>blvd</title>"), std::string::npos);
  EXPECT_EQ(count(svg, "<svg"), 2u);  // outer + the clipping viewport
}

TEST(LinePlot, NanGapsSplitLines) {
  PlotSpec p;
  p.series.push_back({"gappy", {1, 2, NAN, 3, 4, 5, NAN, INFINITY, 6}, "#123456"});
  const std::string svg = svgLinePlot(p);
  EXPECT_EQ(xmlCheck(svg), "");
  EXPECT_TRUE(noNonFinite(svg));
  const auto lines = polylines(svg);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0].size(), 2u);
  EXPECT_EQ(lines[1].size(), 3u);
  EXPECT_EQ(count(svg, "<circle"), 1u);  // the lone 6
  EXPECT_EQ(count(svg, "<polyline fill=\"none\" stroke=\"#123456\""), 2u);
  EXPECT_EQ(count(svg, "fill=\"#123456\""), 1u);
}

TEST(LinePlot, ExplicitXWithGaps) {
  PlotSpec p;
  p.x = {0, 10, NAN, 30, 40};  // y[5] has no x: a gap too
  p.series.push_back({"a", {1, 2, 3, 4, 5, 6}, ""});
  const std::string svg = svgLinePlot(p);
  EXPECT_EQ(xmlCheck(svg), "");
  const auto lines = polylines(svg);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0].size(), 2u);
  EXPECT_EQ(lines[1].size(), 2u);
  // Equal x steps, equal pixel steps.
  EXPECT_NEAR(lines[0][1].x - lines[0][0].x, lines[1][1].x - lines[1][0].x, 0.02);
  const auto xt = texts(svg, "xtick");
  EXPECT_EQ(xt.front(), "0");
  EXPECT_EQ(xt.back(), "40");
}

TEST(LinePlot, TickLabelsAreRoundNumbers) {
  PlotSpec p;
  p.width = 640;
  p.height = 280;
  p.series.push_back({"ms", {16.93, 17.41, 17.02, 18.77, 17.5, 16.88}, ""});
  p.series.push_back({"ssim", {0.83, 0.97, 0.91}, ""});
  const std::string svg = svgLinePlot(p);
  EXPECT_EQ(xmlCheck(svg), "");
  for (const char* cls : {"ytick", "xtick"}) {
    const auto labels = texts(svg, cls);
    ASSERT_GE(labels.size(), 2u) << cls;
    std::vector<double> v;
    for (const auto& s : labels) {
      char* end = nullptr;
      v.push_back(std::strtod(s.c_str(), &end));
      EXPECT_EQ(*end, '\0') << s;
    }
    const double step = v[1] - v[0];
    EXPECT_TRUE(isNiceStep(std::fabs(step))) << cls << " step " << step;
    for (size_t i = 0; i < v.size(); ++i) EXPECT_NEAR(v[i], v[0] + i * step, std::fabs(step) * 1e-9) << cls;
    for (double x : v) EXPECT_NEAR(std::remainder(x, step), 0.0, std::fabs(step) * 1e-9) << cls;
  }
  const auto yl = texts(svg, "ytick");
  EXPECT_LE(std::strtod(yl.front().c_str(), nullptr), 0.83);
  EXPECT_GE(std::strtod(yl.back().c_str(), nullptr), 18.77);
  // Two series, two default colours, two legend entries.
  EXPECT_NE(svg.find(seriesColor(0)), std::string::npos);
  EXPECT_NE(svg.find(seriesColor(1)), std::string::npos);
  EXPECT_NE(svg.find(">ms</text>"), std::string::npos);
  EXPECT_NE(svg.find(">ssim</text>"), std::string::npos);
}

TEST(LinePlot, DegenerateInputsStayWellFormed) {
  std::vector<PlotSpec> specs(6);
  specs[0].title = "nothing";                                 // no series
  specs[1].series.push_back({"empty", {}, ""});              // empty series
  specs[2].series.push_back({"one", {0.5}, ""});             // a single point
  specs[3].series.push_back({"const", {1, 1, 1, 1}, ""});    // constant
  specs[4].series.push_back({"gaps", {NAN, NAN}, ""});       // nothing finite
  specs[5].series.push_back({"huge", {1e300, -1e300, 0}, ""});
  specs[5].y_min = 0;
  specs[5].y_max = 1;
  specs[5].width = specs[5].height = 1;  // raised to the minimum
  for (size_t i = 0; i < specs.size(); ++i) {
    const std::string svg = svgLinePlot(specs[i]);
    EXPECT_EQ(xmlCheck(svg), "") << i;
    EXPECT_TRUE(noNonFinite(svg)) << i << svg;
    EXPECT_GE(texts(svg, "ytick").size(), 2u) << i;
  }
  const std::string one = svgLinePlot(specs[2]);
  EXPECT_EQ(polylines(one).size(), 0u);
  EXPECT_EQ(count(one, "<circle"), 1u);
  const std::string flat = svgLinePlot(specs[3]);
  const auto l = polylines(flat);
  ASSERT_EQ(l.size(), 1u);
  ASSERT_EQ(l[0].size(), 4u);
  for (const Point& q : l[0]) EXPECT_EQ(q.y, l[0][0].y);
  const auto yl = texts(flat, "ytick");  // 0.9 .. 1.1 around the constant 1
  EXPECT_LT(std::strtod(yl.front().c_str(), nullptr), 1.0);
  EXPECT_GT(std::strtod(yl.back().c_str(), nullptr), 1.0);
}

TEST(LinePlot, FixedBoundsAndHLines) {
  PlotSpec p;
  p.y_min = 0;
  p.y_max = 1;
  p.height = 300;
  p.series.push_back({"s", {0, 1, 2}, ""});  // 2 lies above the axis: clipped by the viewport
  p.h_lines = {{0.9, "in"}, {1.5, "out of range"}, {NAN, "nan"}};
  const std::string svg = svgLinePlot(p);
  EXPECT_EQ(xmlCheck(svg), "");
  const auto yl = texts(svg, "ytick");
  EXPECT_EQ(yl.front(), "0.0");
  EXPECT_EQ(yl.back(), "1.0");
  EXPECT_EQ(count(svg, "class=\"hline\""), 1u);
  EXPECT_EQ(svg.find("out of range"), std::string::npos);
  const auto l = polylines(svg);
  ASSERT_EQ(l.size(), 1u);
  EXPECT_LT(l[0][2].y, 0.0);  // above the viewport's top
  EXPECT_EQ(l[0][1].y, 0.0);  // y_max at the top edge
}

TEST(LinePlot, TextIsEscaped) {
  PlotSpec p;
  p.title = "<SSIM & \"PSNR\">";
  p.x_label = "x < 1";
  p.y_label = "y & z";
  p.series.push_back({"a'b", {1, 2}, "red\" onload=\"alert(1)"});
  p.h_lines.push_back({1.5, "<budget>"});
  const std::string svg = svgLinePlot(p);
  EXPECT_EQ(xmlCheck(svg), "");
  EXPECT_NE(svg.find("&lt;SSIM &amp; &quot;PSNR&quot;&gt;"), std::string::npos);
  EXPECT_NE(svg.find("x &lt; 1"), std::string::npos);
  EXPECT_NE(svg.find("y &amp; z"), std::string::npos);
  EXPECT_NE(svg.find("a&#39;b"), std::string::npos);
  EXPECT_NE(svg.find("&lt;budget&gt;"), std::string::npos);
  EXPECT_EQ(svg.find("onload=\""), std::string::npos);
  // Labels longer than any internal buffer are written whole.
  p.series[0].name = std::string(3000, '&');
  const std::string long_svg = svgLinePlot(p);
  EXPECT_EQ(xmlCheck(long_svg), "");
  EXPECT_EQ(count(long_svg, "&amp;"), 2u * 3000 + 2);  // legend + <title>, plus title and y label
}

// ---- map ----------------------------------------------------------------------

TEST(Map, FitsNorthUpWithoutDistortion) {
  MapSpec m;
  m.title = "Street graph: layers per cell";
  m.width = 400;
  m.height = 400;
  m.lines.push_back({{{0, 0}, {0, 100}}, "#ff0000", 2});      // south to north
  m.lines.push_back({{{0, 0}, {100, 0}}, colorRamp(0.5), 1});  // west to east
  m.lines.push_back({{{100, 100}, {NAN, 0}, {50, 50}, {60, 60}}, "", 0});
  m.legend = {{"1 layer", colorRamp(0)}, {"4 layers", colorRamp(1)}, {"<none>", "#555555"}};
  const std::string svg = svgMap(m);
  save("map.svg", svg);
  EXPECT_EQ(xmlCheck(svg), "");
  EXPECT_TRUE(noNonFinite(svg));
  const auto l = polylines(svg);
  ASSERT_EQ(l.size(), 3u);  // the third line: a lone point (circle), then a run of two
  EXPECT_EQ(count(svg, "<circle"), 1u);
  // North up: the northern end is higher on the page.
  EXPECT_LT(l[0][1].y, l[0][0].y);
  EXPECT_NEAR(l[0][1].x, l[0][0].x, 1e-9);
  // East right, and the same scale on both axes.
  EXPECT_GT(l[1][1].x, l[1][0].x);
  EXPECT_NEAR(l[1][1].x - l[1][0].x, l[0][0].y - l[0][1].y, 0.11);
  EXPECT_NE(svg.find("&lt;none&gt;"), std::string::npos);
  EXPECT_NE(svg.find(" m</text>"), std::string::npos);  // scale bar
  EXPECT_NE(svg.find("stroke-width=\"1.00\""), std::string::npos);  // width 0 means 1
}

TEST(Map, WideExtentIsCentredAndScaleBarIsRound) {
  MapSpec m;
  m.width = 600;
  m.height = 300;
  m.lines.push_back({{{1000, 5000}, {1800, 5000}, {1800, 5100}}, "", 1.5});
  const std::string svg = svgMap(m);
  EXPECT_EQ(xmlCheck(svg), "");
  const auto l = polylines(svg);
  ASSERT_EQ(l.size(), 1u);
  // Limited by width: 800 units over 584 px, vertically centred.
  EXPECT_NEAR(l[0][1].x - l[0][0].x, 584.0, 0.11);
  const size_t p = svg.rfind("<text"), a = svg.find('>', p) + 1;
  const std::string bar = svg.substr(a, svg.find("</text>", a) - a);  // e.g. "100 m"
  const double len = std::strtod(bar.c_str(), nullptr);
  EXPECT_TRUE(isNiceStep(len)) << bar;
  EXPECT_LE(len, 800 / 5.0 * 1.0001);
}

TEST(Map, EmptyAndSinglePoint) {
  MapSpec empty;
  empty.title = "nothing";
  const std::string e = svgMap(empty);
  EXPECT_EQ(xmlCheck(e), "");
  EXPECT_NE(e.find("no data"), std::string::npos);
  MapSpec one;
  one.units = "";
  one.lines.push_back({{{3, 4}}, "#000000", 4});
  const std::string o = svgMap(one);
  EXPECT_EQ(xmlCheck(o), "");
  EXPECT_TRUE(noNonFinite(o));
  EXPECT_EQ(count(o, "<circle"), 1u);
}

// ---- HTML ---------------------------------------------------------------------

TEST(Html, PageIsSelfContainedAndWellFormed) {
  HtmlPage page("blvd bench <route> & co");
  page.h2("Summary")
      .paragraph("Median speed-up 17.2x & SSIM 0.93 <target 0.90>")
      .table({{"mode", "frame ms p50", "SSIM p50"}, {"full", "120.5", "1"}, {"blvd", "7.0", "0.93"}, {"ragged"}})
      .raw(svgLinePlot(ssimPlot()))
      .h2("Frames")
      .imageGrid({{"full_0001.png", "full"}, {"blvd_0001.png", "blvd"}, {"diff 0001.png", "diff \"red = bad\""}}, 3)
      .imageGrid({}, 0)
      .table({}, true)
      .table({{"only", "data"}}, false);
  const std::string html = page.str();
  EXPECT_EQ(xmlCheck(html), "");
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_NE(html.find("<title>blvd bench &lt;route&gt; &amp; co</title>"), std::string::npos);
  EXPECT_NE(html.find("<h1>blvd bench &lt;route&gt; &amp; co</h1>"), std::string::npos);
  EXPECT_NE(html.find("17.2x &amp; SSIM 0.93 &lt;target 0.90&gt;"), std::string::npos);
  EXPECT_EQ(count(html, "<tr>"), 5u);
  EXPECT_EQ(count(html, "<th>"), 3u);
  EXPECT_EQ(count(html, "<img "), 3u);
  EXPECT_NE(html.find("repeat(3,1fr)"), std::string::npos);
  EXPECT_NE(html.find("repeat(1,1fr)"), std::string::npos);
  EXPECT_NE(html.find("src=\"diff 0001.png\""), std::string::npos);
  EXPECT_NE(html.find("diff &quot;red = bad&quot;"), std::string::npos);
  EXPECT_EQ(count(html, "<polyline"), 1u);
  // Self-contained: nothing fetched from elsewhere.
  EXPECT_EQ(html.find("http://"), html.find("http://www.w3.org/2000/svg"));
  EXPECT_EQ(html.find("https://"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);

  std::string err;
  EXPECT_TRUE(page.write(outDir() + "/index.html", err)) << err;
  std::ifstream in(outDir() + "/index.html", std::ios::binary);
  const std::string back((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(back, html);
  EXPECT_FALSE(page.write(outDir() + "/no/such/dir/index.html", err));
  EXPECT_NE(err.find("no/such/dir"), std::string::npos);
}

}  // namespace
}  // namespace blvd::cli
