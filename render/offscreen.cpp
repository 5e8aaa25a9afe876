// OSMesa offscreen context and the headless render helpers.
//
// OSMesa renders into a client buffer (its default framebuffer, rows bottom-up). We draw
// into our own multisampled framebuffer object instead, resolve it into a plain one and
// read that back, flipping the rows so images come out top row first.
#include <algorithm>
#include <cstring>

#include "render/gl.h"
#include "render/osmesa_backend.h"
#include "render/renderer.h"

namespace ravel::render {

struct OffscreenContext::Impl {
  void* context = nullptr;
  std::vector<std::uint8_t> buffer;  // OSMesa's own framebuffer (unused but required)
  int width = 0, height = 0, samples = 0;
  GLuint ms_fbo = 0, ms_color = 0, ms_depth = 0;  // drawn into
  GLuint fbo = 0, color = 0, depth = 0;           // resolved (or drawn into when samples <= 1)
  bool loaded = false;

  void free_targets() {
    GLuint fbos[] = {ms_fbo, fbo};
    GLuint rbs[] = {ms_color, ms_depth, color, depth};
    glDeleteFramebuffers(2, fbos);
    glDeleteRenderbuffers(4, rbs);
    ms_fbo = ms_color = ms_depth = fbo = color = depth = 0;
  }

  bool make_targets(std::string* error) {
    if (ms_fbo || fbo) free_targets();
    auto attach = [&](GLuint* f, GLuint* c, GLuint* d, int s) {
      glGenFramebuffers(1, f);
      glGenRenderbuffers(1, c);
      glGenRenderbuffers(1, d);
      glBindFramebuffer(GL_FRAMEBUFFER, *f);
      glBindRenderbuffer(GL_RENDERBUFFER, *c);
      glRenderbufferStorageMultisample(GL_RENDERBUFFER, s, GL_RGBA8, width, height);
      glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, *c);
      glBindRenderbuffer(GL_RENDERBUFFER, *d);
      glRenderbufferStorageMultisample(GL_RENDERBUFFER, s, GL_DEPTH_COMPONENT24, width, height);
      glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, *d);
      return glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
    };
    if (!attach(&fbo, &color, &depth, 0)) {
      if (error) *error = "offscreen framebuffer incomplete";
      return false;
    }
    if (samples > 1 && !attach(&ms_fbo, &ms_color, &ms_depth, samples)) {
      if (error) *error = "multisampled offscreen framebuffer incomplete";
      return false;
    }
    glBindFramebuffer(GL_FRAMEBUFFER, samples > 1 ? ms_fbo : fbo);
    return true;
  }
};

OffscreenContext::OffscreenContext() : impl_(std::make_unique<Impl>()) {}

OffscreenContext::~OffscreenContext() {
  if (impl_->context) {
    if (impl_->loaded && make_current()) impl_->free_targets();
    osmesa::destroy_context(impl_->context);
  }
}

std::unique_ptr<OffscreenContext> OffscreenContext::create(int width, int height, int samples, std::string* error) {
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384) {
    if (error) *error = "image size out of range (1..16384)";
    return nullptr;
  }
  std::unique_ptr<OffscreenContext> c(new OffscreenContext());
  c->impl_->context = osmesa::create_context(error);
  if (!c->impl_->context) return nullptr;
  c->impl_->width = width;
  c->impl_->height = height;
  c->impl_->buffer.assign(static_cast<std::size_t>(width) * height * 4, 0);
  if (!osmesa::make_current(c->impl_->context, c->impl_->buffer.data(), width, height)) {
    if (error) *error = "OSMesaMakeCurrent failed";
    return nullptr;
  }
  if (!load_gl(osmesa::get_proc_address, error)) return nullptr;
  c->impl_->loaded = true;
  GLint max_samples = 0;
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  c->impl_->samples = std::clamp(samples, 0, static_cast<int>(max_samples));
  if (!c->impl_->make_targets(error)) return nullptr;
  return c;
}

bool OffscreenContext::make_current() {
  Impl& m = *impl_;
  if (!osmesa::make_current(m.context, m.buffer.data(), m.width, m.height)) return false;
  if (!load_gl(osmesa::get_proc_address)) return false;
  glBindFramebuffer(GL_FRAMEBUFFER, m.samples > 1 ? m.ms_fbo : m.fbo);
  return true;
}

bool OffscreenContext::resize(int width, int height) {
  Impl& m = *impl_;
  if (width == m.width && height == m.height) return make_current();
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384) return false;
  m.width = width;
  m.height = height;
  m.buffer.assign(static_cast<std::size_t>(width) * height * 4, 0);
  if (!make_current()) return false;
  return m.make_targets(nullptr);
}

int OffscreenContext::width() const {
  return impl_->width;
}
int OffscreenContext::height() const {
  return impl_->height;
}

std::vector<std::uint8_t> OffscreenContext::read_rgb() {
  Impl& m = *impl_;
  if (m.samples > 1) {
    glBindFramebuffer(GL_READ_FRAMEBUFFER, m.ms_fbo);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, m.fbo);
    glBlitFramebuffer(0, 0, m.width, m.height, 0, 0, m.width, m.height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  }
  glBindFramebuffer(GL_READ_FRAMEBUFFER, m.fbo);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  const std::size_t row = static_cast<std::size_t>(m.width) * 3;
  std::vector<std::uint8_t> bottom_up(row * m.height), rgb(row * m.height);
  glReadPixels(0, 0, m.width, m.height, GL_RGB, GL_UNSIGNED_BYTE, bottom_up.data());
  for (int y = 0; y < m.height; ++y)  // GL rows are bottom-up; images are top-down
    std::memcpy(&rgb[y * row], &bottom_up[(m.height - 1 - y) * row], row);
  glBindFramebuffer(GL_FRAMEBUFFER, m.samples > 1 ? m.ms_fbo : m.fbo);
  return rgb;
}

std::string OffscreenContext::gl_version() const {
  const GLubyte* s = glGetString(GL_VERSION);
  return s ? reinterpret_cast<const char*>(s) : "";
}

std::string OffscreenContext::gl_renderer() const {
  const GLubyte* s = glGetString(GL_RENDERER);
  return s ? reinterpret_cast<const char*>(s) : "";
}

// ---- HeadlessRenderer ----------------------------------------------------------------------

HeadlessRenderer::HeadlessRenderer() = default;

HeadlessRenderer::~HeadlessRenderer() {
  if (context_ && renderer_) {
    context_->make_current();
    renderer_.reset();  // GL objects die with the context current
  }
}

std::unique_ptr<HeadlessRenderer> HeadlessRenderer::create(std::string* error) {
  std::unique_ptr<HeadlessRenderer> h(new HeadlessRenderer());
  h->context_ = OffscreenContext::create(64, 64, 4, error);
  if (!h->context_) return nullptr;
  try {
    h->renderer_ = std::make_unique<Renderer>();
  } catch (const std::exception& e) {
    if (error) *error = e.what();
    return nullptr;
  }
  return h;
}

bool HeadlessRenderer::render(const Frame& frame, const ViewOptions& options, int width, int height,
                              std::vector<std::uint8_t>* rgb, std::string* error) {
  if (height <= 0) {
    if (error) *error = "bad image size";
    return false;
  }
  const Camera camera = fitted_camera(frame, options.view, static_cast<float>(width) / height);
  return render(frame, camera, options, width, height, rgb, error);
}

bool HeadlessRenderer::render(const Frame& frame, const Camera& camera, const ViewOptions& options, int width,
                              int height, std::vector<std::uint8_t>* rgb, std::string* error) {
  if (!context_->resize(width, height)) {
    if (error) *error = "cannot make an offscreen image of " + std::to_string(width) + "x" + std::to_string(height);
    return false;
  }
  renderer_->draw(frame, camera, options, 0, 0, width, height);
  *rgb = context_->read_rgb();
  const GLenum err = glGetError();
  if (err != GL_NO_ERROR) {
    if (error) *error = "GL error " + std::to_string(err);
    return false;
  }
  return true;
}

bool HeadlessRenderer::render_png(const Frame& frame, const ViewOptions& options, int width, int height,
                                  const std::string& path, std::string* error) {
  std::vector<std::uint8_t> rgb;
  return render(frame, options, width, height, &rgb, error) && write_png(path, width, height, rgb, error);
}

OffscreenContext& HeadlessRenderer::context() {
  return *context_;
}
Renderer& HeadlessRenderer::renderer() {
  return *renderer_;
}
const DrawStats& HeadlessRenderer::stats() const {
  return renderer_->stats();
}

bool render_frame_png(const Frame& frame, const ViewOptions& options, int width, int height, const std::string& path,
                      std::string* error) {
  auto h = HeadlessRenderer::create(error);
  return h && h->render_png(frame, options, width, height, path, error);
}

}  // namespace ravel::render
