#include "chart.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>

#include "results.h"

// Both stb headers are used with static linkage so they never clash with the render
// library's own copies in the same executable.
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>
#include <stb/stb_easy_font.h>

namespace ravel::studies {

Rgb palette(int i) {
  static const Rgb colors[] = {{0, 114, 178},  {213, 94, 0},    {0, 158, 115}, {204, 121, 167}, {230, 159, 0},
                               {86, 180, 233}, {120, 120, 120}, {0, 0, 0},     {160, 60, 60}};
  const int n = int(sizeof colors / sizeof colors[0]);
  return colors[((i % n) + n) % n];
}

std::vector<double> nice_ticks(double lo, double hi, int target) {
  std::vector<double> t;
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi)) return {lo};
  const double raw = (hi - lo) / std::max(1, target);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  const double first = std::ceil(lo / step - 1e-9) * step;
  for (double v = first; v <= hi + 1e-9 * step; v += step) t.push_back(std::abs(v) < 1e-12 * step ? 0.0 : v);
  return t;
}

std::string tick_label(double v, double step) {
  char buf[32];
  const double a = std::max(std::abs(v), std::abs(step));
  if (a != 0 && (a >= 1e6 || a < 1e-3)) {
    std::snprintf(buf, sizeof buf, "%.3g", v);
  } else {
    int decimals = std::max(0, int(std::ceil(-std::log10(std::abs(step)) - 1e-9)));
    if (std::abs(step * std::pow(10.0, decimals) - std::round(step * std::pow(10.0, decimals))) > 1e-6) ++decimals;
    std::snprintf(buf, sizeof buf, "%.*f", std::min(decimals, 6), v);
  }
  return buf;
}

namespace {
// A value that can be drawn on the axis (finite; positive on a log axis).
bool drawable(const Axis& a, double v) {
  return std::isfinite(v) && (!a.log || v > 0);
}
}  // namespace

int finite_point_count(const Chart& chart) {
  int n = 0;
  for (int c : chart.grid.cells)
    if (c >= 0) ++n;
  for (const auto& s : chart.series)
    for (size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
      if (drawable(chart.x, s.x[i]) && drawable(chart.y, s.y[i])) ++n;
  return n;
}

std::vector<double> log_ticks(double lo, double hi) {
  std::vector<double> t;
  if (!(lo > 0) || !(hi > lo) || !std::isfinite(hi)) return {lo};
  const int d0 = int(std::floor(std::log10(lo) + 1e-9)), d1 = int(std::ceil(std::log10(hi) - 1e-9));
  const bool fine = d1 - d0 <= 2;
  for (int d = d0; d <= d1; ++d)
    for (double m : {1.0, 2.0, 5.0}) {
      if (m != 1.0 && !fine) continue;
      const double v = m * std::pow(10.0, d);
      if (v >= lo * (1 - 1e-9) && v <= hi * (1 + 1e-9)) t.push_back(v);
    }
  return t;
}

namespace {

void axis_range(const Axis& a, double dlo, double dhi, double* lo, double* hi) {
  if (a.fixed_range) {
    *lo = a.min;
    *hi = a.max;
    return;
  }
  if (a.log) {  // whole decades around the positive data
    if (!(dlo > 0) || !std::isfinite(dhi)) dlo = 1, dhi = 10;
    *lo = std::pow(10.0, std::floor(std::log10(dlo) + 1e-9));
    *hi = std::pow(10.0, std::ceil(std::log10(dhi) - 1e-9));
    if (*hi <= *lo) *hi = *lo * 10;
    return;
  }
  if (a.include_zero) {
    dlo = std::min(dlo, 0.0);
    dhi = std::max(dhi, 0.0);
  }
  if (!std::isfinite(dlo) || !std::isfinite(dhi)) {
    dlo = 0;
    dhi = 1;
  }
  if (dhi - dlo <= 1e-12 * std::max(1.0, std::abs(dhi))) {
    const double pad = dlo == 0 ? 1.0 : 0.1 * std::abs(dlo);
    dlo -= pad;
    dhi += pad;
  }
  const auto t = nice_ticks(dlo, dhi, 6);
  const double step = t.size() > 1 ? t[1] - t[0] : (dhi - dlo);
  // Ends on a major tick unless that wastes more than 15 % of the span on a side; then on
  // a minor tick (a fifth of a step), so a tiny negative value does not add a whole step.
  const double span = dhi - dlo, minor = step / 5;
  *lo = std::floor(dlo / step + 1e-9) * step;
  if (dlo - *lo > 0.15 * span) *lo = std::floor(dlo / minor + 1e-9) * minor;
  *hi = std::ceil(dhi / step - 1e-9) * step;
  if (*hi - dhi > 0.15 * span) *hi = std::ceil(dhi / minor - 1e-9) * minor;
}

}  // namespace

void chart_ranges(const Chart& chart, double* x0, double* x1, double* y0, double* y1) {
  double xl = INFINITY, xh = -INFINITY, yl = INFINITY, yh = -INFINITY;
  for (const auto& s : chart.series)
    for (size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
      if (!drawable(chart.x, s.x[i]) || !drawable(chart.y, s.y[i])) continue;
      xl = std::min(xl, s.x[i]);
      xh = std::max(xh, s.x[i]);
      yl = std::min(yl, s.y[i]);
      yh = std::max(yh, s.y[i]);
      if (s.has_error_bars()) {
        if (drawable(chart.y, s.y_lo[i])) yl = std::min(yl, s.y_lo[i]);
        if (drawable(chart.y, s.y_hi[i])) yh = std::max(yh, s.y_hi[i]);
      }
    }
  axis_range(chart.x, xl, xh, x0, x1);
  axis_range(chart.y, yl, yh, y0, y1);
}

void Painter::polyline(const std::vector<std::array<double, 2>>& pts, Rgb c, double width, bool dashed) {
  if (!dashed) {
    for (size_t i = 1; i < pts.size(); ++i) line(pts[i - 1][0], pts[i - 1][1], pts[i][0], pts[i][1], c, width, false);
    return;
  }
  // Dashes carried across vertices so short segments still show the pattern.
  const double on = 4 * width + 3, off = 3 * width + 2;
  double phase = 0;
  for (size_t i = 1; i < pts.size(); ++i) {
    const double dx = pts[i][0] - pts[i - 1][0], dy = pts[i][1] - pts[i - 1][1];
    const double len = std::hypot(dx, dy);
    double s = 0;
    while (s < len) {
      const double period_pos = std::fmod(phase + s, on + off);
      const bool drawing = period_pos < on;
      // At least a hundredth of a pixel per pass: fmod rounding must not stall the walk.
      const double run = std::max(0.01, std::min(len - s, drawing ? on - period_pos : on + off - period_pos));
      if (drawing && len > 0)
        line(pts[i - 1][0] + dx * s / len, pts[i - 1][1] + dy * s / len, pts[i - 1][0] + dx * (s + run) / len,
             pts[i - 1][1] + dy * (s + run) / len, c, width, false);
      s += run;
    }
    phase = std::fmod(phase + len, on + off);
  }
}

void Painter::rect_outline(double x0, double y0, double x1, double y1, Rgb c, double w) {
  line(x0, y0, x1, y0, c, w, false);
  line(x1, y0, x1, y1, c, w, false);
  line(x1, y1, x0, y1, c, w, false);
  line(x0, y1, x0, y0, c, w, false);
}

namespace {

// A legend entry's text broken at spaces into lines no wider than `width` (a word wider than
// that stays whole on its own line): long names wrap instead of running off the image.
std::vector<std::string> wrap_text(const Painter& p, const std::string& text, double size, double width) {
  std::vector<std::string> lines;
  std::string line;
  size_t at = 0;
  while (at < text.size()) {
    size_t end = text.find(' ', at);
    if (end == std::string::npos) end = text.size();
    const std::string word = text.substr(at, end - at);
    const std::string longer = line.empty() ? word : line + " " + word;
    if (!line.empty() && p.text_width(longer, size) > width) {
      lines.push_back(line);
      line = word;
    } else {
      line = longer;
    }
    at = end + 1;
  }
  if (!line.empty() || lines.empty()) lines.push_back(line);
  return lines;
}

// The y title, rotated, along the chart's left edge centred on the plot (mid). On a short
// chart (a panel in the app) a long title would spill past the chart's top and be cut: it
// shrinks to the chart's height (down to 0.6 of the font) and moves off the plot's middle
// only as far as it must to stay inside [Y, Y + H] (centred on the chart if even then too long).
void y_title(Painter& p, const std::string& title, double X, double Y, double H, double mid, double fs, Rgb ink) {
  const double room = H - 0.6 * fs, full = p.text_width(title, fs);
  const double size = full > room && full > 0 ? std::max(0.6 * fs, fs * room / full) : fs;
  const double half = 0.5 * p.text_width(title, size);
  mid = 2 * half < room ? std::clamp(mid, Y + 0.3 * fs + half, Y + H - 0.3 * fs - half) : Y + H / 2;
  p.text(X + 0.9 * fs, mid, title, size, ink, 1, true);
}

// A categorical grid chart (Chart::grid): cells, row and column labels, a legend of the
// categories. Same fonts and margins as the x-y charts.
void draw_grid_chart(const Chart& chart, Painter& p, double X, double Y, double W, double H, double fs) {
  const Rgb ink{30, 30, 30}, frame{90, 90, 90}, white{255, 255, 255};
  const Grid& g = chart.grid;
  const size_t nx = g.x_labels.size(), ny = g.y_labels.size();
  if (nx == 0 || ny == 0 || g.cells.size() != nx * ny) return;
  double ylab_w = 0;
  for (const auto& l : g.y_labels) ylab_w = std::max(ylab_w, p.text_width(l, fs));
  double legend_w = 0;
  if (chart.legend)
    for (const auto& c : g.categories) legend_w = std::max(legend_w, p.text_width(c, fs) + 2.6 * fs);
  legend_w = std::min(legend_w, 0.35 * W);
  const double top = Y + (chart.subtitle.empty() ? 2.6 : 3.9) * fs;
  const double left = X + ylab_w + 2.6 * fs;
  const double right = X + W - (legend_w > 0 ? legend_w + 1.2 * fs : 1.2 * fs);
  const double bottom = Y + H - 3.4 * fs;
  if (right - left < 20 || bottom - top < 20) return;
  p.text(X + W / 2, Y + 1.2 * fs, chart.title, 1.2 * fs, ink, 1, false);
  if (!chart.subtitle.empty()) p.text(X + W / 2, Y + 2.6 * fs, chart.subtitle, 0.85 * fs, {90, 90, 90}, 1, false);
  const double cw = (right - left) / double(nx), ch = (bottom - top) / double(ny);
  const double gap = std::max(1.0, std::min(cw, ch) * 0.04);
  for (size_t yi = 0; yi < ny; ++yi)
    for (size_t xi = 0; xi < nx; ++xi) {
      const double cx0 = left + xi * cw, cy1 = bottom - yi * ch;
      const int k = g.cell(xi, yi);
      const Rgb c = k >= 0 && size_t(k) < g.colors.size() ? g.colors[size_t(k)] : Rgb{240, 240, 240};
      p.rect_filled(cx0 + gap, cy1 - ch + gap, cx0 + cw - gap, cy1 - gap, c);
      const size_t i = yi * nx + xi;
      if (i < g.cell_text.size() && !g.cell_text[i].empty()) {
        const double lum = 0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2];
        const double ts = std::min(fs, 0.9 * (cw - 2 * gap) / std::max(1.0, p.text_width(g.cell_text[i], 1.0)));
        p.text(cx0 + cw / 2, cy1 - ch / 2, g.cell_text[i], std::max(6.0, ts), lum < 140 ? white : ink, 1, false);
      }
    }
  for (size_t xi = 0; xi < nx; ++xi)
    p.text(left + (xi + 0.5) * cw, bottom + 1.1 * fs, g.x_labels[xi], fs, ink, 1, false);
  for (size_t yi = 0; yi < ny; ++yi)
    p.text(left - 0.7 * fs, bottom - (yi + 0.5) * ch, g.y_labels[yi], fs, ink, 2, false);
  p.text((left + right) / 2, bottom + 2.5 * fs, chart.x.title(), fs, ink, 1, false);
  y_title(p, chart.y.title(), X, Y, H, (top + bottom) / 2, fs, ink);
  p.rect_outline(left, top, right, bottom, frame, 1);
  if (legend_w > 0) {
    double ly = top + 0.8 * fs;
    const double lx = right + 1.0 * fs;
    for (size_t k = 0; k < g.categories.size(); ++k) {
      const Rgb c = k < g.colors.size() ? g.colors[k] : Rgb{240, 240, 240};
      p.rect_filled(lx, ly - 0.5 * fs, lx + fs, ly + 0.5 * fs, c);
      for (const auto& line : wrap_text(p, g.categories[k], fs, legend_w - 1.6 * fs)) {
        p.text(lx + 1.6 * fs, ly, line, fs, ink, 0, false);
        ly += 1.2 * fs;
      }
      ly += 0.3 * fs;
    }
  }
}

}  // namespace

void draw_chart(const Chart& chart, Painter& p, double X, double Y, double W, double H) {
  const Rgb ink{30, 30, 30}, grid{225, 225, 225}, frame{90, 90, 90}, white{255, 255, 255};
  const double fs = std::clamp(H / 40.0, 9.0, 18.0);  // base font size
  p.rect_filled(X, Y, X + W, Y + H, white);
  if (!chart.grid.empty()) {
    draw_grid_chart(chart, p, X, Y, W, H, fs);
    return;
  }

  double x0, x1, y0, y1;
  chart_ranges(chart, &x0, &x1, &y0, &y1);
  // Linear axes: the target chart_ranges() padded to; log axes: decades.
  const auto xt = chart.x.log ? log_ticks(x0, x1) : nice_ticks(x0, x1, 6);
  const auto yt = chart.y.log ? log_ticks(y0, y1) : nice_ticks(y0, y1, 6);
  const double xstep = xt.size() > 1 ? xt[1] - xt[0] : 1, ystep = yt.size() > 1 ? yt[1] - yt[0] : 1;
  auto xlabel = [&](double v) { return chart.x.log ? tick_label(v, v) : tick_label(v, xstep); };
  auto ylabel = [&](double v) { return chart.y.log ? tick_label(v, v) : tick_label(v, ystep); };

  double ylab_w = 0;
  for (double v : yt) ylab_w = std::max(ylab_w, p.text_width(ylabel(v), fs));
  double legend_w = 0;
  if (chart.legend && chart.series.size() > 1)
    for (const auto& s : chart.series) legend_w = std::max(legend_w, p.text_width(s.name, fs) + 3.2 * fs);
  legend_w = std::min(legend_w, 0.35 * W);

  const double top = Y + (chart.subtitle.empty() ? 2.6 : 3.9) * fs;
  const double left = X + ylab_w + 2.6 * fs;
  const double right = X + W - (legend_w > 0 ? legend_w + 1.2 * fs : 1.2 * fs);
  const double bottom = Y + H - 3.4 * fs;
  if (right - left < 20 || bottom - top < 20) return;
  auto tx = [&](double v) { return chart.x.log ? std::log10(v) : v; };
  auto ty = [&](double v) { return chart.y.log ? std::log10(v) : v; };
  auto px = [&](double v) { return left + (tx(v) - tx(x0)) / (tx(x1) - tx(x0)) * (right - left); };
  auto py = [&](double v) { return bottom - (ty(v) - ty(y0)) / (ty(y1) - ty(y0)) * (bottom - top); };

  p.text(X + W / 2, Y + 1.2 * fs, chart.title, 1.2 * fs, ink, 1, false);
  if (!chart.subtitle.empty()) p.text(X + W / 2, Y + 2.6 * fs, chart.subtitle, 0.85 * fs, {90, 90, 90}, 1, false);

  // Log axes: faint minor lines at 2..9 x each decade.
  const Rgb minor_grid{242, 242, 242};
  if (chart.x.log)
    for (double d = x0; d < x1 * (1 - 1e-9); d *= 10)
      for (int m = 2; m <= 9; ++m) p.line(px(m * d), top, px(m * d), bottom, minor_grid, 1, false);
  if (chart.y.log)
    for (double d = y0; d < y1 * (1 - 1e-9); d *= 10)
      for (int m = 2; m <= 9; ++m) p.line(left, py(m * d), right, py(m * d), minor_grid, 1, false);
  for (double v : xt) {
    p.line(px(v), top, px(v), bottom, grid, 1, false);
    p.line(px(v), bottom, px(v), bottom + 0.4 * fs, frame, 1, false);
    p.text(px(v), bottom + 1.1 * fs, xlabel(v), fs, ink, 1, false);
  }
  for (double v : yt) {
    p.line(left, py(v), right, py(v), grid, 1, false);
    p.line(left - 0.4 * fs, py(v), left, py(v), frame, 1, false);
    p.text(left - 0.7 * fs, py(v), ylabel(v), fs, ink, 2, false);
  }
  p.text((left + right) / 2, bottom + 2.5 * fs, chart.x.title(), fs, ink, 1, false);
  y_title(p, chart.y.title(), X, Y, H, (top + bottom) / 2, fs, ink);

  p.clip(left, top, right, bottom);
  for (size_t k = 0; k < chart.series.size(); ++k) {
    const Series& s = chart.series[k];
    const Rgb c = palette(s.color >= 0 ? s.color : int(k));
    p.begin_series(s);
    std::vector<std::array<double, 2>> run;
    auto flush = [&] {
      if (s.style != SeriesStyle::markers && run.size() > 1) p.polyline(run, c, std::max(1.5, fs / 7), s.dashed);
      run.clear();
    };
    for (size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
      if (!drawable(chart.x, s.x[i]) || !drawable(chart.y, s.y[i])) {
        flush();
        continue;
      }
      run.push_back({px(s.x[i]), py(s.y[i])});
      if (s.style != SeriesStyle::line) p.marker(px(s.x[i]), py(s.y[i]), std::max(2.5, fs / 3.5), c);
      if (s.has_error_bars() && drawable(chart.y, s.y_lo[i]) && drawable(chart.y, s.y_hi[i])) {
        const double xb = px(s.x[i]), cap = 0.4 * fs, w = std::max(1.2, fs / 9);
        p.line(xb, py(s.y_lo[i]), xb, py(s.y_hi[i]), c, w, false);
        p.line(xb - cap, py(s.y_lo[i]), xb + cap, py(s.y_lo[i]), c, w, false);
        p.line(xb - cap, py(s.y_hi[i]), xb + cap, py(s.y_hi[i]), c, w, false);
      }
    }
    flush();
    p.end_series();
  }
  p.unclip();
  p.rect_outline(left, top, right, bottom, frame, 1);

  if (legend_w > 0) {
    double ly = top + 0.8 * fs;
    const double lx = right + 1.0 * fs;
    for (size_t k = 0; k < chart.series.size(); ++k) {
      const Series& s = chart.series[k];
      const Rgb c = palette(s.color >= 0 ? s.color : int(k));
      if (s.style != SeriesStyle::markers) p.line(lx, ly, lx + 2.0 * fs, ly, c, std::max(1.5, fs / 7), s.dashed);
      if (s.style != SeriesStyle::line) p.marker(lx + 1.0 * fs, ly, std::max(2.5, fs / 3.5), c);
      for (const auto& line : wrap_text(p, s.name, fs, legend_w - 2.5 * fs)) {
        p.text(lx + 2.5 * fs, ly, line, fs, ink, 0, false);
        ly += 1.2 * fs;
      }
      ly += 0.3 * fs;
    }
  }
}

// ---------------------------------------------------------------------------------------
// SVG
namespace {

std::string xml_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&':
        o += "&amp;";
        break;
      case '<':
        o += "&lt;";
        break;
      case '>':
        o += "&gt;";
        break;
      case '"':
        o += "&quot;";
        break;
      default:
        o += c;
    }
  }
  return o;
}

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f", v);
  return b;
}
std::string col(Rgb c) {
  char b[16];
  std::snprintf(b, sizeof b, "#%02x%02x%02x", c[0], c[1], c[2]);
  return b;
}

class SvgPainter : public Painter {
 public:
  std::ostringstream out;
  int clip_id = 0;
  bool clipped = false;
  void line(double x0, double y0, double x1, double y1, Rgb c, double w, bool dashed) override {
    out << "<line x1=\"" << fmt(x0) << "\" y1=\"" << fmt(y0) << "\" x2=\"" << fmt(x1) << "\" y2=\"" << fmt(y1)
        << "\" stroke=\"" << col(c) << "\" stroke-width=\"" << fmt(w) << "\""
        << (dashed ? " stroke-dasharray=\"6,4\"" : "") << "/>\n";
  }
  void polyline(const std::vector<std::array<double, 2>>& pts, Rgb c, double w, bool dashed) override {
    out << "<polyline fill=\"none\" stroke=\"" << col(c) << "\" stroke-width=\"" << fmt(w)
        << "\" stroke-linejoin=\"round\"" << (dashed ? " stroke-dasharray=\"6,4\"" : "") << " points=\"";
    for (const auto& q : pts) out << fmt(q[0]) << "," << fmt(q[1]) << " ";
    out << "\"/>\n";
  }
  void rect_filled(double x0, double y0, double x1, double y1, Rgb c) override {
    out << "<rect x=\"" << fmt(x0) << "\" y=\"" << fmt(y0) << "\" width=\"" << fmt(x1 - x0) << "\" height=\""
        << fmt(y1 - y0) << "\" fill=\"" << col(c) << "\"/>\n";
  }
  void rect_outline(double x0, double y0, double x1, double y1, Rgb c, double w) override {
    out << "<rect x=\"" << fmt(x0) << "\" y=\"" << fmt(y0) << "\" width=\"" << fmt(x1 - x0) << "\" height=\""
        << fmt(y1 - y0) << "\" fill=\"none\" stroke=\"" << col(c) << "\" stroke-width=\"" << fmt(w) << "\"/>\n";
  }
  void marker(double x, double y, double r, Rgb c) override {
    out << "<circle cx=\"" << fmt(x) << "\" cy=\"" << fmt(y) << "\" r=\"" << fmt(r) << "\" fill=\"" << col(c)
        << "\"/>\n";
  }
  void text(double x, double y, const std::string& s, double size, Rgb c, int align, bool vertical) override {
    const char* anchor = align == 0 ? "start" : align == 1 ? "middle" : "end";
    out << "<text x=\"" << fmt(x) << "\" y=\"" << fmt(y) << "\" font-size=\"" << fmt(size) << "\" fill=\"" << col(c)
        << "\" text-anchor=\"" << anchor << "\" dominant-baseline=\"central\"";
    if (vertical) out << " transform=\"rotate(-90 " << fmt(x) << " " << fmt(y) << ")\"";
    out << ">" << xml_escape(s) << "</text>\n";
  }
  void begin_series(const Series& s) override {
    out << "<g class=\"series\" data-name=\"" << xml_escape(s.name) << "\" data-points=\"";
    char b[64];
    for (size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
      std::snprintf(b, sizeof b, "%s%.9g,%.9g", i ? " " : "", s.x[i], s.y[i]);
      out << b;
    }
    out << "\">\n";
  }
  void end_series() override { out << "</g>\n"; }
  void clip(double x0, double y0, double x1, double y1) override {
    ++clip_id;
    out << "<clipPath id=\"plot" << clip_id << "\"><rect x=\"" << fmt(x0) << "\" y=\"" << fmt(y0) << "\" width=\""
        << fmt(x1 - x0) << "\" height=\"" << fmt(y1 - y0) << "\"/></clipPath>\n<g clip-path=\"url(#plot" << clip_id
        << ")\">\n";
    clipped = true;
  }
  void unclip() override {
    if (clipped) out << "</g>\n";
    clipped = false;
  }
};

}  // namespace

std::string chart_svg(const Chart& chart, int width, int height) {
  SvgPainter p;
  p.out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
        << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
        << "\" viewBox=\"0 0 " << width << " " << height
        << "\" font-family=\"DejaVu Sans, Helvetica, Arial, sans-serif\">\n"
        << "<title>" << xml_escape(chart.title) << "</title>\n";
  draw_chart(chart, p, 0, 0, width, height);
  p.out << "</svg>\n";
  return p.out.str();
}

// ---------------------------------------------------------------------------------------
// PNG: a small anti-aliased software rasteriser.
namespace {

class RasterPainter : public Painter {
 public:
  RasterPainter(int w, int h) : w_(w), h_(h), px_(size_t(w) * h * 3, 255) { unclip(); }
  std::vector<unsigned char> take() { return std::move(px_); }

  void blend(int x, int y, Rgb c, double a) {
    if (x < cx0_ || y < cy0_ || x >= cx1_ || y >= cy1_ || a <= 0) return;
    a = std::min(a, 1.0);
    unsigned char* p = &px_[(size_t(y) * w_ + x) * 3];
    for (int k = 0; k < 3; ++k) p[k] = (unsigned char)std::lround(p[k] * (1 - a) + c[k] * a);
  }
  void line(double x0, double y0, double x1, double y1, Rgb c, double w, bool dashed) override {
    if (dashed) {
      Painter::polyline({{x0, y0}, {x1, y1}}, c, w, true);
      return;
    }
    const double r = w / 2;
    const int xa = int(std::floor(std::min(x0, x1) - r - 1)), xb = int(std::ceil(std::max(x0, x1) + r + 1));
    const int ya = int(std::floor(std::min(y0, y1) - r - 1)), yb = int(std::ceil(std::max(y0, y1) + r + 1));
    const double dx = x1 - x0, dy = y1 - y0, len2 = dx * dx + dy * dy;
    for (int y = std::max(ya, cy0_); y <= std::min(yb, cy1_ - 1); ++y)
      for (int x = std::max(xa, cx0_); x <= std::min(xb, cx1_ - 1); ++x) {
        const double qx = x + 0.5, qy = y + 0.5;
        double t = len2 > 0 ? ((qx - x0) * dx + (qy - y0) * dy) / len2 : 0;
        t = std::clamp(t, 0.0, 1.0);
        const double d = std::hypot(qx - (x0 + t * dx), qy - (y0 + t * dy));
        blend(x, y, c, std::clamp(r + 0.5 - d, 0.0, 1.0));
      }
  }
  void polyline(const std::vector<std::array<double, 2>>& pts, Rgb c, double w, bool dashed) override {
    Painter::polyline(pts, c, w, dashed);
  }
  void rect_filled(double x0, double y0, double x1, double y1, Rgb c) override {
    // Box-filtered coverage so thin text strokes stay smooth at fractional scales.
    for (int y = std::max(int(std::floor(y0)), cy0_); y < std::min(int(std::ceil(y1)), cy1_); ++y) {
      const double cy = std::min(y1, y + 1.0) - std::max(y0, double(y));
      for (int x = std::max(int(std::floor(x0)), cx0_); x < std::min(int(std::ceil(x1)), cx1_); ++x) {
        const double cx = std::min(x1, x + 1.0) - std::max(x0, double(x));
        blend(x, y, c, cx * cy);
      }
    }
  }
  void marker(double x, double y, double r, Rgb c) override {
    for (int yy = int(y - r - 1); yy <= int(y + r + 1); ++yy)
      for (int xx = int(x - r - 1); xx <= int(x + r + 1); ++xx)
        blend(xx, yy, c, std::clamp(r + 0.5 - std::hypot(xx + 0.5 - x, yy + 0.5 - y), 0.0, 1.0));
  }
  double text_width(const std::string& s, double size) const override {
    return stb_easy_font_width(const_cast<char*>(s.c_str())) * size / kGlyphHeight;
  }
  void text(double x, double y, const std::string& s, double size, Rgb c, int align, bool vertical) override {
    static thread_local std::vector<char> buf(1 << 16);
    const double scale = size / kGlyphHeight;
    const int quads = stb_easy_font_print(0, 0, const_cast<char*>(s.c_str()), nullptr, buf.data(), int(buf.size()));
    const double width = text_width(s, size);
    const double shift = align == 0 ? 0 : align == 1 ? -width / 2 : -width;
    const double vshift = -0.5 * kGlyphHeight * scale;  // glyph cap height centred on y
    for (int q = 0; q < quads; ++q) {
      const float* v = reinterpret_cast<const float*>(buf.data() + q * 64);
      // Vertex 0 and 2 are opposite corners (each vertex: x, y, z floats + 4 colour bytes).
      double ax = v[0] * scale + shift, ay = v[1] * scale + vshift;
      double bx = v[8] * scale + shift, by = v[9] * scale + vshift;
      if (!vertical) {
        rect_filled(x + std::min(ax, bx), y + std::min(ay, by), x + std::max(ax, bx), y + std::max(ay, by), c);
      } else {  // rotate 90 degrees counter-clockwise: (u, v) -> (v, -u)
        rect_filled(x + std::min(ay, by), y - std::max(ax, bx), x + std::max(ay, by), y - std::min(ax, bx), c);
      }
    }
  }
  void clip(double x0, double y0, double x1, double y1) override {
    cx0_ = std::max(0, int(std::floor(x0)));
    cy0_ = std::max(0, int(std::floor(y0)));
    cx1_ = std::min(w_, int(std::ceil(x1)));
    cy1_ = std::min(h_, int(std::ceil(y1)));
  }
  void unclip() override {
    cx0_ = cy0_ = 0;
    cx1_ = w_;
    cy1_ = h_;
  }

 private:
  static constexpr double kGlyphHeight = 8.0;  // stb_easy_font: caps ~7 px, descenders to ~9
  int w_, h_;
  std::vector<unsigned char> px_;
  int cx0_ = 0, cy0_ = 0, cx1_ = 0, cy1_ = 0;
};

void append_bytes(void* ctx, void* data, int size) {
  auto* v = static_cast<std::vector<unsigned char>*>(ctx);
  v->insert(v->end(), static_cast<unsigned char*>(data), static_cast<unsigned char*>(data) + size);
}

}  // namespace

std::vector<unsigned char> chart_rgb(const Chart& chart, int width, int height) {
  RasterPainter p(width, height);
  draw_chart(chart, p, 0, 0, width, height);
  return p.take();
}

std::vector<unsigned char> png_bytes(const std::vector<unsigned char>& rgb, int width, int height) {
  std::vector<unsigned char> out;
  stbi_write_png_to_func(append_bytes, &out, width, height, 3, rgb.data(), width * 3);
  return out;
}

std::string chart_csv(const Chart& chart) {
  auto quote = [](const std::string& s) {
    if (s.find_first_of(",\"\n") == std::string::npos) return s;
    std::string o = "\"";
    for (char c : s) o += c == '"' ? std::string("\"\"") : std::string(1, c);
    return o + "\"";
  };
  if (!chart.grid.empty()) {
    const Grid& g = chart.grid;
    std::string out = quote(chart.x.title()) + "," + quote(chart.y.title()) + ",category,text\n";
    for (size_t yi = 0; yi < g.y_labels.size(); ++yi)
      for (size_t xi = 0; xi < g.x_labels.size(); ++xi) {
        const size_t i = yi * g.x_labels.size() + xi;
        if (i >= g.cells.size()) break;
        const int k = g.cells[i];
        out += quote(g.x_labels[xi]) + "," + quote(g.y_labels[yi]) + "," +
               (k >= 0 && size_t(k) < g.categories.size() ? quote(g.categories[size_t(k)]) : std::string()) + "," +
               (i < g.cell_text.size() ? quote(g.cell_text[i]) : std::string()) + "\n";
      }
    return out;
  }
  bool bars = false;
  for (const auto& s : chart.series) bars = bars || s.has_error_bars();
  std::string out =
      "series," + quote(chart.x.title()) + "," + quote(chart.y.title()) + (bars ? ",low,high" : "") + "\n";
  char buf[96];
  for (const auto& s : chart.series)
    for (size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
      std::snprintf(buf, sizeof buf, ",%.9g,%.9g", s.x[i], s.y[i]);
      out += quote(s.name) + buf;
      if (bars) {
        if (s.has_error_bars())
          std::snprintf(buf, sizeof buf, ",%.9g,%.9g\n", s.y_lo[i], s.y_hi[i]);
        else
          std::snprintf(buf, sizeof buf, ",,\n");
        out += buf;
      } else {
        out += "\n";
      }
    }
  return out;
}

void write_chart(const Chart& chart, const std::string& stem, int width, int height) {
  write_file_atomic(stem + ".csv", chart_csv(chart));
  write_file_atomic(stem + ".svg", chart_svg(chart, width, height));
  // PNG at 1.5x for crisp text in reports.
  const int pw = width * 3 / 2, ph = height * 3 / 2;
  const auto png = png_bytes(chart_rgb(chart, pw, ph), pw, ph);
  write_file_atomic(stem + ".png", std::string(png.begin(), png.end()));
}

}  // namespace ravel::studies
