#include "chart_imgui.h"

#include <algorithm>

namespace ravel::studies {

namespace {

ImU32 to_u32(Rgb c) {
  return IM_COL32(c[0], c[1], c[2], 255);
}

class ImGuiPainter : public Painter {
 public:
  explicit ImGuiPainter(ImDrawList* dl) : dl_(dl) {}
  void line(double x0, double y0, double x1, double y1, Rgb c, double w, bool dashed) override {
    if (dashed) {
      Painter::polyline({{x0, y0}, {x1, y1}}, c, w, true);
      return;
    }
    dl_->AddLine(ImVec2(float(x0), float(y0)), ImVec2(float(x1), float(y1)), to_u32(c), float(w));
  }
  void polyline(const std::vector<std::array<double, 2>>& pts, Rgb c, double w, bool dashed) override {
    if (dashed) {
      Painter::polyline(pts, c, w, true);
      return;
    }
    std::vector<ImVec2> v;
    v.reserve(pts.size());
    for (const auto& p : pts) v.emplace_back(float(p[0]), float(p[1]));
    dl_->AddPolyline(v.data(), int(v.size()), to_u32(c), ImDrawFlags_None, float(w));
  }
  void rect_filled(double x0, double y0, double x1, double y1, Rgb c) override {
    dl_->AddRectFilled(ImVec2(float(x0), float(y0)), ImVec2(float(x1), float(y1)), to_u32(c));
  }
  void marker(double x, double y, double r, Rgb c) override {
    dl_->AddCircleFilled(ImVec2(float(x), float(y)), float(r), to_u32(c));
  }
  double text_width(const std::string& s, double size) const override {
    return ImGui::GetFont()->CalcTextSizeA(float(size), 1e9f, 0, s.c_str()).x;
  }
  void text(double x, double y, const std::string& s, double size, Rgb c, int align, bool vertical) override {
    const ImVec2 ts = ImGui::GetFont()->CalcTextSizeA(float(size), 1e9f, 0, s.c_str());
    if (vertical) {  // ImGui 1.86 has no rotated text: rotate the emitted glyph quads
      draw_vertical(x, y, s, size, c);
      return;
    }
    const double shift = align == 0 ? 0 : align == 1 ? -ts.x / 2 : -ts.x;
    dl_->AddText(ImGui::GetFont(), float(size), ImVec2(float(x + shift), float(y - ts.y / 2)), to_u32(c), s.c_str());
  }
  void clip(double x0, double y0, double x1, double y1) override {
    dl_->PushClipRect(ImVec2(float(x0), float(y0)), ImVec2(float(x1), float(y1)), true);
    clipped_ = true;
  }
  void unclip() override {
    if (clipped_) dl_->PopClipRect();
    clipped_ = false;
  }

 private:
  // Rotate the glyph quads ImGui just emitted by 90 degrees about (x, y). ImGui drops glyphs
  // that lie outside the clip rectangle as laid out, before they are turned: a title centred
  // on an axis near the window's left edge lost its first letters ("y absorbed (J)"). So the
  // line is laid out where it lies inside the clip rectangle and moved as it is turned.
  void draw_vertical(double x, double y, const std::string& s, double size, Rgb c) {
    const ImVec2 ts = ImGui::GetFont()->CalcTextSizeA(float(size), 1e9f, 0, s.c_str());
    const ImVec2 lo = dl_->GetClipRectMin(), hi = dl_->GetClipRectMax();
    const float want_x = float(x - ts.x / 2), want_y = float(y - ts.y / 2);
    const float at_x = std::max(lo.x, std::min(want_x, hi.x - ts.x));
    const float at_y = std::max(lo.y, std::min(want_y, hi.y - ts.y));
    const int start = dl_->VtxBuffer.Size;
    dl_->AddText(ImGui::GetFont(), float(size), ImVec2(at_x, at_y), to_u32(c), s.c_str());
    for (int i = start; i < dl_->VtxBuffer.Size; ++i) {
      ImVec2& p = dl_->VtxBuffer[i].pos;
      const float dx = p.x + (want_x - at_x) - float(x), dy = p.y + (want_y - at_y) - float(y);
      p = ImVec2(float(x) + dy, float(y) - dx);  // counter-clockwise on screen
    }
  }
  ImDrawList* dl_;
  bool clipped_ = false;
};

}  // namespace

void draw_chart_imgui(const Chart& chart, ImVec2 size) {
  const ImVec2 avail = ImGui::GetContentRegionAvail();
  if (size.x <= 0) size.x = std::max(100.0f, avail.x);
  if (size.y <= 0) size.y = std::max(80.0f, 0.6f * size.x);
  const ImVec2 p0 = ImGui::GetCursorScreenPos();
  ImGuiPainter painter(ImGui::GetWindowDrawList());
  draw_chart(chart, painter, p0.x, p0.y, size.x, size.y);
  ImGui::Dummy(size);
}

}  // namespace ravel::studies
