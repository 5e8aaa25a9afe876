#version 330 core
in vec3 v_world;
in vec3 v_normal;
uniform vec3 u_eye;
uniform vec3 u_key_dir;
uniform vec3 u_fill_dir;
uniform vec3 u_color;
uniform float u_shininess;
uniform float u_specular;
out vec4 o_color;
void main() {
  vec3 n = normalize(v_normal);
  vec3 v = normalize(u_eye - v_world);
  if (!gl_FrontFacing) {  // inside of a cut solid
    o_color = vec4(u_color * 0.6 + vec3(0.04), 1.0);
    return;
  }
  float key = max(dot(n, u_key_dir), 0.0);
  float fill = max(dot(n, u_fill_dir), 0.0);
  vec3 h = normalize(u_key_dir + v);
  float spec = pow(max(dot(n, h), 0.0), u_shininess) * u_specular;
  // A cheap environment term: steel reflects a bright sky above, a dark floor below.
  vec3 r = reflect(-v, n);
  float sky = 0.5 + 0.5 * r.z;
  vec3 env = mix(vec3(0.10, 0.10, 0.12), vec3(0.75, 0.80, 0.90), sky) * u_specular * 0.45;
  float rim = pow(1.0 - max(dot(n, v), 0.0), 3.0) * 0.2;
  vec3 c = u_color * (0.18 + 0.75 * key + 0.25 * fill) + vec3(spec + rim) + env;
  o_color = vec4(c, 1.0);
}
