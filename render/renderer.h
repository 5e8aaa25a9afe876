// Renderer: draws one frozen ravel::Frame with OpenGL 3.3 core.
//
// The renderer never sees the solver: it draws a Frame (a copy taken under the
// simulation's lock) into whatever context is current, a GLFW window or an OSMesa
// offscreen buffer. Yarn elements are instanced tubes with a flattened (elliptic)
// cross-section of the yarn's real width and thickness, coloured by a field through a
// colour map; the modelled quarter / half is mirrored by drawing the same instance
// buffer again with a sign flip. See docs/rendering.md.
//
// This header includes no GL header, so it can sit next to GLFW or ImGui in the app.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/frame.h"

namespace ravel::render {

using Vec3 = std::array<float, 3>;

// ---------------------------------------------------------------------------------------
// GL loading. Call once a context is current (and again after switching to a context of
// another kind), with glfwGetProcAddress or OSMesaGetProcAddress (cast as needed).
using GlProcLoader = void* (*)(const char* name);
bool load_gl(GlProcLoader loader, std::string* error = nullptr);

// ---------------------------------------------------------------------------------------
// Fields and colour maps.
enum class ColorField { strain, velocity, sliding, friction };
const char* to_string(ColorField f);
bool parse_color_field(const std::string& name, ColorField* out);
// The names parse_color_field accepts, for messages: "strain, velocity, sliding or friction".
std::string color_field_names();
// Colour-bar title with units, e.g. "strain / failure strain", "speed (m/s)".
const char* field_title(ColorField f);

enum class ColorMap { turbo, viridis, inferno, gray };
const char* to_string(ColorMap m);
bool parse_color_map(const std::string& name, ColorMap* out);
// The map at t in [0, 1] (clamped), linear RGB in [0, 1].
Vec3 colormap(ColorMap map, float t);

// ---------------------------------------------------------------------------------------
// Camera. An orbit camera around a target point. World z is "up" (the projectile comes
// from +z); yaw turns about z, pitch lifts above the fabric plane (+90 = looking down on
// the impact face, -90 = looking up at the back face).
enum class ViewPreset { oblique, top, back, section };
const char* to_string(ViewPreset v);
bool parse_view_preset(const std::string& name, ViewPreset* out);
// The names parse_view_preset accepts, for messages: "oblique, top, back or section".
std::string view_preset_names();

class Camera {
 public:
  Vec3 target{0, 0, 0};
  float distance_m = 0.3f;
  float yaw_deg = -60.0f;
  float pitch_deg = 35.0f;
  float fov_y_deg = 30.0f;

  // Orientation of a preset (target and distance untouched; call fit() after).
  static Camera preset(ViewPreset v);

  // Move target and distance so the whole (mirrored) fabric fills the view with a
  // margin, keeping the orientation. `aspect` = width / height.
  void fit(const Frame& frame, float aspect, float margin = 1.06f);
  // Fit an axis-aligned box instead.
  void fit_box(const Vec3& lo, const Vec3& hi, float aspect, float margin = 1.06f);

  // Interaction for the app.
  void orbit(float d_yaw_deg, float d_pitch_deg);  // pitch is clamped to [-90, 90]
  void zoom(float factor);                         // distance *= factor (> 0)
  void pan(float dx, float dy);                    // in units of the view height at the target

  Vec3 eye() const;
  Vec3 forward() const;  // unit, from eye towards target
  Vec3 right() const;    // unit, screen right
  Vec3 up() const;       // unit, screen up

  // Column-major 4x4 matrices (OpenGL convention).
  std::array<float, 16> view_matrix() const;
  std::array<float, 16> projection_matrix(float aspect) const;
  std::array<float, 16> view_projection(float aspect) const;

  // Where a world point lands in an image of the given aspect: u, v in [0, 1] with
  // (0, 0) the top-left corner (image rows run top to bottom). False if behind the eye.
  bool project(const Vec3& world, float aspect, float* u, float* v) const;
};

// The preset camera for `view`, fitted to the frame.
Camera fitted_camera(const Frame& frame, ViewPreset view, float aspect);

// ---------------------------------------------------------------------------------------
// What to draw and how.

// How yarn elements are drawn. `tubes`: instanced tubes of `tube_sides` sides. `ribbons`:
// flat strips turned towards the eye whose fragment shader rebuilds the elliptic tube's
// normal per pixel: the same outline and (smoother) shading at 4 vertices per element
// instead of 2 x sides, several times cheaper under a software GL. `automatic`: ribbons
// unless the yarn is wider on screen than `tube_min_px`, then tubes (close-ups, where
// the real geometry of joints and cut ends shows).
enum class YarnGeometry { automatic, tubes, ribbons };
const char* to_string(YarnGeometry g);
bool parse_yarn_geometry(const std::string& name, YarnGeometry* out);

struct ViewOptions {
  ViewPreset view = ViewPreset::oblique;  // used by the headless helpers to build a Camera;
                                          // `section` also cuts the scene (see below)
  ColorField field = ColorField::strain;
  ColorMap map = ColorMap::turbo;
  // Colour range in the field's units; min >= max means the field's default range:
  // strain [0, 1] of failure strain, velocity [0, impact velocity], sliding [0, max in frame].
  float range_min = 0.0f, range_max = 0.0f;

  bool mirror = true;  // show the full fabric when the frame holds a quarter / half
  bool show_fabric = true;
  bool show_projectile = true;
  bool show_clamps = true;
  bool show_broken_stubs = true;  // frayed stubs where an element broke
  bool show_colorbar = true;
  bool show_caption = true;
  bool show_scale_bar = true;  // a bar of a round length in mm, true at the camera's target depth
  bool show_axes = true;       // x / y / z triad in the lower left corner, turning with the camera

  // A picked item drawn over the fabric (render/picking.h): the element (modelled index) in
  // the copy mirrored by highlight_mirror, or a crossing's two tracked nodes. -1 = none.
  int highlight_element = -1;
  int highlight_crossing = -1;
  std::array<float, 3> highlight_mirror{1, 1, 1};
  bool show_background = true;  // gradient; otherwise clear to background_bottom

  // Cut away y < (projectile y) to show a section through the impact point. Always on
  // for view == section.
  bool section_cut = false;

  // Tube cross-section: an ellipse, `yarn_width_m` across in the fabric plane and
  // `yarn_thickness_m` through it. 0 = automatic: width 0.92 x the yarn spacing measured
  // from the frame, thickness = frame.yarn_diameter_m (the contact diameter D).
  float yarn_width_m = 0.0f;
  float yarn_thickness_m = 0.0f;
  int tube_sides = 8;  // 4..16
  YarnGeometry yarn_geometry = YarnGeometry::automatic;
  float tube_min_px = 16.0f;  // automatic: tubes when the yarn is at least this wide on screen
  // Level of detail for ribbons: merge two consecutive elements of a yarn into one when
  // their shared node is within this many pixels of the merged segment and their colours
  // match (0 = off, the default: every element is drawn). For interactive views in motion.
  float merge_px = 0.0f;

  // Draw the background and the fabric at this fraction of the viewport's resolution and
  // upscale them (0.25..1; 1 = off). The projectile, the clamps and the overlay are still
  // drawn at full resolution, so they stay crisp. For interactive views while a run plays;
  // exported images keep 1.
  float render_scale = 1.0f;

  float ui_scale = 0.0f;  // text / colour-bar scale; 0 = from the viewport height

  Vec3 background_top{0.36f, 0.40f, 0.48f};
  Vec3 background_bottom{0.08f, 0.09f, 0.12f};
};

// Numbers the renderer derived for the last frame (for tests, the app and the bench).
struct DrawStats {
  int tubes_drawn = 0;      // tube / ribbon instances including mirrored copies and stubs
  int broken_elements = 0;  // in the modelled part
  int mirror_copies = 1;    // 1, 2 or 4
  float yarn_width_m = 0, yarn_thickness_m = 0;
  float range_min = 0, range_max = 0;       // colour range actually used
  bool ribbons = false;                     // yarns drawn as ribbons (else tubes)
  float yarn_width_px = 0;                  // yarn width on screen at the camera target
  int fabric_width = 0, fabric_height = 0;  // resolution the fabric was drawn at
  bool instances_uploaded = false;          // false when the instance buffer already held them
};

// The colour range a field uses for a frame under `options`.
void field_range(const Frame& frame, const ViewOptions& options, float* lo, float* hi);
// Several frames drawn side by side with one colour bar (demos, compare): a field scaled
// from the data (sliding, friction) gets one range for all, the largest of their own; the
// other fields, and a range already set, are left as they are.
void share_field_range(const std::vector<const Frame*>& frames, ViewOptions* o);
// The caption text the renderer prints (one line per entry).
std::vector<std::string> caption_lines(const Frame& frame, const ViewOptions& options);

// ---------------------------------------------------------------------------------------
// Renderer. Construct with a current context whose GL entry points are loaded (load_gl);
// use and destroy it with the same context current. Throws std::runtime_error when a
// shader fails to compile. No global state: one per context.
class Renderer {
 public:
  Renderer();
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Draw `frame` into the viewport (x, y, w, h) of the framebuffer currently bound, in
  // GL window coordinates (y up). Clears that rectangle (colour and depth) first.
  void draw(const Frame& frame, const Camera& camera, const ViewOptions& options, int x, int y, int w, int h);

  const DrawStats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// ---------------------------------------------------------------------------------------
// Headless rendering with OSMesa (llvmpipe, GL core profile). Draws into a multisampled
// framebuffer object and reads it back top row first.
class OffscreenContext {
 public:
  // Returns nullptr (and says why) when OSMesa cannot give a 3.3+ core context.
  static std::unique_ptr<OffscreenContext> create(int width, int height, int samples = 4, std::string* error = nullptr);
  ~OffscreenContext();
  OffscreenContext(const OffscreenContext&) = delete;
  OffscreenContext& operator=(const OffscreenContext&) = delete;

  // Make this context current, (re)load GL entry points and bind its framebuffer.
  bool make_current();
  bool resize(int width, int height);
  int width() const;
  int height() const;
  // Resolve and read the image: RGB, 3 bytes per pixel, top row first.
  std::vector<std::uint8_t> read_rgb();
  std::string gl_version() const;   // e.g. "4.5 (Core Profile) Mesa 22.3.6"
  std::string gl_renderer() const;  // e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"

 private:
  OffscreenContext();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// An offscreen context plus a renderer, reused across images (shader compilation and
// context creation are paid once).
class HeadlessRenderer {
 public:
  static std::unique_ptr<HeadlessRenderer> create(std::string* error = nullptr);
  ~HeadlessRenderer();

  // Render with the preset camera of options.view fitted to the frame.
  bool render(const Frame& frame, const ViewOptions& options, int width, int height, std::vector<std::uint8_t>* rgb,
              std::string* error = nullptr);
  // Render with a given camera.
  bool render(const Frame& frame, const Camera& camera, const ViewOptions& options, int width, int height,
              std::vector<std::uint8_t>* rgb, std::string* error = nullptr);
  bool render_png(const Frame& frame, const ViewOptions& options, int width, int height, const std::string& path,
                  std::string* error = nullptr);

  OffscreenContext& context();
  Renderer& renderer();
  const DrawStats& stats() const;

 private:
  HeadlessRenderer();
  std::unique_ptr<OffscreenContext> context_;
  std::unique_ptr<Renderer> renderer_;
};

// One-shot helper: render `frame` offscreen and write a PNG atomically.
bool render_frame_png(const Frame& frame, const ViewOptions& options, int width, int height, const std::string& path,
                      std::string* error = nullptr);

// Write an RGB image (top row first) as PNG: to a temporary name in the same folder,
// then renamed, so a reader never sees half a file.
bool write_png(const std::string& path, int width, int height, const std::vector<std::uint8_t>& rgb,
               std::string* error = nullptr);

}  // namespace ravel::render
