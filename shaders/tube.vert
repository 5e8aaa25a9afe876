#version 330 core
// One yarn element = one instance of a short tube with an elliptic cross-section
// (width across in the fabric plane, thickness through it).
layout(location = 0) in vec3 a_ring;  // cos(angle), sin(angle), end (0 at node a, 1 at b)
layout(location = 1) in vec4 i_a;     // node a (m), colour-map coordinate in [0, 1]
layout(location = 2) in vec4 i_b;     // node b (m), kind: 0 warp, 1 weft, 2 broken stub

uniform mat4 u_view_proj;
uniform vec3 u_mirror;      // +-1 per axis: which mirrored copy of the modelled part
uniform vec2 u_half_size;   // half width, half thickness (m)
uniform vec4 u_clip_plane;  // keep dot(p, xyz) + w >= 0
uniform sampler2D u_colormap;

out vec3 v_world;
out vec3 v_normal;
out vec3 v_color;
flat out float v_kind;

void main() {
  vec3 a = i_a.xyz * u_mirror;
  vec3 b = i_b.xyz * u_mirror;
  vec3 d = b - a;
  float len = length(d);
  vec3 t = len > 1e-12 ? d / len : vec3(1.0, 0.0, 0.0);
  // "side" lies in the fabric plane across the yarn, "up" through the fabric.
  vec3 side = cross(t, vec3(0.0, 0.0, 1.0));
  if (dot(side, side) < 1e-6) side = cross(t, vec3(1.0, 0.0, 0.0));
  side = normalize(side);
  vec3 up = cross(side, t);

  float kind = i_b.w;
  vec2 hs = u_half_size * (kind > 1.5 ? 0.55 : 1.0);  // stubs fray thinner
  vec3 p = mix(a, b, a_ring.z) + a_ring.x * hs.x * side + a_ring.y * hs.y * up;
  v_normal = normalize(a_ring.x / hs.x * side + a_ring.y / hs.y * up);
  v_world = p;
  vec3 c = texture(u_colormap, vec2(i_a.w, 0.5)).rgb;
  // Weft a shade darker than warp so the two families read apart at any colour.
  if (kind > 0.5 && kind < 1.5) c *= 0.72;
  if (kind > 1.5) c = mix(c, vec3(0.25, 0.22, 0.2), 0.45);
  v_color = c;
  v_kind = kind;
  gl_ClipDistance[0] = dot(p, u_clip_plane.xyz) + u_clip_plane.w;
  gl_Position = u_view_proj * vec4(p, 1.0);
}
