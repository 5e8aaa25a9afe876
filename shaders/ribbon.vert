#version 330 core
// One yarn element as a flat ribbon that always faces the eye: an impostor for the
// elliptic tube of tube.vert with the same silhouette and per-pixel normals, at 4
// vertices and 2 triangles per element instead of 2 x sides vertices and triangles
// (llvmpipe spends most of a fabric draw on vertices and triangle set-up).
//
// The cross-section is the ellipse A * unit circle, A = diag(half width, half thickness)
// in the (side, up) frame. Mapped by A^-1 to the unit circle, the eye direction becomes
// u, the silhouette points are +-w (w perpendicular to u), and the visible point at
// screen parameter s in [-1, 1] is q = s w + sqrt(1 - s^2) u, which lies on the screen
// line through A (+-w): the ribbon spans exactly the tube's outline. Its normal is A^-1 q.
// Vertices come from gl_VertexID (a 4-vertex triangle strip), no vertex buffer.
layout(location = 1) in vec4 i_a;  // node a (m), colour-map coordinate in [0, 1]
layout(location = 2) in vec4 i_b;  // node b (m), kind: 0 warp, 1 weft, 2 broken stub

uniform mat4 u_view_proj;
uniform vec3 u_mirror;
uniform vec2 u_half_size;   // half width, half thickness (m)
uniform vec4 u_clip_plane;  // keep dot(p, xyz) + w >= 0
uniform vec3 u_eye;
uniform vec3 u_key_dir;  // towards the key light (unit)
uniform sampler2D u_colormap;

out vec3 v_nw;     // A^-1 w: the normal at the ribbon's edges
out vec3 v_nu;     // A^-1 u: the normal facing the eye
out float v_s;     // -1 .. 1 across the ribbon
out vec3 v_view;   // unit, towards the eye
out vec3 v_half;   // unit, half way between the key light and the eye
out vec3 v_color;

void main() {
  float s = (gl_VertexID & 1) != 0 ? 1.0 : -1.0;
  float end = float(gl_VertexID >> 1);
  vec3 a = i_a.xyz * u_mirror;
  vec3 b = i_b.xyz * u_mirror;
  vec3 d = b - a;
  float len = length(d);
  vec3 t = len > 1e-12 ? d / len : vec3(1.0, 0.0, 0.0);
  vec3 side = cross(t, vec3(0.0, 0.0, 1.0));
  if (dot(side, side) < 1e-6) side = cross(t, vec3(1.0, 0.0, 0.0));
  side = normalize(side);
  vec3 up = cross(side, t);

  float kind = i_b.w;
  vec2 hs = u_half_size * (kind > 1.5 ? 0.55 : 1.0);  // stubs fray thinner
  vec3 c0 = mix(a, b, end);
  vec3 e = u_eye - c0;
  vec2 u = vec2(dot(e, side) / hs.x, dot(e, up) / hs.y);
  float lu = length(u);
  u = lu > 1e-20 ? u / lu : vec2(0.0, 1.0);
  vec2 w = vec2(-u.y, u.x);
  vec3 p = c0 + s * (w.x * hs.x * side + w.y * hs.y * up);
  // Scaled by the half thickness so both stay near unit length (the fragment normalizes).
  v_nw = hs.y * (w.x / hs.x * side + w.y / hs.y * up);
  v_nu = hs.y * (u.x / hs.x * side + u.y / hs.y * up);
  v_s = s;
  v_view = normalize(e);
  v_half = normalize(u_key_dir + v_view);
  vec3 c = texture(u_colormap, vec2(i_a.w, 0.5)).rgb;
  if (kind > 0.5 && kind < 1.5) c *= 0.72;  // weft a shade darker than warp
  if (kind > 1.5) c = mix(c, vec3(0.25, 0.22, 0.2), 0.45);
  v_color = c;
  gl_ClipDistance[0] = dot(p, u_clip_plane.xyz) + u_clip_plane.w;
  gl_Position = u_view_proj * vec4(p, 1.0);
}
