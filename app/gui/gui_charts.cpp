#include "gui_charts.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace ravel::app::gui {

namespace {

ImU32 with_alpha(ImU32 c, float a) {
  const unsigned alpha = unsigned(std::clamp(a, 0.0f, 1.0f) * float((c >> IM_COL32_A_SHIFT) & 0xff));
  return (c & ~IM_COL32_A_MASK) | (alpha << IM_COL32_A_SHIFT);
}

std::string tick_text(double v, double step) {
  char b[32];
  const int decimals = step >= 1 ? 0 : std::min(6, int(std::ceil(-std::log10(step) - 1e-9)));
  std::snprintf(b, sizeof b, "%.*f", decimals, std::abs(v) < step * 1e-6 ? 0.0 : v);
  return b;
}

// Polyline of one series, clipped to the plot by the caller's clip rect. Rows beyond a
// few per pixel are thinned so a long run stays cheap to draw.
void plot_rows(ImDrawList* dl, const std::vector<HistoryRow>& rows, RowValue value, ImU32 color, float thickness,
               const ImVec2& p0, const ImVec2& p1, double x_max_s, double y_min, double y_max) {
  if (rows.size() < 2) return;
  const double sx = (p1.x - p0.x) / x_max_s, sy = (p1.y - p0.y) / (y_max - y_min);
  const size_t stride = std::max<size_t>(1, rows.size() / size_t(std::max(1.0f, (p1.x - p0.x) * 2)));
  std::vector<ImVec2> pts;
  pts.reserve(rows.size() / stride + 2);
  for (size_t i = 0; i < rows.size(); i += stride) {
    const double v = value(rows[i]);
    if (!std::isfinite(v)) break;
    pts.emplace_back(float(p0.x + rows[i].t_s * sx), float(p1.y - (v - y_min) * sy));
  }
  if (stride > 1 && std::isfinite(value(rows.back())))
    pts.emplace_back(float(p0.x + rows.back().t_s * sx), float(p1.y - (value(rows.back()) - y_min) * sy));
  if (pts.size() >= 2) dl->AddPolyline(pts.data(), int(pts.size()), color, ImDrawFlags_None, thickness);
}

const HistoryRow* row_at(const std::vector<HistoryRow>& rows, double t_s) {
  if (rows.empty()) return nullptr;
  auto it = std::lower_bound(rows.begin(), rows.end(), t_s, [](const HistoryRow& r, double t) { return r.t_s < t; });
  if (it == rows.end()) return &rows.back();
  if (it != rows.begin() && std::abs(std::prev(it)->t_s - t_s) < std::abs(it->t_s - t_s)) --it;
  return &*it;
}

}  // namespace

double nice_step(double range, int target) {
  if (!(range > 0)) return 1;
  const double raw = range / std::max(1, target);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / mag;
  return (f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10) * mag;
}

double draw_chart(const ChartSpec& spec, ImVec2 size) {
  ImDrawList* dl = ImGui::GetWindowDrawList();
  const ImVec2 origin = ImGui::GetCursorScreenPos();
  ImGui::InvisibleButton(spec.id, size);
  const bool hovered = ImGui::IsItemHovered();
  const float fs = ImGui::GetFontSize();
  const ImU32 text = ImGui::GetColorU32(ImGuiCol_Text);
  const ImU32 dim = ImGui::GetColorU32(ImGuiCol_TextDisabled);
  const ImU32 grid = IM_COL32(255, 255, 255, 22);
  const ImU32 axis = IM_COL32(200, 205, 215, 160);

  // Data range: the requested axes, grown to fit every series (current and overlays).
  double x_max = spec.x_max_s > 0 ? spec.x_max_s : 1e-6;
  double y_min = spec.y_min, y_max = spec.y_max;
  auto grow = [&](const std::vector<HistoryRow>& rows) {
    if (!rows.empty()) x_max = std::max(x_max, rows.back().t_s);
    for (const auto& s : spec.series)
      for (const auto& r : rows) {
        const double v = s.value(r);
        if (std::isfinite(v)) y_min = std::min(y_min, v), y_max = std::max(y_max, v);
      }
  };
  if (spec.rows) grow(*spec.rows);
  for (const auto& o : spec.overlays) grow(*o.rows);
  // Round-off below zero (a ledger term of -1e-3 J) does not earn a negative axis.
  if (y_min < 0 && spec.y_min >= 0 && -y_min < 0.02 * (y_max - spec.y_min)) y_min = spec.y_min;
  if (!(y_max > y_min)) y_max = y_min + 1;
  const double y_step = nice_step(y_max - y_min, 5);
  y_min = std::floor(y_min / y_step + 1e-9) * y_step;
  y_max = std::ceil(y_max / y_step - 1e-9) * y_step;
  const double x_us = x_max * 1e6;
  const double x_step = nice_step(x_us, 6);

  // Layout: title, then the legend flowing in rows (so it never hides a curve), the
  // y-axis label, the plot, the x tick labels and the x label.
  const float sw = fs * 1.3f, pad = fs * 0.4f, lh = fs * 1.2f;
  struct Item {
    std::string text;
    ImU32 color;
    bool faint;
    float w;
  };
  std::vector<Item> items;
  for (const auto& s : spec.series)
    items.push_back({s.label, s.color, false, sw + pad + ImGui::CalcTextSize(s.label.c_str()).x});
  const bool own_colours = !spec.overlays.empty() && spec.overlays[0].color != 0;
  if (own_colours) {
    for (const auto& o : spec.overlays)
      items.push_back({o.label, o.color, true, sw + pad + ImGui::CalcTextSize(o.label.c_str()).x});
  } else if (!spec.overlays.empty()) {
    std::string faint = spec.overlays.size() == 1 ? spec.overlays[0].label + " (faint)"
                                                  : std::to_string(spec.overlays.size()) + " earlier runs (faint)";
    items.push_back({faint, IM_COL32(200, 200, 200, 110), true, sw + pad + ImGui::CalcTextSize(faint.c_str()).x});
  }
  const float legend_x0 = origin.x + 2, legend_x1 = origin.x + size.x - fs * 0.5f;
  std::vector<ImVec2> item_pos;
  float lx = legend_x0, ly = origin.y + fs * 1.35f;
  for (const auto& it : items) {
    if (lx > legend_x0 && lx + it.w > legend_x1) {
      lx = legend_x0;
      ly += lh;
    }
    item_pos.emplace_back(lx, ly);
    lx += it.w + fs * 1.1f;
  }
  const float y_label_y = ly + lh + fs * 0.15f;

  char widest[32];
  std::snprintf(widest, sizeof widest, "%s",
                tick_text(std::abs(y_min) > std::abs(y_max) ? y_min : y_max, y_step).c_str());
  const float left = ImGui::CalcTextSize(widest).x + fs * 0.9f;
  const ImVec2 p0(origin.x + left, y_label_y + fs * 1.5f);
  const ImVec2 p1(origin.x + size.x - fs * 0.8f, origin.y + size.y - fs * 2.6f);
  if (p1.x - p0.x < 20 || p1.y - p0.y < 20) return -1;

  dl->AddText(ImVec2(origin.x + 2, origin.y), text, spec.title.c_str());
  for (size_t i = 0; i < items.size(); ++i) {
    const ImVec2 q = item_pos[i];
    dl->AddLine(ImVec2(q.x, q.y + lh * 0.5f), ImVec2(q.x + sw, q.y + lh * 0.5f), items[i].color,
                items[i].faint ? 1.5f : 3.0f);
    dl->AddText(ImVec2(q.x + sw + pad, q.y), items[i].faint ? dim : text, items[i].text.c_str());
  }
  dl->AddText(ImVec2(origin.x + 2, y_label_y), dim, spec.y_label.c_str());
  const ImVec2 xl = ImGui::CalcTextSize(spec.x_label.c_str());
  dl->AddText(ImVec2(0.5f * (p0.x + p1.x - xl.x), p1.y + fs * 1.35f), dim, spec.x_label.c_str());
  dl->AddRectFilled(p0, p1, IM_COL32(0, 0, 0, 60));

  // Grid and ticks.
  for (double y = y_min; y <= y_max + 0.5 * y_step; y += y_step) {
    const float py = float(p1.y - (y - y_min) / (y_max - y_min) * (p1.y - p0.y));
    dl->AddLine(ImVec2(p0.x, py), ImVec2(p1.x, py), std::abs(y) < 0.5 * y_step ? axis : grid);
    const std::string t = tick_text(y, y_step);
    const ImVec2 ts = ImGui::CalcTextSize(t.c_str());
    dl->AddText(ImVec2(p0.x - ts.x - fs * 0.35f, py - ts.y * 0.5f), text, t.c_str());
  }
  for (double x = 0; x <= x_us + 0.5 * x_step; x += x_step) {
    const float px = float(p0.x + x / x_us * (p1.x - p0.x));
    if (px > p1.x + 0.5f) break;
    dl->AddLine(ImVec2(px, p0.y), ImVec2(px, p1.y), grid);
    dl->AddLine(ImVec2(px, p1.y), ImVec2(px, p1.y + fs * 0.3f), axis);
    const std::string t = tick_text(x, x_step);
    const ImVec2 ts = ImGui::CalcTextSize(t.c_str());
    dl->AddText(ImVec2(px - ts.x * 0.5f, p1.y + fs * 0.3f), text, t.c_str());
  }
  dl->AddLine(ImVec2(p0.x, p0.y), ImVec2(p0.x, p1.y), axis);
  dl->AddLine(ImVec2(p0.x, p1.y), ImVec2(p1.x, p1.y), axis);

  // Curves: earlier runs faint first, then the current run on top.
  dl->PushClipRect(p0, p1, true);
  for (const auto& o : spec.overlays)
    for (const auto& s : spec.series)
      plot_rows(dl, *o.rows, s.value, o.color ? o.color : with_alpha(s.color, 0.28f), 1.4f, p0, p1, x_max, y_min,
                y_max);
  if (spec.rows)
    for (const auto& s : spec.series) plot_rows(dl, *spec.rows, s.value, s.color, 2.0f, p0, p1, x_max, y_min, y_max);
  if (spec.cursor_s >= 0 && spec.cursor_s <= x_max) {
    const float cx = float(p0.x + spec.cursor_s / x_max * (p1.x - p0.x));
    dl->AddLine(ImVec2(cx, p0.y), ImVec2(cx, p1.y), IM_COL32(255, 80, 210, 220), 2.0f);
  }
  dl->PopClipRect();

  double clicked = -1;
  if (hovered && ImGui::IsMouseClicked(ImGuiMouseButton_Left)) {
    const ImVec2 m = ImGui::GetIO().MousePos;
    if (m.x >= p0.x && m.x <= p1.x) clicked = (m.x - p0.x) / (p1.x - p0.x) * x_max;
  }
  // Hover read-out: the values of the current run at the time under the mouse.
  if (hovered && spec.rows && !spec.rows->empty()) {
    const ImVec2 m = ImGui::GetIO().MousePos;
    if (m.x >= p0.x && m.x <= p1.x) {
      const double t = (m.x - p0.x) / (p1.x - p0.x) * x_max;
      dl->AddLine(ImVec2(m.x, p0.y), ImVec2(m.x, p1.y), IM_COL32(255, 255, 255, 90));
      if (const HistoryRow* r = row_at(*spec.rows, t)) {
        ImGui::BeginTooltip();
        ImGui::Text("t = %.2f \xC2\xB5s", r->t_s * 1e6);
        for (const auto& s : spec.series) {
          ImGui::TextColored(ImGui::ColorConvertU32ToFloat4(s.color), "%s", s.label.c_str());
          ImGui::SameLine(fs * 11);
          ImGui::Text("%.4g", s.value(*r));
        }
        for (const auto& o : spec.overlays)
          if (const HistoryRow* q = row_at(*o.rows, t); q && !spec.series.empty()) {
            ImGui::TextDisabled("%s", o.label.c_str());
            ImGui::SameLine();
            ImGui::TextDisabled("%s %.4g", spec.series.size() == 1 ? "" : spec.series[0].label.c_str(),
                                spec.series[0].value(*q));
          }
        ImGui::TextDisabled("click: show the fabric at this time");
        ImGui::EndTooltip();
      }
    }
  }
  return clicked;
}

}  // namespace ravel::app::gui
