#version 330 core
// Upscales the fabric drawn at a lower internal resolution (ViewOptions::render_scale)
// into the viewport: colour filtered, depth copied (nearest) so the projectile and the
// clamps, drawn afterwards at full resolution, are still hidden by fabric in front.
// Vertex shader: background.vert (a full-viewport triangle, v_uv in [0, 1]).
in vec2 v_uv;
uniform sampler2D u_color;
uniform sampler2D u_depth;
uniform vec2 u_uv_scale;  // the part of the textures the low-resolution pass used
out vec4 o_color;
void main() {
  vec2 uv = v_uv * u_uv_scale;
  o_color = vec4(texture(u_color, uv).rgb, 1.0);
  gl_FragDepth = texture(u_depth, uv).r;
}
