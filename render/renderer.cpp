// Renderer: tubes, projectile, clamps, colour bar and caption for one Frame.
#include "render/renderer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "render/gl.h"
#include "render/gl_program.h"
#include "render/math.h"
#include "render/overlay.h"

namespace ravel::render {

const char* embedded_shader(const char* name);  // generated: build/render/embedded_shaders.cpp

namespace {

// ---- GL helpers ------------------------------------------------------------------------

GLuint compile(GLenum type, const char* name) {
  const char* src = embedded_shader(name);
  if (!src) throw std::runtime_error(std::string("shader not embedded: ") + name);
  GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    glDeleteShader(s);
    throw std::runtime_error(std::string("shader ") + name + ": " + log);
  }
  return s;
}

struct Vertex {
  float px, py, pz, nx, ny, nz;
};

struct Mesh {
  GLuint vao = 0, vbo = 0, ebo = 0;
  GLsizei index_count = 0;

  void upload(const std::vector<Vertex>& v, const std::vector<std::uint32_t>& idx) {
    glGenVertexArrays(1, &vao);
    glGenBuffers(1, &vbo);
    glGenBuffers(1, &ebo);
    glBindVertexArray(vao);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, v.size() * sizeof(Vertex), v.data(), GL_STATIC_DRAW);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, idx.size() * 4, idx.data(), GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex), nullptr);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex), reinterpret_cast<void*>(3 * sizeof(float)));
    glBindVertexArray(0);
    index_count = static_cast<GLsizei>(idx.size());
  }
  void destroy() {
    glDeleteBuffers(1, &vbo);
    glDeleteBuffers(1, &ebo);
    glDeleteVertexArrays(1, &vao);
  }
};

// Unit sphere, counter-clockwise seen from outside.
void make_sphere(int slices, int stacks, std::vector<Vertex>* v, std::vector<std::uint32_t>* idx) {
  const float pi = 3.14159265f;
  for (int j = 0; j <= stacks; ++j) {
    const float th = pi * j / stacks;  // from +z down
    for (int i = 0; i <= slices; ++i) {
      const float ph = 2 * pi * i / slices;
      const float x = std::sin(th) * std::cos(ph), y = std::sin(th) * std::sin(ph), z = std::cos(th);
      v->push_back({x, y, z, x, y, z});
    }
  }
  for (int j = 0; j < stacks; ++j)
    for (int i = 0; i < slices; ++i) {
      const std::uint32_t a = j * (slices + 1) + i, b = a + slices + 1;
      idx->insert(idx->end(), {a, b, a + 1, a + 1, b, b + 1});
    }
}

// Unit-radius solid of revolution along +z from z = 0 to z = 1: a cylinder (tip_radius 1)
// or a cone (tip_radius 0), with flat caps.
void make_revolved(int slices, float tip_radius, std::vector<Vertex>* v, std::vector<std::uint32_t>* idx) {
  const float pi = 3.14159265f;
  const float slope = 1.0f - tip_radius;  // radius drop per unit length
  const float nl = std::sqrt(1 + slope * slope);
  for (int i = 0; i <= slices; ++i) {
    const float ph = 2 * pi * i / slices, c = std::cos(ph), s = std::sin(ph);
    v->push_back({c, s, 0, c / nl, s / nl, slope / nl});
    v->push_back({c * tip_radius, s * tip_radius, 1, c / nl, s / nl, slope / nl});
  }
  for (int i = 0; i < slices; ++i) {
    const std::uint32_t a = 2 * i;
    idx->insert(idx->end(), {a, a + 2, a + 1, a + 1, a + 2, a + 3});
  }
  for (int cap = 0; cap < 2; ++cap) {
    const float z = static_cast<float>(cap), r = cap ? tip_radius : 1.0f, nz = cap ? 1.0f : -1.0f;
    if (r <= 0) continue;
    const std::uint32_t centre = static_cast<std::uint32_t>(v->size());
    v->push_back({0, 0, z, 0, 0, nz});
    for (int i = 0; i <= slices; ++i) {
      const float ph = 2 * pi * i / slices;
      v->push_back({r * std::cos(ph), r * std::sin(ph), z, 0, 0, nz});
    }
    for (int i = 0; i < slices; ++i) {
      const std::uint32_t a = centre + 1 + i;
      if (cap)
        idx->insert(idx->end(), {centre, a, a + 1});
      else
        idx->insert(idx->end(), {centre, a + 1, a});
    }
  }
}

// Cube [-1, 1]^3 with flat faces.
void make_box(std::vector<Vertex>* v, std::vector<std::uint32_t>* idx) {
  for (int axis = 0; axis < 3; ++axis)
    for (int sign = -1; sign <= 1; sign += 2) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;
      const std::uint32_t base = static_cast<std::uint32_t>(v->size());
      const float cu[4] = {-1, 1, 1, -1}, cw[4] = {-1, -1, 1, 1};
      for (int k = 0; k < 4; ++k) {
        float p[3], n[3] = {0, 0, 0};
        p[axis] = static_cast<float>(sign);
        p[u] = cu[k];
        p[w] = cw[k];
        n[axis] = static_cast<float>(sign);
        v->push_back({p[0], p[1], p[2], n[0], n[1], n[2]});
      }
      if (sign > 0)
        idx->insert(idx->end(), {base, base + 1, base + 2, base, base + 2, base + 3});
      else
        idx->insert(idx->end(), {base, base + 2, base + 1, base, base + 3, base + 2});
    }
}

struct TubeInstance {
  float ax, ay, az, t;     // node a, colour-map coordinate
  float bx, by, bz, kind;  // node b, 0 warp / 1 weft / 2 broken stub
};

// Model matrix mapping the unit meshes: columns are the scaled axes, then the origin.
Mat4 model_matrix(const Vec3& x_axis, const Vec3& y_axis, const Vec3& z_axis, const Vec3& origin) {
  return {x_axis[0], x_axis[1], x_axis[2], 0, y_axis[0], y_axis[1], y_axis[2], 0,
          z_axis[0], z_axis[1], z_axis[2], 0, origin[0], origin[1], origin[2], 1};
}

// Normal matrix for a model matrix with orthogonal axes: each axis divided by its length^2.
std::array<float, 9> normal_matrix(const Vec3& x_axis, const Vec3& y_axis, const Vec3& z_axis) {
  const Vec3 a = x_axis * (1.0f / dot(x_axis, x_axis)), b = y_axis * (1.0f / dot(y_axis, y_axis)),
             c = z_axis * (1.0f / dot(z_axis, z_axis));
  return {a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2]};
}

std::string format_number(double x) {
  char buf[32];
  if (x == 0)
    return "0";
  else if (std::abs(x) >= 1000 || std::abs(x) < 0.01)
    std::snprintf(buf, sizeof buf, "%.2g", x);
  else
    std::snprintf(buf, sizeof buf, "%.3g", x);
  return buf;
}

// A "nice" upper bound for an automatic colour range: 1, 2, 2.5 or 5 x 10^k.
float nice_ceil(float x) {
  if (!(x > 0)) return 1.0f;
  const float p = std::pow(10.0f, std::floor(std::log10(x)));
  for (float m : {1.0f, 2.0f, 2.5f, 5.0f, 10.0f})
    if (x <= m * p * 1.0001f) return m * p;
  return 10 * p;
}

}  // namespace

const char* to_string(YarnGeometry g) {
  switch (g) {
    case YarnGeometry::automatic:
      return "auto";
    case YarnGeometry::tubes:
      return "tubes";
    case YarnGeometry::ribbons:
      return "ribbons";
  }
  return "?";
}

bool parse_yarn_geometry(const std::string& name, YarnGeometry* out) {
  for (YarnGeometry g : {YarnGeometry::automatic, YarnGeometry::tubes, YarnGeometry::ribbons})
    if (name == to_string(g)) {
      *out = g;
      return true;
    }
  return false;
}

// ---- field values ------------------------------------------------------------------------

static float element_value(const Frame& f, ColorField field, std::size_t e) {
  const std::uint32_t a = f.elem_a[e], b = f.elem_b[e];
  switch (field) {
    case ColorField::strain:
      return e < f.elem_strain.size() ? f.elem_strain[e] : 0.0f;  // raw strain
    case ColorField::velocity: {
      if (a >= f.node_vel.size() || b >= f.node_vel.size()) return 0.0f;
      const auto& va = f.node_vel[a];
      const auto& vb = f.node_vel[b];
      const float x = 0.5f * (va[0] + vb[0]), y = 0.5f * (va[1] + vb[1]), z = 0.5f * (va[2] + vb[2]);
      return std::sqrt(x * x + y * y + z * z);
    }
    case ColorField::sliding:
      if (a >= f.node_slip_rate.size() || b >= f.node_slip_rate.size()) return 0.0f;
      return 0.5f * (std::abs(f.node_slip_rate[a]) + std::abs(f.node_slip_rate[b]));
    case ColorField::friction:
      if (a >= f.node_friction_j_per_g.size() || b >= f.node_friction_j_per_g.size()) return 0.0f;
      return 0.5f * (f.node_friction_j_per_g[a] + f.node_friction_j_per_g[b]);
  }
  return 0.0f;
}

void field_range(const Frame& frame, const ViewOptions& options, float* lo, float* hi) {
  if (options.range_max > options.range_min) {
    *lo = options.range_min;
    *hi = options.range_max;
    return;
  }
  *lo = 0.0f;
  switch (options.field) {
    case ColorField::strain:
      *hi = 1.0f;  // in units of the failure strain
      break;
    case ColorField::velocity:
      *hi = frame.impact_velocity_mps > 0 ? static_cast<float>(frame.impact_velocity_mps) : 1.0f;
      break;
    case ColorField::sliding: {
      float m = 0;
      for (float s : frame.node_slip_rate) m = std::max(m, std::abs(s));
      *hi = nice_ceil(std::max(m, 1e-3f));
      break;
    }
    case ColorField::friction: {
      // The top of the scale at the 98th percentile of the nodes' values: friction gathers
      // at a few crossings under the projectile, and the rest of the ply would be one colour
      // under the largest (values above it take the top colour).
      std::vector<float> v;
      v.reserve(frame.node_friction_j_per_g.size());
      for (float x : frame.node_friction_j_per_g)
        if (x > 0) v.push_back(x);
      float top = 0;
      if (!v.empty()) {
        const std::size_t k = std::min(v.size() - 1, std::size_t(0.98 * double(v.size())));
        std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(k), v.end());
        top = v[k];
      }
      *hi = nice_ceil(std::max(top, 1e-3f));
      break;
    }
  }
}

void share_field_range(const std::vector<const Frame*>& frames, ViewOptions* o) {
  if (o->range_max > o->range_min || (o->field != ColorField::sliding && o->field != ColorField::friction)) return;
  float hi = 0;
  for (const Frame* f : frames) {
    float lo_i = 0, hi_i = 0;
    field_range(*f, *o, &lo_i, &hi_i);
    hi = std::max(hi, hi_i);
  }
  if (hi > 0) o->range_min = 0, o->range_max = hi;
}

std::vector<std::string> caption_lines(const Frame& frame, const ViewOptions& options) {
  // Short lines: the caption sits in the margin beside the fabric, not over it.
  char buf[128];
  std::vector<std::string> lines;
  lines.push_back(frame.scene_name.empty() ? "(unnamed scene)" : frame.scene_name);
  std::snprintf(buf, sizeof buf, "t = %.1f us", frame.time_s * 1e6);
  lines.push_back(buf);
  std::snprintf(buf, sizeof buf, "mu = %.2f", frame.friction);
  lines.push_back(buf);
  std::snprintf(buf, sizeof buf, "V0 = %.0f m/s", frame.impact_velocity_mps);
  lines.push_back(buf);
  lines.push_back(frame.model_label.empty() ? "model: -" : frame.model_label);
  return lines;
}

// ---- Renderer ------------------------------------------------------------------------------

struct Renderer::Impl {
  GLuint bg_prog = 0, tube_prog = 0, ribbon_prog = 0, mesh_prog = 0, overlay_prog = 0, upscale_prog = 0;
  GLuint empty_vao = 0;
  GLuint tube_vao = 0, ring_vbo = 0, ring_ebo = 0, inst_vbo = 0;
  int ring_sides = 0;
  GLsizei ring_index_count = 0;
  std::size_t inst_capacity = 0;
  GLuint overlay_vao = 0, overlay_vbo = 0;
  std::size_t overlay_capacity = 0;
  GLuint colormap_tex = 0;
  int colormap_loaded = -1;
  Mesh sphere, cylinder, cone, box;
  std::vector<TubeInstance> instances;
  std::vector<TubeInstance> uploaded;   // what inst_vbo holds
  std::vector<std::int32_t> next_elem;  // level of detail: element leaving each node
  std::vector<std::uint8_t> merged;     // element already drawn by a merged instance
  // Low-resolution target for ViewOptions::render_scale < 1: colour + depth textures.
  GLuint low_fbo = 0, low_color = 0, low_depth = 0;
  int low_w = 0, low_h = 0;
  std::vector<std::uint8_t> intact;
  OverlayBatch overlay;
  DrawStats stats;

  void build_ring(int sides);
  void ensure_low_target(int w, int h);
  void load_colormap(ColorMap map);
  void draw_mesh(const Mesh& m, const Mat4& model, const std::array<float, 9>& nmat, const Vec3& color, float shininess,
                 float specular);
  void draw_overlay(const Frame& frame, const Camera& camera, const ViewOptions& o, int w, int h);
};

Renderer::Renderer() : impl_(std::make_unique<Impl>()) {
  Impl& r = *impl_;
  r.bg_prog = link_program("background.vert", "background.frag");
  r.tube_prog = link_program("tube.vert", "tube.frag");
  r.ribbon_prog = link_program("ribbon.vert", "ribbon.frag");
  r.upscale_prog = link_program("background.vert", "upscale.frag");
  r.mesh_prog = link_program("mesh.vert", "mesh.frag");
  r.overlay_prog = link_program("overlay.vert", "overlay.frag");
  glGenVertexArrays(1, &r.empty_vao);

  glGenVertexArrays(1, &r.tube_vao);
  glGenBuffers(1, &r.ring_vbo);
  glGenBuffers(1, &r.ring_ebo);
  glGenBuffers(1, &r.inst_vbo);
  glBindVertexArray(r.tube_vao);
  glBindBuffer(GL_ARRAY_BUFFER, r.inst_vbo);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, sizeof(TubeInstance), nullptr);
  glVertexAttribDivisor(1, 1);
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 4, GL_FLOAT, GL_FALSE, sizeof(TubeInstance), reinterpret_cast<void*>(4 * sizeof(float)));
  glVertexAttribDivisor(2, 1);
  glBindVertexArray(0);
  r.build_ring(8);

  glGenVertexArrays(1, &r.overlay_vao);
  glGenBuffers(1, &r.overlay_vbo);
  glBindVertexArray(r.overlay_vao);
  glBindBuffer(GL_ARRAY_BUFFER, r.overlay_vbo);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, sizeof(OverlayVertex), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, sizeof(OverlayVertex), reinterpret_cast<void*>(2 * sizeof(float)));
  glBindVertexArray(0);

  glGenTextures(1, &r.colormap_tex);

  std::vector<Vertex> v;
  std::vector<std::uint32_t> idx;
  make_sphere(48, 24, &v, &idx);
  r.sphere.upload(v, idx);
  v.clear();
  idx.clear();
  make_revolved(48, 1.0f, &v, &idx);
  r.cylinder.upload(v, idx);
  v.clear();
  idx.clear();
  make_revolved(48, 0.0f, &v, &idx);
  r.cone.upload(v, idx);
  v.clear();
  idx.clear();
  make_box(&v, &idx);
  r.box.upload(v, idx);
}

Renderer::~Renderer() {
  Impl& r = *impl_;
  for (GLuint p : {r.bg_prog, r.tube_prog, r.ribbon_prog, r.mesh_prog, r.overlay_prog, r.upscale_prog})
    glDeleteProgram(p);
  if (r.low_fbo) glDeleteFramebuffers(1, &r.low_fbo);
  GLuint low_tex[] = {r.low_color, r.low_depth};
  glDeleteTextures(2, low_tex);
  GLuint vaos[] = {r.empty_vao, r.tube_vao, r.overlay_vao};
  glDeleteVertexArrays(3, vaos);
  GLuint bufs[] = {r.ring_vbo, r.ring_ebo, r.inst_vbo, r.overlay_vbo};
  glDeleteBuffers(4, bufs);
  glDeleteTextures(1, &r.colormap_tex);
  r.sphere.destroy();
  r.cylinder.destroy();
  r.cone.destroy();
  r.box.destroy();
}

const DrawStats& Renderer::stats() const {
  return impl_->stats;
}

void Renderer::Impl::build_ring(int sides) {
  // Two rings of `sides` vertices (at node a and node b); quads between them.
  std::vector<float> ring;
  const float pi = 3.14159265f;
  for (int end = 0; end < 2; ++end)
    for (int i = 0; i < sides; ++i) {
      // Start half a step off so a flat face (not an edge) looks up out of the fabric.
      const float ph = 2 * pi * (i + 0.5f) / sides;
      ring.insert(ring.end(), {std::cos(ph), std::sin(ph), static_cast<float>(end)});
    }
  std::vector<std::uint16_t> idx;
  for (int i = 0; i < sides; ++i) {
    const std::uint16_t a = static_cast<std::uint16_t>(i), b = static_cast<std::uint16_t>((i + 1) % sides);
    const std::uint16_t c = static_cast<std::uint16_t>(a + sides), d = static_cast<std::uint16_t>(b + sides);
    idx.insert(idx.end(), {a, c, b, b, c, d});
  }
  glBindVertexArray(tube_vao);
  glBindBuffer(GL_ARRAY_BUFFER, ring_vbo);
  glBufferData(GL_ARRAY_BUFFER, ring.size() * sizeof(float), ring.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float), nullptr);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ring_ebo);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, idx.size() * 2, idx.data(), GL_STATIC_DRAW);
  glBindVertexArray(0);
  ring_sides = sides;
  ring_index_count = static_cast<GLsizei>(idx.size());
}

void Renderer::Impl::ensure_low_target(int w, int h) {
  if (low_fbo && w == low_w && h == low_h) return;
  if (!low_fbo) {
    glGenFramebuffers(1, &low_fbo);
    glGenTextures(1, &low_color);
    glGenTextures(1, &low_depth);
  }
  glBindTexture(GL_TEXTURE_2D, low_color);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glBindTexture(GL_TEXTURE_2D, low_depth);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT24, w, h, 0, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, nullptr);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_NONE);
  glBindTexture(GL_TEXTURE_2D, 0);
  GLint previous = 0;
  glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &previous);
  glBindFramebuffer(GL_FRAMEBUFFER, low_fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, low_color, 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, low_depth, 0);
  glBindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(previous));
  low_w = w;
  low_h = h;
}

void Renderer::Impl::load_colormap(ColorMap map) {
  if (colormap_loaded == static_cast<int>(map)) return;
  constexpr int n = 256;
  std::vector<std::uint8_t> texels(n * 3);
  for (int i = 0; i < n; ++i) {
    const Vec3 c = colormap(map, (i + 0.5f) / n);
    for (int k = 0; k < 3; ++k)
      texels[3 * i + k] = static_cast<std::uint8_t>(std::lround(std::clamp(c[k], 0.0f, 1.0f) * 255));
  }
  glBindTexture(GL_TEXTURE_2D, colormap_tex);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, n, 1, 0, GL_RGB, GL_UNSIGNED_BYTE, texels.data());
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  colormap_loaded = static_cast<int>(map);
}

void Renderer::Impl::draw_mesh(const Mesh& m, const Mat4& model, const std::array<float, 9>& nmat, const Vec3& color,
                               float shininess, float specular) {
  glUniformMatrix4fv(glGetUniformLocation(mesh_prog, "u_model"), 1, GL_FALSE, model.data());
  glUniformMatrix3fv(glGetUniformLocation(mesh_prog, "u_normal_matrix"), 1, GL_FALSE, nmat.data());
  glUniform3fv(glGetUniformLocation(mesh_prog, "u_color"), 1, color.data());
  glUniform1f(glGetUniformLocation(mesh_prog, "u_shininess"), shininess);
  glUniform1f(glGetUniformLocation(mesh_prog, "u_specular"), specular);
  glBindVertexArray(m.vao);
  glDrawElements(GL_TRIANGLES, m.index_count, GL_UNSIGNED_INT, nullptr);
}

// Median in-plane length of intact elements: the node spacing along a yarn, which is
// also the spacing between neighbouring parallel yarns in a balanced weave.
static float yarn_spacing(const Frame& f) {
  std::vector<float> len;
  const std::size_t n = f.elem_a.size();
  const std::size_t stride = std::max<std::size_t>(1, n / 4096);
  for (std::size_t e = 0; e < n; e += stride) {
    if (e < f.elem_broken.size() && f.elem_broken[e]) continue;
    const auto& a = f.node_pos[f.elem_a[e]];
    const auto& b = f.node_pos[f.elem_b[e]];
    len.push_back(std::hypot(b[0] - a[0], b[1] - a[1]));
  }
  if (len.empty()) return 4.0f * f.yarn_diameter_m;
  std::nth_element(len.begin(), len.begin() + len.size() / 2, len.end());
  return len[len.size() / 2];
}

void Renderer::draw(const Frame& frame, const Camera& camera, const ViewOptions& o, int x, int y, int w, int h) {
  Impl& r = *impl_;
  r.stats = DrawStats{};
  if (w <= 0 || h <= 0) return;
  const float aspect = static_cast<float>(w) / h;

  glViewport(x, y, w, h);
  glEnable(GL_SCISSOR_TEST);
  glScissor(x, y, w, h);
  glClearColor(o.background_bottom[0], o.background_bottom[1], o.background_bottom[2], 1.0f);
  glClearDepth(1.0);
  glDepthMask(GL_TRUE);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glDisable(GL_BLEND);

  // Lower internal resolution for the background and the fabric (render_scale < 1):
  // only into single-sampled targets (the upscale pass writes depth per pixel).
  GLint target_draw = 0, target_read = 0, target_samples = 0;
  glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &target_draw);
  glGetIntegerv(GL_READ_FRAMEBUFFER_BINDING, &target_read);
  glGetIntegerv(GL_SAMPLES, &target_samples);
  const float scale = std::clamp(o.render_scale, 0.25f, 1.0f);
  const bool low = scale < 0.999f && target_samples <= 1;
  const int fw = low ? std::max(1, static_cast<int>(std::lround(w * scale))) : w;
  const int fh = low ? std::max(1, static_cast<int>(std::lround(h * scale))) : h;
  r.stats.fabric_width = fw;
  r.stats.fabric_height = fh;
  if (low) {
    r.ensure_low_target(fw, fh);
    glBindFramebuffer(GL_FRAMEBUFFER, r.low_fbo);
    glViewport(0, 0, fw, fh);
    glScissor(0, 0, fw, fh);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  }

  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glEnable(GL_CULL_FACE);
  glCullFace(GL_BACK);
  glFrontFace(GL_CCW);
  glEnable(GL_CLIP_DISTANCE0);

  const Mat4 vp = camera.view_projection(aspect);
  const Vec3 eye = camera.eye();
  // Lights ride with the camera (a key from upper left, a weak fill from lower right), so
  // every preset, including the back view, is lit from the viewer's side.
  const Vec3 fwd = camera.forward(), rt = camera.right(), upv = camera.up();
  const Vec3 key_dir = normalize(fwd * -0.75f + upv * 0.55f + rt * -0.35f);
  const Vec3 fill_dir = normalize(fwd * -0.5f + upv * -0.4f + rt * 0.6f);
  const bool cut = o.section_cut || o.view == ViewPreset::section;
  const std::array<float, 4> clip =
      cut ? std::array<float, 4>{0, 1, 0, -frame.projectile_pos[1]} : std::array<float, 4>{0, 0, 0, 1};

  // Mirrored copies of the modelled part.
  std::vector<Vec3> mirrors = {{1, 1, 1}};
  if (o.mirror && frame.mirror_x) mirrors.push_back({-1, 1, 1});
  if (o.mirror && frame.mirror_y) {
    const std::size_t n = mirrors.size();
    for (std::size_t i = 0; i < n; ++i) mirrors.push_back({mirrors[i][0], -1, 1});
  }
  r.stats.mirror_copies = static_cast<int>(mirrors.size());
  // Nearest copy first, so the depth test rejects hidden fragments before shading them.
  std::stable_sort(mirrors.begin(), mirrors.end(), [&](const Vec3& p, const Vec3& q) {
    const Vec3 cp{p[0] * 0.5f * frame.half_width_m, p[1] * 0.5f * frame.half_length_m, 0};
    const Vec3 cq{q[0] * 0.5f * frame.half_width_m, q[1] * 0.5f * frame.half_length_m, 0};
    return length(cp - eye) < length(cq - eye);
  });

  // ---- yarn tubes
  float lo = 0, hi = 1;
  field_range(frame, o, &lo, &hi);
  r.stats.range_min = lo;
  r.stats.range_max = hi;
  const std::size_t n_elem = std::min({frame.elem_a.size(), frame.elem_b.size()});
  for (std::size_t e = 0; e < n_elem && e < frame.elem_broken.size(); ++e)
    r.stats.broken_elements += frame.elem_broken[e] ? 1 : 0;

  if (o.show_fabric && n_elem > 0) {
    const float spacing = yarn_spacing(frame);
    const float width = o.yarn_width_m > 0 ? o.yarn_width_m : 0.92f * spacing;
    const float thick = o.yarn_thickness_m > 0 ? o.yarn_thickness_m : frame.yarn_diameter_m;
    r.stats.yarn_width_m = width;
    r.stats.yarn_thickness_m = thick;
    const float strain_scale =
        o.field == ColorField::strain && frame.failure_strain > 0 ? 1.0f / frame.failure_strain : 1.0f;
    const float inv_range = 1.0f / (hi - lo);
    const float max_stub = 0.5f * spacing;

    // Intact elements per node: a broken element leaves a frayed stub only on a node
    // still held by its yarn; nodes whose elements all broke are loose fibre, not drawn.
    r.intact.assign(frame.node_pos.size(), 0);
    for (std::size_t e = 0; e < n_elem; ++e) {
      if (e < frame.elem_broken.size() && frame.elem_broken[e]) continue;
      if (frame.elem_a[e] < r.intact.size()) r.intact[frame.elem_a[e]] = 1;
      if (frame.elem_b[e] < r.intact.size()) r.intact[frame.elem_b[e]] = 1;
    }
    // Yarn width on screen at the camera target decides ribbons or tubes.
    const float view_h_m = 2.0f * camera.distance_m * std::tan(0.5f * camera.fov_y_deg * 3.14159265f / 180.0f);
    const float px_per_m = view_h_m > 0 ? h / view_h_m : 0.0f;
    r.stats.yarn_width_px = width * px_per_m;
    const bool ribbons = o.yarn_geometry == YarnGeometry::ribbons ||
                         (o.yarn_geometry == YarnGeometry::automatic && r.stats.yarn_width_px < o.tube_min_px);
    r.stats.ribbons = ribbons;
    // Level of detail (ribbons only): two consecutive intact elements of a yarn become one
    // when their shared node lies within merge_px of the merged segment on screen and
    // their colours match.
    const float merge_tol_m = ribbons && o.merge_px > 0 && px_per_m > 0 ? o.merge_px / px_per_m : 0.0f;
    auto t_of = [&](std::size_t e) {
      const float value = element_value(frame, o.field, e) * strain_scale;
      return std::clamp((value - lo) * inv_range, 0.0f, 1.0f);
    };
    auto intact_elem = [&](std::size_t e) {
      return e < n_elem && !(e < frame.elem_broken.size() && frame.elem_broken[e]) &&
             frame.elem_a[e] < frame.node_pos.size() && frame.elem_b[e] < frame.node_pos.size();
    };

    // The element leaving each node along its yarn (each node is on one yarn), and which
    // elements a merge already drew.
    if (merge_tol_m > 0) {
      r.next_elem.assign(frame.node_pos.size(), -1);
      for (std::size_t e = 0; e < n_elem; ++e)
        if (frame.elem_a[e] < r.next_elem.size()) r.next_elem[frame.elem_a[e]] = static_cast<std::int32_t>(e);
      r.merged.assign(n_elem, 0);
    }
    r.instances.clear();
    r.instances.reserve(n_elem + 64);
    for (std::size_t e = 0; e < n_elem; ++e) {
      if (merge_tol_m > 0 && r.merged[e]) continue;
      const std::uint32_t ia = frame.elem_a[e], ib = frame.elem_b[e];
      if (ia >= frame.node_pos.size() || ib >= frame.node_pos.size()) continue;
      const auto& a = frame.node_pos[ia];
      const auto& b = frame.node_pos[ib];
      const float t = t_of(e);
      const bool broken = e < frame.elem_broken.size() && frame.elem_broken[e];
      const float kind = e < frame.elem_family.size() && frame.elem_family[e] ? 1.0f : 0.0f;
      if (!broken) {
        const std::size_t n =
            merge_tol_m > 0 && r.next_elem[ib] >= 0 ? static_cast<std::size_t>(r.next_elem[ib]) : n_elem;
        if (n > e && intact_elem(n) && (frame.elem_yarn.size() <= n || frame.elem_yarn[n] == frame.elem_yarn[e])) {
          const float tn = t_of(n);
          const auto& c = frame.node_pos[frame.elem_b[n]];
          const Vec3 pa{a[0], a[1], a[2]}, pb{b[0], b[1], b[2]}, pc{c[0], c[1], c[2]};
          const Vec3 chord = pc - pa;
          const float l2 = dot(chord, chord);
          const float u = l2 > 0 ? std::clamp(dot(pb - pa, chord) / l2, 0.0f, 1.0f) : 0.0f;
          if (std::abs(tn - t) < 0.02f && length(pb - (pa + chord * u)) < merge_tol_m) {
            r.instances.push_back({a[0], a[1], a[2], 0.5f * (t + tn), c[0], c[1], c[2], kind});
            r.merged[n] = 1;  // drawn by this instance
            continue;
          }
        }
        r.instances.push_back({a[0], a[1], a[2], t, b[0], b[1], b[2], kind});
        continue;
      }
      if (!o.show_broken_stubs) continue;
      // Frayed stubs: a short thin piece left on each node, pointing at the lost partner.
      const Vec3 pa{a[0], a[1], a[2]}, pb{b[0], b[1], b[2]};
      const Vec3 d = pb - pa;
      const float len = length(d);
      if (len <= 0) continue;
      const Vec3 s = d * (std::min(0.3f * len, max_stub) / len);
      const Vec3 ea = pa + s, eb = pb - s;
      if (r.intact[ia]) r.instances.push_back({pa[0], pa[1], pa[2], t, ea[0], ea[1], ea[2], 2.0f});
      if (r.intact[ib]) r.instances.push_back({pb[0], pb[1], pb[2], t, eb[0], eb[1], eb[2], 2.0f});
    }

    const int sides = std::clamp(o.tube_sides, 4, 16);
    if (sides != r.ring_sides) r.build_ring(sides);
    r.load_colormap(o.map);

    // Upload only when the instances changed (a camera move redraws the same frame).
    glBindBuffer(GL_ARRAY_BUFFER, r.inst_vbo);
    const std::size_t bytes = r.instances.size() * sizeof(TubeInstance);
    if (bytes > r.inst_capacity) {
      r.inst_capacity = bytes + bytes / 2;
      glBufferData(GL_ARRAY_BUFFER, r.inst_capacity, nullptr, GL_DYNAMIC_DRAW);
      r.uploaded.clear();
    }
    if (r.uploaded.size() != r.instances.size() || std::memcmp(r.uploaded.data(), r.instances.data(), bytes) != 0) {
      glBufferSubData(GL_ARRAY_BUFFER, 0, bytes, r.instances.data());
      r.uploaded = r.instances;
      r.stats.instances_uploaded = true;
    }

    const GLuint prog = ribbons ? r.ribbon_prog : r.tube_prog;

    glUseProgram(prog);
    glUniformMatrix4fv(glGetUniformLocation(prog, "u_view_proj"), 1, GL_FALSE, vp.data());
    glUniform2f(glGetUniformLocation(prog, "u_half_size"), 0.5f * width, 0.5f * thick);
    glUniform4fv(glGetUniformLocation(prog, "u_clip_plane"), 1, clip.data());
    glUniform3fv(glGetUniformLocation(prog, "u_eye"), 1, eye.data());
    glUniform3fv(glGetUniformLocation(prog, "u_key_dir"), 1, key_dir.data());
    glUniform3fv(glGetUniformLocation(prog, "u_fill_dir"), 1, fill_dir.data());
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, r.colormap_tex);
    glUniform1i(glGetUniformLocation(prog, "u_colormap"), 0);
    glBindVertexArray(r.tube_vao);
    const GLint mirror_loc = glGetUniformLocation(prog, "u_mirror");
    if (ribbons) glDisable(GL_CULL_FACE);  // a ribbon always faces the eye; either winding
    for (const Vec3& m : mirrors) {
      glUniform3fv(mirror_loc, 1, m.data());
      if (ribbons)
        glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, static_cast<GLsizei>(r.instances.size()));
      else
        glDrawElementsInstanced(GL_TRIANGLES, r.ring_index_count, GL_UNSIGNED_SHORT, nullptr,
                                static_cast<GLsizei>(r.instances.size()));
    }
    glEnable(GL_CULL_FACE);
    r.stats.tubes_drawn = static_cast<int>(r.instances.size() * mirrors.size());
  }

  // Background after the fabric: only where nothing was drawn (depth still cleared).
  auto draw_background = [&]() {
    if (!o.show_background) return;
    glDepthFunc(GL_LEQUAL);
    glDepthMask(GL_FALSE);
    glUseProgram(r.bg_prog);
    glUniform3fv(glGetUniformLocation(r.bg_prog, "u_top"), 1, o.background_top.data());
    glUniform3fv(glGetUniformLocation(r.bg_prog, "u_bottom"), 1, o.background_bottom.data());
    glBindVertexArray(r.empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_LESS);
  };
  if (low) {
    draw_background();
    // Back to the caller's target; upscale colour and depth into the viewport.
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, static_cast<GLuint>(target_draw));
    glBindFramebuffer(GL_READ_FRAMEBUFFER, static_cast<GLuint>(target_read));
    glViewport(x, y, w, h);
    glScissor(x, y, w, h);
    glDisable(GL_CLIP_DISTANCE0);
    glDepthFunc(GL_ALWAYS);
    glUseProgram(r.upscale_prog);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, r.low_color);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, r.low_depth);
    glUniform1i(glGetUniformLocation(r.upscale_prog, "u_color"), 0);
    glUniform1i(glGetUniformLocation(r.upscale_prog, "u_depth"), 1);
    glUniform2f(glGetUniformLocation(r.upscale_prog, "u_uv_scale"), 1.0f, 1.0f);
    glBindVertexArray(r.empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glActiveTexture(GL_TEXTURE0);
    glDepthFunc(GL_LESS);
    glEnable(GL_CLIP_DISTANCE0);
  }

  // ---- clamps and projectile
  glUseProgram(r.mesh_prog);
  glUniformMatrix4fv(glGetUniformLocation(r.mesh_prog, "u_view_proj"), 1, GL_FALSE, vp.data());
  glUniform4fv(glGetUniformLocation(r.mesh_prog, "u_clip_plane"), 1, clip.data());
  glUniform3fv(glGetUniformLocation(r.mesh_prog, "u_eye"), 1, eye.data());
  glUniform3fv(glGetUniformLocation(r.mesh_prog, "u_key_dir"), 1, key_dir.data());
  glUniform3fv(glGetUniformLocation(r.mesh_prog, "u_fill_dir"), 1, fill_dir.data());
  if (cut) glDisable(GL_CULL_FACE);  // show the inside of cut solids

  if (o.show_clamps) {
    const float W = frame.half_width_m, L = frame.half_length_m;
    const float c = 0.035f * std::max(W, L) * 2.0f;  // jaw width
    const float hz = 0.22f * c;                      // jaw half height
    const Vec3 steel{0.20f, 0.21f, 0.24f};
    auto jaw = [&](float x0, float x1, float y0, float y1) {
      const Vec3 centre{0.5f * (x0 + x1), 0.5f * (y0 + y1), 0.0f};
      const Vec3 ax{0.5f * (x1 - x0), 0, 0}, ay{0, 0.5f * (y1 - y0), 0}, az{0, 0, hz};
      r.draw_mesh(r.box, model_matrix(ax, ay, az, centre), normal_matrix(ax, ay, az), steel, 24.0f, 0.35f);
    };
    const float over = 0.12f * c;  // the jaw grips a strip of fabric
    if (frame.clamped_left) jaw(-W - c, -W + over, -L - 0.15f * c, L + 0.15f * c);
    if (frame.clamped_right) jaw(W - over, W + c, -L - 0.15f * c, L + 0.15f * c);
    if (frame.clamped_bottom) jaw(-W - 0.15f * c, W + 0.15f * c, -L - c, -L + over);
    if (frame.clamped_top) jaw(-W - 0.15f * c, W + 0.15f * c, L - over, L + c);
  }

  if (o.show_projectile && frame.projectile_radius_m > 0) {
    const Vec3 pos{frame.projectile_pos[0], frame.projectile_pos[1], frame.projectile_pos[2]};
    const float R = frame.projectile_radius_m;
    const Vec3 steel{0.55f, 0.57f, 0.62f};
    if (frame.projectile_shape == 0) {
      const Vec3 ax{R, 0, 0}, ay{0, R, 0}, az{0, 0, R};
      r.draw_mesh(r.sphere, model_matrix(ax, ay, az, pos), normal_matrix(ax, ay, az), steel, 60.0f, 0.8f);
    } else {
      // Cylinder / cone: the mesh's +z is the flight direction, `pos` is the nose centre
      // (the point that meets the fabric first), the body trails behind it.
      Vec3 k = normalize(Vec3{frame.projectile_axis[0], frame.projectile_axis[1], frame.projectile_axis[2]});
      if (length(k) == 0) k = {0, 0, -1};
      const Vec3 helper = std::abs(k[0]) < 0.9f ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
      const Vec3 i = normalize(cross(helper, k)), j = cross(k, i);
      const float len = frame.projectile_length_m > 0 ? frame.projectile_length_m : 2 * R;
      const Vec3 ax = i * R, ay = j * R, az = k * len;
      const bool cone = frame.projectile_shape == 2;
      // Cone mesh narrows towards +z: its tip leads, so the tip sits at pos.
      r.draw_mesh(cone ? r.cone : r.cylinder, model_matrix(ax, ay, az, pos - az), normal_matrix(ax, ay, az), steel,
                  60.0f, 0.8f);
    }
  }
  glEnable(GL_CULL_FACE);
  glDisable(GL_CLIP_DISTANCE0);
  if (!low) draw_background();

  // ---- overlay
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  r.draw_overlay(frame, camera, o, w, h);
  glDisable(GL_BLEND);
  glDisable(GL_SCISSOR_TEST);
  glBindVertexArray(0);
  glUseProgram(0);
}

// The colour-bar title on two short lines ("strain /", "failure strain").
static std::vector<std::string> title_lines(ColorField f) {
  const std::string t = field_title(f);
  std::size_t cut = t.find(" / ");
  if (cut != std::string::npos) return {t.substr(0, cut + 2), t.substr(cut + 3)};
  cut = t.find(" (");
  if (cut != std::string::npos) return {t.substr(0, cut), t.substr(cut + 1)};
  return {t};
}

// A round length (1, 2 or 5 x 10^k) near `target`.
static float round_length(float target) {
  if (!(target > 0)) return 0;
  const float p = std::pow(10.0f, std::floor(std::log10(target)));
  for (float m : {5.0f, 2.0f, 1.0f})
    if (m * p <= target) return m * p;
  return p;
}

void Renderer::Impl::draw_overlay(const Frame& frame, const Camera& camera, const ViewOptions& o, int w, int h) {
  overlay.clear();
  const float s = o.ui_scale > 0 ? o.ui_scale : std::max(1.0f, std::round(h / 520.0f));
  const float pad = 5 * s, line = 11 * s;
  const Rgba white{0.95f, 0.96f, 0.98f, 1.0f}, dim{0.78f, 0.81f, 0.87f, 1.0f};
  const Rgba panel{0.02f, 0.03f, 0.05f, 0.45f};
  // Panel height for n text lines.
  auto block = [&](std::size_t n) { return n * line - (line - 7 * s) + 2 * pad; };
  const float aspect = float(w) / float(std::max(1, h));

  // The picked item: a bright line over the element (or the crossing's two nodes) and a
  // ring at its middle, drawn in the copy the user picked.
  auto to_px = [&](const std::array<float, 3>& p, const std::array<float, 3>& m, float* x, float* y) {
    float u = 0, v = 0;
    if (!camera.project(Vec3{p[0] * m[0], p[1] * m[1], p[2] * m[2]}, aspect, &u, &v)) return false;
    *x = u * float(w);
    *y = v * float(h);
    return true;
  };
  auto mark = [&](const std::array<float, 3>& a, const std::array<float, 3>& b) {
    float xa = 0, ya = 0, xb = 0, yb = 0;
    if (!to_px(a, o.highlight_mirror, &xa, &ya) || !to_px(b, o.highlight_mirror, &xb, &yb)) return;
    const Rgba hl{1.0f, 0.2f, 0.85f, 1.0f}, shadow{0, 0, 0, 0.8f};
    overlay.line(xa, ya, xb, yb, 4 * s, shadow);
    overlay.line(xa, ya, xb, yb, 2 * s, hl);
    const float cx = 0.5f * (xa + xb), cy = 0.5f * (ya + yb), r = 7 * s;
    constexpr int n = 20;
    for (int i = 0; i < n; ++i) {
      const float t0 = 6.2831853f * i / n, t1 = 6.2831853f * (i + 1) / n;
      overlay.line(cx + r * std::cos(t0), cy + r * std::sin(t0), cx + r * std::cos(t1), cy + r * std::sin(t1), 1.5f * s,
                   hl);
    }
  };
  const std::size_t np = frame.node_pos.size();
  if (o.highlight_element >= 0 && std::size_t(o.highlight_element) < frame.elem_a.size()) {
    const std::size_t e = std::size_t(o.highlight_element);
    if (frame.elem_a[e] < np && frame.elem_b[e] < np)
      mark(frame.node_pos[frame.elem_a[e]], frame.node_pos[frame.elem_b[e]]);
  }
  if (o.highlight_crossing >= 0 && std::size_t(o.highlight_crossing) < frame.crossing_warp_node.size()) {
    const std::size_t c = std::size_t(o.highlight_crossing);
    const std::uint32_t a = frame.crossing_warp_node[c], b = frame.crossing_weft_node[c];
    if (a < np && b < np) mark(frame.node_pos[a], frame.node_pos[b]);
  }

  // Axes triad, lower left: the world axes as the camera sees them (x red, y green, z blue).
  float corner_x = 2 * pad;
  if (o.show_axes) {
    const float len = 22 * s, cx = 2 * pad + len + 6 * s, cy = h - 2 * pad - len - 6 * s;
    const Vec3 rt = camera.right(), up = camera.up(), fwd = camera.forward();
    struct Axis {
      Vec3 dir;
      Rgba colour;
      const char* name;
    };
    Axis axes[3] = {{{1, 0, 0}, {0.95f, 0.35f, 0.32f, 1}, "x"},
                    {{0, 1, 0}, {0.45f, 0.88f, 0.40f, 1}, "y"},
                    {{0, 0, 1}, {0.40f, 0.62f, 1.0f, 1}, "z"}};
    // Far axes first, so the near ones are drawn on top.
    std::sort(std::begin(axes), std::end(axes),
              [&](const Axis& a, const Axis& b) { return dot(a.dir, fwd) > dot(b.dir, fwd); });
    overlay.rect(cx - len - 6 * s, cy - len - 6 * s, cx + len + 6 * s, cy + len + 6 * s, panel);
    for (const Axis& a : axes) {
      const float dx = dot(a.dir, rt) * len, dy = -dot(a.dir, up) * len;
      overlay.line(cx, cy, cx + dx, cy + dy, 2 * s, a.colour);
      const float lx = cx + 1.2f * dx - 0.5f * OverlayBatch::text_width(a.name, s), ly = cy + 1.2f * dy - 3.5f * s;
      if (std::abs(dx) + std::abs(dy) > 4 * s) overlay.text_shadowed(lx, ly, a.name, s, a.colour);
    }
    corner_x = cx + len + 6 * s + 2 * pad;
  }
  // Scale bar, lower left beside the triad: a round length in mm, true at the camera's
  // target (the fabric's centre plane in the presets).
  if (o.show_scale_bar) {
    const float px_per_m =
        float(h) / (2.0f * camera.distance_m * std::tan(0.5f * camera.fov_y_deg * 3.14159265f / 180));
    const float length_m = round_length(110 * s / px_per_m);
    if (length_m > 0) {
      const float bar = length_m * px_per_m, y = h - 2 * pad - 10 * s;
      char label[32];
      if (length_m >= 1e-3f)
        std::snprintf(label, sizeof label, "%g mm", std::round(length_m * 1e4f) / 10);
      else
        std::snprintf(label, sizeof label, "%g um", std::round(length_m * 1e7f) / 10);
      const float tw = OverlayBatch::text_width(label, s);
      const float x0 = corner_x, x1 = corner_x + bar;
      overlay.rect(x0 - pad, y - line - pad, std::max(x1, x0 + tw) + pad, y + 4 * s + pad, panel);
      overlay.rect(x0, y, x1, y + 3 * s, white);
      overlay.rect(x0, y - 3 * s, x0 + s, y + 3 * s, white);
      overlay.rect(x1 - s, y - 3 * s, x1, y + 3 * s, white);
      overlay.text_shadowed(x0, y - line, label, s, white);
    }
  }

  if (o.show_caption) {
    std::vector<std::string> lines = caption_lines(frame, o);
    std::vector<Rgba> colors(lines.size(), dim);
    colors[0] = white;
    if (frame.perforated) {
      lines.push_back("PERFORATED");
      colors.push_back({1.0f, 0.58f, 0.28f, 1.0f});
    }
    if (stats.broken_elements > 0) {
      lines.push_back(std::to_string(stats.broken_elements * stats.mirror_copies) + " broken");
      colors.push_back(dim);
    }
    float tw = 0;
    for (const auto& l : lines) tw = std::max(tw, OverlayBatch::text_width(l, s));
    const float x0 = 2 * pad, y0 = 2 * pad;
    overlay.rect(x0, y0, x0 + tw + 2 * pad, y0 + block(lines.size()), panel);
    for (std::size_t i = 0; i < lines.size(); ++i)
      overlay.text_shadowed(x0 + pad, y0 + pad + i * line, lines[i], s, colors[i]);
  }

  if (o.show_colorbar) {
    const std::vector<std::string> title = title_lines(o.field);
    const float bar_w = 8 * s, bar_h = std::min(0.4f * h, 110.0f * s);
    const float right = w - 2 * pad;  // panel's right edge
    const float x1 = right - pad, x0 = x1 - bar_w;
    const float y0 = 2 * pad + block(title.size()) + 2 * s, y1 = y0 + bar_h;
    const std::vector<std::string> legend = {"warp (y)", "weft (x)"};
    float tw = 0;
    for (const auto& l : title) tw = std::max(tw, OverlayBatch::text_width(l, s));
    for (const auto& l : legend) tw = std::max(tw, OverlayBatch::text_width(l, s) + 10 * s);
    const float lo = stats.range_min, hi = stats.range_max;
    constexpr int ticks = 5;
    std::vector<std::string> labels;
    float label_w = 0;
    for (int i = 0; i < ticks; ++i) {
      labels.push_back(format_number(lo + (hi - lo) * i / (ticks - 1)));
      label_w = std::max(label_w, OverlayBatch::text_width(labels.back(), s));
    }
    tw = std::max(tw, bar_w + 5 * s + label_w);
    const float left = right - tw - 2 * pad;
    const float legend_y = y1 + 0.8f * line;
    overlay.rect(left, 2 * pad, right, legend_y + block(legend.size()) - pad, panel);
    for (std::size_t i = 0; i < title.size(); ++i)
      overlay.text_shadowed(x1 - OverlayBatch::text_width(title[i], s), 3 * pad + i * line, title[i], s, white);
    constexpr int steps = 64;
    for (int i = 0; i < steps; ++i) {  // top of the bar is the high end
      const float t1 = 1.0f - static_cast<float>(i) / steps, t0 = 1.0f - static_cast<float>(i + 1) / steps;
      const Vec3 c1 = colormap(o.map, t1), c0 = colormap(o.map, t0);
      const Rgba a{c1[0], c1[1], c1[2], 1}, b{c0[0], c0[1], c0[2], 1};
      overlay.quad(x0, y0 + bar_h * i / steps, x1, y0 + bar_h * (i + 1) / steps, a, a, b, b);
    }
    for (int i = 0; i < ticks; ++i) {
      const float yy = y1 - bar_h * i / (ticks - 1);
      overlay.rect(x0 - 3 * s, yy - 0.5f * s, x0, yy + 0.5f * s, white);
      overlay.text_shadowed(x0 - 5 * s - OverlayBatch::text_width(labels[i], s), yy - 3.5f * s, labels[i], s, white);
    }
    // Warp / weft: the two shades the tubes use for a mid-range colour.
    const Vec3 mid = colormap(o.map, 0.5f);
    const Rgba shade[2] = {{mid[0], mid[1], mid[2], 1}, {mid[0] * 0.72f, mid[1] * 0.72f, mid[2] * 0.72f, 1}};
    for (int k = 0; k < 2; ++k) {
      const float ly = legend_y + k * line;
      const float tx = x1 - OverlayBatch::text_width(legend[k], s);
      overlay.rect(tx - 10 * s, ly, tx - 3 * s, ly + 7 * s, shade[k]);
      overlay.text_shadowed(tx, ly, legend[k], s, dim);
    }
  }

  const auto& v = overlay.vertices();
  if (v.empty()) return;
  glUseProgram(overlay_prog);
  glUniform2f(glGetUniformLocation(overlay_prog, "u_viewport"), static_cast<float>(w), static_cast<float>(h));
  glBindVertexArray(overlay_vao);
  glBindBuffer(GL_ARRAY_BUFFER, overlay_vbo);
  const std::size_t bytes = v.size() * sizeof(OverlayVertex);
  if (bytes > overlay_capacity) {
    overlay_capacity = bytes * 2;
    glBufferData(GL_ARRAY_BUFFER, overlay_capacity, nullptr, GL_DYNAMIC_DRAW);
  }
  glBufferSubData(GL_ARRAY_BUFFER, 0, bytes, v.data());
  glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(v.size()));
}

GLuint link_program(const char* vert, const char* frag) {
  GLuint vs = compile(GL_VERTEX_SHADER, vert), fs = compile(GL_FRAGMENT_SHADER, frag);
  GLuint p = glCreateProgram();
  glAttachShader(p, vs);
  glAttachShader(p, fs);
  glLinkProgram(p);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetProgramInfoLog(p, sizeof log, nullptr, log);
    glDeleteProgram(p);
    throw std::runtime_error(std::string("program ") + vert + "+" + frag + ": " + log);
  }
  return p;
}

}  // namespace ravel::render
