#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <sstream>

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

#include "chart.h"
#include "study_test_util.h"
#include "sweep.h"

namespace ravel::studies {
namespace {

// A small well-formedness check of XML: tags nest and close, attributes are quoted,
// '&' starts an entity, nothing follows the root element.
bool well_formed_xml(const std::string& s, std::string* why) {
  std::vector<std::string> stack;
  size_t i = 0;
  bool root_done = false;
  auto fail = [&](const std::string& w) {
    *why = w + " at offset " + std::to_string(i);
    return false;
  };
  while (i < s.size()) {
    if (s[i] != '<') {
      if (s[i] == '&') {
        const size_t semi = s.find(';', i);
        const std::string ent = semi == std::string::npos ? "" : s.substr(i, semi - i + 1);
        if (ent != "&amp;" && ent != "&lt;" && ent != "&gt;" && ent != "&quot;" && ent != "&apos;")
          return fail("bad entity");
      }
      if (root_done && !std::isspace(static_cast<unsigned char>(s[i]))) return fail("text after the root");
      ++i;
      continue;
    }
    if (s.compare(i, 5, "<?xml") == 0) {
      i = s.find("?>", i);
      if (i == std::string::npos) return fail("unterminated declaration");
      i += 2;
      continue;
    }
    if (s.compare(i, 4, "<!--") == 0) {
      i = s.find("-->", i);
      if (i == std::string::npos) return fail("unterminated comment");
      i += 3;
      continue;
    }
    const size_t end = s.find('>', i);
    if (end == std::string::npos) return fail("unterminated tag");
    std::string tag = s.substr(i + 1, end - i - 1);
    // Quotes must balance inside the tag.
    size_t quotes = std::count(tag.begin(), tag.end(), '"');
    if (quotes % 2) return fail("unbalanced quotes");
    if (tag.find('<') != std::string::npos) return fail("'<' inside a tag");
    if (!tag.empty() && tag[0] == '/') {
      const std::string name = tag.substr(1);
      if (stack.empty() || stack.back() != name) return fail("mismatched </" + name + ">");
      stack.pop_back();
      if (stack.empty()) root_done = true;
    } else {
      if (root_done) return fail("second root element");
      const bool self = !tag.empty() && tag.back() == '/';
      const std::string name = tag.substr(0, tag.find_first_of(" \t\n/"));
      if (name.empty()) return fail("empty tag name");
      if (!self)
        stack.push_back(name);
      else if (stack.empty())
        root_done = true;
    }
    i = end + 1;
  }
  if (!stack.empty()) return fail("unclosed <" + stack.back() + ">");
  return root_done || fail("no root element");
}

Chart sample_chart() {
  Chart c;
  c.title = "Energy absorbed vs impact velocity <test & check>";
  c.x = {"impact velocity", "m/s"};
  c.y = {"energy absorbed", "J"};
  c.series.push_back({"mu = 0.2", {180, 220, 260, 300}, {31.5, 42.25, 12.125, 18.0}});
  c.series.push_back({"mu = 0", {180, 260, 500}, {-3.75, 7.5, 93.875}, SeriesStyle::line, -1, true});
  return c;
}

TEST(Chart, NiceTicksCoverTheRange) {
  const auto t = nice_ticks(0, 1, 5);
  ASSERT_EQ(t.size(), 6u);
  EXPECT_DOUBLE_EQ(t[1], 0.2);
  const auto u = nice_ticks(180, 500, 6);
  EXPECT_GE(u.front(), 180);
  EXPECT_LE(u.back(), 500);
  EXPECT_EQ(tick_label(0.25, 0.05), "0.25");
  EXPECT_EQ(tick_label(300, 50), "300");
  double x0, x1, y0, y1;
  chart_ranges(sample_chart(), &x0, &x1, &y0, &y1);
  EXPECT_LE(x0, 180);
  EXPECT_GE(x1, 500);
  EXPECT_LE(y0, -3.75);
  EXPECT_GE(y1, 93.875);
}

TEST(Chart, SvgParsesAndCarriesTheDataExtremes) {
  const std::string svg = chart_svg(sample_chart());
  std::string why;
  EXPECT_TRUE(well_formed_xml(svg, &why)) << why;
  EXPECT_NE(svg.find("&lt;test &amp; check&gt;"), std::string::npos) << "title escaped";
  // Every number of every series, the extremes included, is in the file.
  for (const char* v : {"180,31.5", "300,18", "500,93.875", "180,-3.75", "260,12.125"})
    EXPECT_NE(svg.find(v), std::string::npos) << v;
  // Axis titles with units, legend entries.
  for (const char* t : {"impact velocity (m/s)", "energy absorbed (J)", "mu = 0.2", "mu = 0"})
    EXPECT_NE(svg.find(t), std::string::npos) << t;
  // Tick labels: y from 0 to 80 in steps of 20 inside the range [-4, 94] that holds the data.
  for (const char* t : {">0<", ">20<", ">80<", ">200<", ">500<"}) EXPECT_NE(svg.find(t), std::string::npos) << t;
}

TEST(Chart, PngIsAValidImageAndNotBlank) {
  const int w = 600, h = 400;
  const auto rgb = chart_rgb(sample_chart(), w, h);
  ASSERT_EQ(rgb.size(), size_t(w) * h * 3);
  const auto png = png_bytes(rgb, w, h);
  int pw = 0, ph = 0, n = 0;
  unsigned char* px = stbi_load_from_memory(png.data(), int(png.size()), &pw, &ph, &n, 3);
  ASSERT_NE(px, nullptr);
  EXPECT_EQ(pw, w);
  EXPECT_EQ(ph, h);
  long non_white = 0, series0 = 0, series1 = 0;
  const Rgb c0 = palette(0), c1 = palette(1);
  for (int i = 0; i < w * h; ++i) {
    const unsigned char* p = px + 3 * i;
    non_white += !(p[0] > 250 && p[1] > 250 && p[2] > 250);
    series0 += std::abs(p[0] - c0[0]) + std::abs(p[1] - c0[1]) + std::abs(p[2] - c0[2]) < 30;
    series1 += std::abs(p[0] - c1[0]) + std::abs(p[1] - c1[1]) + std::abs(p[2] - c1[2]) < 30;
  }
  stbi_image_free(px);
  EXPECT_GT(non_white, w * h / 100) << "axes, text and data should cover > 1 % of the image";
  EXPECT_GT(series0, 50) << "first series not drawn";
  EXPECT_GT(series1, 50) << "second series not drawn";
}

TEST(Chart, WriteChartPutsTheCsvBesideTheImages) {
  const std::string dir = testing::scratch_dir();
  write_chart(sample_chart(), dir + "/energy");
  for (const char* ext : {".csv", ".svg", ".png"}) EXPECT_TRUE(std::filesystem::exists(dir + "/energy" + ext)) << ext;
  const Csv csv = parse_csv(read_text_file(dir + "/energy.csv"));
  EXPECT_EQ(csv.header, (std::vector<std::string>{"series", "impact velocity (m/s)", "energy absorbed (J)"}));
  ASSERT_EQ(csv.rows.size(), 7u);
  EXPECT_EQ(csv.rows[6][0], "mu = 0");
  EXPECT_DOUBLE_EQ(std::stod(csv.rows[6][2]), 93.875);
}

TEST(Chart, EmptyChartDrawsAxesOnly) {
  Chart c;
  c.title = "nothing";
  EXPECT_EQ(finite_point_count(c), 0);
  std::string why;
  EXPECT_TRUE(well_formed_xml(chart_svg(c), &why)) << why;
}

// Records every text call with its extent, as the PNG and SVG painters would draw it.
class TextExtents : public Painter {
 public:
  struct Box {
    std::string s;
    double x0, x1;
  };
  std::vector<Box> boxes;
  void line(double, double, double, double, Rgb, double, bool) override {}
  void rect_filled(double, double, double, double, Rgb) override {}
  void marker(double, double, double, Rgb) override {}
  void text(double x, double, const std::string& s, double size, Rgb, int align, bool vertical) override {
    if (vertical) return;
    const double w = text_width(s, size), x0 = align == 0 ? x : align == 1 ? x - w / 2 : x - w;
    boxes.push_back({s, x0, x0 + w});
  }
};

// A legend entry too long for the legend's share of the width (at most 35 %) wraps onto
// more lines at spaces, and every line stays inside the chart (the paper's Fig. 16 label
// "sliding model (bracket midpoint; bars: the bracket)" ran off its PNG).
TEST(Chart, LongLegendEntriesWrapInsideTheChart) {
  Chart c;
  c.title = "t";
  Series a{"sliding model (bracket midpoint; bars: the bracket) and then some more words", {0, 1}, {0, 1}};
  Series b{"pin-jointed model", {0, 1}, {1, 0}};
  c.series = {a, b};
  for (double W : {600.0, 900.0, 1350.0}) {
    TextExtents p;
    draw_chart(c, p, 0, 0, W, 600);
    std::string joined;
    int pieces = 0;
    for (const auto& box : p.boxes) {
      EXPECT_LE(box.x1, W) << "'" << box.s << "' runs off a " << W << " px chart";
      EXPECT_GE(box.x0, 0) << box.s;
      if (a.name.find(box.s) != std::string::npos && box.s.size() > 3)
        joined += (joined.empty() ? "" : " ") + box.s, ++pieces;
    }
    EXPECT_EQ(joined, a.name) << "at " << W << " px";  // all of it, in order, nothing lost
    EXPECT_GE(pieces, 2) << "at " << W << " px the long entry did not wrap";
  }
}

// The rotated y title of a short chart (a panel in the app, 150 px high) is longer than the
// chart at the base font: it shrinks to the chart's height and stays inside it. On a chart of
// the default size the same title keeps the base font, centred on the plot.
TEST(Chart, LongYTitleFitsAShortChart) {
  Chart c;
  c.title = "friction work";
  c.x.label = "yarn.friction";
  c.y.label = "friction work up to perforation";
  c.y.unit = "J";
  Series s;
  s.x = {0, 0.5, 1};
  s.y = {0, 31, 5};
  c.series.push_back(s);
  auto vertical = [&](int w, int h, double* y, double* size) {
    const std::string svg = chart_svg(c, w, h);
    const size_t at = svg.find("rotate(-90");
    ASSERT_NE(at, std::string::npos);
    const size_t open = svg.rfind("<text", at);
    auto attr = [&](const std::string& name) {
      const size_t k = svg.find(" " + name + "=\"", open);
      return std::stod(svg.substr(k + name.size() + 3));
    };
    *y = attr("y");
    *size = attr("font-size");
  };
  // Per pixel of font size, as the SVG painter measures text (Painter::text_width's 0.6 em).
  const double width = 0.6 * double(c.y.title().size());
  double y, size;
  vertical(400, 150, &y, &size);
  EXPECT_LT(size, 9.0);  // below the base font (9 px at this height): it had to shrink
  EXPECT_GE(y - 0.5 * width * size, 0.0);
  EXPECT_LE(y + 0.5 * width * size, 150.0);
  vertical(900, 600, &y, &size);
  EXPECT_DOUBLE_EQ(size, 15.0);  // the base font H / 40
  EXPECT_GE(y - 0.5 * width * size, 0.0);
  EXPECT_LE(y + 0.5 * width * size, 600.0);
}

}  // namespace
}  // namespace ravel::studies
