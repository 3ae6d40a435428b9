
// Pixel rectangles (x0, y0, x1, y1), two triangles each.
layout(binding = 6) uniform isamplerBuffer u_rects;
uniform vec2 u_viewport;
void main() {
  ivec4 q = texelFetch(u_rects, gl_VertexID / 6);
  int corner = gl_VertexID % 6;
  corner = corner < 3 ? corner : corner - 2;  // 0 1 2, 1 2 3
  vec2 p = vec2((corner & 1) != 0 ? q.z : q.x, (corner & 2) != 0 ? q.w : q.y);
  gl_Position = vec4(2.0 * p / u_viewport - 1.0, 0.0, 1.0);
}
