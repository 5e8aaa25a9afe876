#version 330 core
// Shading of a yarn ribbon (ribbon.vert): the elliptic tube's normal rebuilt per pixel,
// then the same key + fill + sheen + rim as tube.frag, with the powers unrolled into
// multiplications (llvmpipe is fragment bound at large sizes).
in vec3 v_nw;
in vec3 v_nu;
in float v_s;
in vec3 v_view;
in vec3 v_half;  // unit, half way between the key light and the eye
in vec3 v_color;

uniform vec3 u_key_dir;   // towards the key light (unit)
uniform vec3 u_fill_dir;  // towards the fill light (unit)

out vec4 o_color;

void main() {
  float s = clamp(v_s, -1.0, 1.0);
  vec3 n = normalize(s * v_nw + sqrt(1.0 - s * s) * v_nu);
  vec3 v = v_view;
  float key = max(dot(n, u_key_dir), 0.0);
  float fill = max(dot(n, u_fill_dir), 0.0);
  float x = max(dot(n, v_half), 0.0);
  float x2 = x * x, x4 = x2 * x2, x8 = x4 * x4, x16 = x8 * x8, x32 = x16 * x16;
  float spec = x32 * x8 * 0.35;  // x^40: aramid has a soft sheen
  float r = 1.0 - max(dot(n, v), 0.0);
  float rim = r * r * r * 0.15;
  vec3 c = v_color * (0.22 + 0.78 * key + 0.25 * fill) + vec3(spec + rim);
  o_color = vec4(c, 1.0);
}
