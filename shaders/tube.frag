#version 330 core
in vec3 v_world;
in vec3 v_normal;
in vec3 v_color;
flat in float v_kind;

uniform vec3 u_eye;
uniform vec3 u_key_dir;   // towards the key light (unit)
uniform vec3 u_fill_dir;  // towards the fill light (unit)

out vec4 o_color;

void main() {
  vec3 n = normalize(v_normal);
  vec3 v = normalize(u_eye - v_world);
  if (dot(n, v) < 0.0) n = -n;  // seen through an open stub end
  float key = max(dot(n, u_key_dir), 0.0);
  float fill = max(dot(n, u_fill_dir), 0.0);
  vec3 h = normalize(u_key_dir + v);
  float spec = pow(max(dot(n, h), 0.0), 40.0) * 0.35;  // aramid has a soft sheen
  float rim = pow(1.0 - max(dot(n, v), 0.0), 3.0) * 0.15;
  vec3 c = v_color * (0.22 + 0.78 * key + 0.25 * fill) + vec3(spec + rim);
  o_color = vec4(c, 1.0);
}
