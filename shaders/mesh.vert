#version 330 core
// Lit solid meshes: the projectile and the clamps.
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;
uniform mat4 u_view_proj;
uniform mat4 u_model;
uniform mat3 u_normal_matrix;
uniform vec4 u_clip_plane;
out vec3 v_world;
out vec3 v_normal;
void main() {
  vec4 p = u_model * vec4(a_pos, 1.0);
  v_world = p.xyz;
  v_normal = u_normal_matrix * a_normal;
  gl_ClipDistance[0] = dot(p.xyz, u_clip_plane.xyz) + u_clip_plane.w;
  gl_Position = u_view_proj * p;
}
