// Charts: one description, drawn the same way to SVG, to PNG (a small software
// rasteriser, no GL: chart PNGs must work wherever the studies run) and, through the
// same Painter interface, to the app's ImGui draw lists (studies/chart_imgui.h).
//
// A chart is only ever drawn from the numbers it is given; write_chart() always puts the
// CSV of exactly those numbers beside the images, so every picture can be checked.
#pragma once

#include <array>
#include <string>
#include <vector>

namespace ravel::studies {

using Rgb = std::array<unsigned char, 3>;

enum class SeriesStyle { line, markers, line_markers };

struct Series {
  std::string name;          // legend entry
  std::vector<double> x, y;  // same length; non-finite points are skipped (a gap)
  SeriesStyle style = SeriesStyle::line_markers;
  int color = -1;  // index into the palette; -1 = the series' position
  bool dashed = false;
  // Optional error bars: the interval [y_lo[i], y_hi[i]] drawn as a capped vertical bar at
  // x[i] (empty: none; non-finite ends: no bar at that point).
  std::vector<double> y_lo = {}, y_hi = {};
  bool has_error_bars() const { return !y_lo.empty() && y_lo.size() == x.size() && y_hi.size() == x.size(); }
};

struct Axis {
  std::string label;         // "impact velocity"
  std::string unit;          // "m/s" (shown as "impact velocity (m/s)")
  bool fixed_range = false;  // false: from the data, padded to nice ticks
  double min = 0, max = 1;
  bool include_zero = false;  // extend the data range to 0
  bool log = false;           // log10 scale: decade ticks; values <= 0 are skipped (a gap)
  std::string title() const { return unit.empty() ? label : label + " (" + unit + ")"; }
};

// A categorical grid ("heat map" of categories, e.g. a stability map): one coloured cell
// per (x, y) label pair. A chart with a grid draws it instead of its series; the axes give
// only the titles.
struct Grid {
  std::vector<std::string> x_labels;    // columns, left to right
  std::vector<std::string> y_labels;    // rows, bottom to top
  std::vector<std::string> categories;  // legend entries
  std::vector<Rgb> colors;              // one per category
  std::vector<int> cells;               // category per cell, row-major from the bottom row; -1 = no data
  std::vector<std::string> cell_text;   // optional short text per cell (same layout)
  bool empty() const { return cells.empty(); }
  int cell(size_t xi, size_t yi) const { return cells[yi * x_labels.size() + xi]; }
};

struct Chart {
  std::string title;
  std::string subtitle;  // e.g. the scene and what quick mode changed
  Axis x, y;
  std::vector<Series> series;
  bool legend = true;
  Grid grid;  // non-empty: a categorical grid chart
};

// Palette shared by every backend (colour-blind safe, Okabe-Ito order).
Rgb palette(int index);

// Tick positions covering [lo, hi] with about `target` steps of 1, 2 or 5 x 10^k.
std::vector<double> nice_ticks(double lo, double hi, int target = 6);
// Short tick label ("0.25", "1e-05", "300").
std::string tick_label(double v, double step);
// The ranges a chart is drawn with (data extremes widened to nice ticks, or fixed).
void chart_ranges(const Chart& chart, double* x0, double* x1, double* y0, double* y1);
// Ticks of a log axis over [lo, hi] (decades; 2 and 5 between them over few decades).
std::vector<double> log_ticks(double lo, double hi);
// Points of the chart that actually have data (every series, finite x and y; on log axes
// positive; the cells with data of a grid chart).
int finite_point_count(const Chart& chart);

// What any backend can draw. Coordinates in pixels, y down, origin top left.
class Painter {
 public:
  virtual ~Painter() = default;
  virtual void line(double x0, double y0, double x1, double y1, Rgb c, double width, bool dashed) = 0;
  virtual void polyline(const std::vector<std::array<double, 2>>& pts, Rgb c, double width, bool dashed);
  virtual void rect_filled(double x0, double y0, double x1, double y1, Rgb c) = 0;
  virtual void rect_outline(double x0, double y0, double x1, double y1, Rgb c, double width);
  virtual void marker(double x, double y, double radius, Rgb c) = 0;
  // Text with its anchor at (x, y): align 0 left, 1 centre, 2 right; vertically centred.
  // vertical = rotated 90 degrees counter-clockwise (y-axis title).
  virtual void text(double x, double y, const std::string& s, double size_px, Rgb c, int align, bool vertical) = 0;
  virtual double text_width(const std::string& s, double size_px) const { return 0.6 * size_px * double(s.size()); }
  // Around each series' drawing (the SVG keeps the numbers as data-* attributes).
  virtual void begin_series(const Series& s) {}
  virtual void end_series() {}
  virtual void clip(double x0, double y0, double x1, double y1) {}
  virtual void unclip() {}
};

// Lay the chart out in the rectangle (x, y, w, h) and draw it with `p`.
void draw_chart(const Chart& chart, Painter& p, double x, double y, double w, double h);

// Whole documents.
std::string chart_svg(const Chart& chart, int width = 900, int height = 600);
// RGB pixels, top row first.
std::vector<unsigned char> chart_rgb(const Chart& chart, int width, int height);
std::vector<unsigned char> png_bytes(const std::vector<unsigned char>& rgb, int width, int height);
// Long format: series,<x title>,<y title>; one row per point (and, when a series has error
// bars, two more columns: low,high). A grid chart:
// <x title>,<y title>,category,text; one row per cell.
std::string chart_csv(const Chart& chart);

// Write STEM.csv, STEM.svg and STEM.png atomically. Throws ravel::OutputError.
void write_chart(const Chart& chart, const std::string& path_stem, int width = 900, int height = 600);

}  // namespace ravel::studies
