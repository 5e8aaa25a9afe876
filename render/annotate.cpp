// Annotator: world-space polylines and text blocks on top of a rendered view.
#include "render/annotate.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "render/gl.h"
#include "render/gl_program.h"
#include "render/overlay.h"

namespace ravel::render {

namespace {

// A thick segment as two triangles, with round-ish joins (a small square at each end).
void push_segment(std::vector<OverlayVertex>& v, float x0, float y0, float x1, float y1, float width, Rgba c) {
  const float dx = x1 - x0, dy = y1 - y0, len = std::sqrt(dx * dx + dy * dy);
  if (len < 1e-6f) return;
  const float hw = 0.5f * width;
  const float nx = -dy / len * hw, ny = dx / len * hw;
  const float ex = dx / len * hw * 0.5f, ey = dy / len * hw * 0.5f;  // extend a little: closed joins
  const OverlayVertex a{x0 + nx - ex, y0 + ny - ey, c.r, c.g, c.b, c.a},
      b{x1 + nx + ex, y1 + ny + ey, c.r, c.g, c.b, c.a}, d{x0 - nx - ex, y0 - ny - ey, c.r, c.g, c.b, c.a},
      e{x1 - nx + ex, y1 - ny + ey, c.r, c.g, c.b, c.a};
  v.insert(v.end(), {a, b, e, a, e, d});
}

}  // namespace

std::vector<PixelSegment> annotation_geometry(const WorldPolyline& line, const Camera& camera, int w, int h) {
  std::vector<PixelSegment> out;
  const std::size_t n = line.points.size();
  if (n < 2 || w <= 0 || h <= 0) return out;
  const float aspect = float(w) / float(h);
  const std::size_t segs = line.closed ? n : n - 1;
  for (std::size_t i = 0; i < segs; ++i) {
    float u0, v0, u1, v1;
    if (!camera.project(line.points[i], aspect, &u0, &v0)) continue;
    if (!camera.project(line.points[(i + 1) % n], aspect, &u1, &v1)) continue;
    out.push_back({u0 * w, v0 * h, u1 * w, v1 * h});
  }
  return out;
}

struct Annotator::Impl {
  GLuint prog = 0, vao = 0, vbo = 0;
  std::size_t capacity = 0;
};

Annotator::Annotator() : impl_(std::make_unique<Impl>()) {
  Impl& r = *impl_;
  r.prog = link_program("overlay.vert", "overlay.frag");
  glGenVertexArrays(1, &r.vao);
  glGenBuffers(1, &r.vbo);
  glBindVertexArray(r.vao);
  glBindBuffer(GL_ARRAY_BUFFER, r.vbo);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, sizeof(OverlayVertex), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, sizeof(OverlayVertex), reinterpret_cast<void*>(2 * sizeof(float)));
  glBindVertexArray(0);
}

Annotator::~Annotator() {
  Impl& r = *impl_;
  if (r.vbo) glDeleteBuffers(1, &r.vbo);
  if (r.vao) glDeleteVertexArrays(1, &r.vao);
  if (r.prog) glDeleteProgram(r.prog);
}

float Annotator::text_width(const std::string& s, float scale) {
  return OverlayBatch::text_width(s, scale);
}
float Annotator::default_scale(int h) {
  return std::max(1.0f, std::round(float(h) / 420.0f));
}

void Annotator::draw(const Camera& camera, const std::vector<WorldPolyline>& lines, const std::vector<TextBlock>& texts,
                     int x, int y, int w, int h) {
  if (w <= 0 || h <= 0) return;
  std::vector<OverlayVertex> v;
  const float ui = std::max(1.0f, float(h) / 600.0f);
  OverlayBatch labels;
  for (const WorldPolyline& line : lines) {
    const Rgba c{line.color[0], line.color[1], line.color[2], 0.95f};
    const Rgba shadow{0.0f, 0.0f, 0.0f, 0.55f};
    const float width = line.width_px * ui;
    const auto segs = annotation_geometry(line, camera, w, h);
    // A dark halo under the line so it reads on any colour of the fabric.
    for (int pass = 0; pass < 2; ++pass) {
      for (const PixelSegment& s : segs) {
        if (!line.dashed) {
          push_segment(v, s.x0, s.y0, s.x1, s.y1, pass == 0 ? width + 2.0f * ui : width, pass == 0 ? shadow : c);
          continue;
        }
        const float len = std::hypot(s.x1 - s.x0, s.y1 - s.y0), dash = 9.0f * ui;
        for (float a = 0; a < len; a += 2 * dash) {
          const float b = std::min(len, a + dash);
          const float t0 = a / len, t1 = b / len;
          push_segment(v, s.x0 + (s.x1 - s.x0) * t0, s.y0 + (s.y1 - s.y0) * t0, s.x0 + (s.x1 - s.x0) * t1,
                       s.y0 + (s.y1 - s.y0) * t1, pass == 0 ? width + 2.0f * ui : width, pass == 0 ? shadow : c);
        }
      }
    }
    if (!line.label.empty()) {
      float u, vv;
      if (camera.project(line.label_at, float(w) / float(h), &u, &vv)) {
        const float s = default_scale(h);
        labels.text_shadowed(u * w + 4 * s, vv * h + 3 * s, line.label, s, c);
      }
    }
  }
  OverlayBatch text;
  for (const TextBlock& t : texts) {
    if (t.lines.empty()) continue;
    const float s = t.scale > 0 ? t.scale : default_scale(h);
    const float pad = 6 * s, line_h = 11 * s;
    float tw = t.min_width_px - 2 * pad;
    for (const auto& l : t.lines) tw = std::max(tw, OverlayBatch::text_width(l, s));
    const float bw = tw + 2 * pad, bh = t.lines.size() * line_h - (line_h - 7 * s) + 2 * pad;
    const float x0 = t.x >= 0 ? t.x : w + t.x - bw;
    const float y0 = t.y >= 0 ? t.y : h + t.y - bh;
    if (t.panel) text.rect(x0, y0, x0 + bw, y0 + bh, {0.02f, 0.03f, 0.05f, 0.72f});
    for (std::size_t i = 0; i < t.lines.size(); ++i) {
      const Vec3 c = i < t.colors.size() ? t.colors[i] : Vec3{0.96f, 0.97f, 0.99f};
      text.text_shadowed(x0 + pad, y0 + pad + i * line_h, t.lines[i], s, {c[0], c[1], c[2], 1.0f});
    }
  }
  v.insert(v.end(), labels.vertices().begin(), labels.vertices().end());
  v.insert(v.end(), text.vertices().begin(), text.vertices().end());
  if (v.empty()) return;

  Impl& r = *impl_;
  glViewport(x, y, w, h);
  glEnable(GL_SCISSOR_TEST);
  glScissor(x, y, w, h);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glUseProgram(r.prog);
  glUniform2f(glGetUniformLocation(r.prog, "u_viewport"), float(w), float(h));
  glBindVertexArray(r.vao);
  glBindBuffer(GL_ARRAY_BUFFER, r.vbo);
  const std::size_t bytes = v.size() * sizeof(OverlayVertex);
  if (bytes > r.capacity) {
    r.capacity = bytes * 2;
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(r.capacity), nullptr, GL_DYNAMIC_DRAW);
  }
  glBufferSubData(GL_ARRAY_BUFFER, 0, GLsizeiptr(bytes), v.data());
  glDrawArrays(GL_TRIANGLES, 0, GLsizei(v.size()));
  glBindVertexArray(0);
  glUseProgram(0);
  glDisable(GL_BLEND);
  glDisable(GL_SCISSOR_TEST);
}

}  // namespace ravel::render
