
uniform vec3 u_corner[4];  // camera-relative billboard corners, in triangle-strip order
uniform vec3 u_clip_x;     // right / (tan(vfov/2) aspect)
uniform vec3 u_clip_y;     // up / tan(vfov/2)
uniform vec3 u_clip_w;     // forward
out vec2 v_uv;
out vec3 v_position;
void main() {
  vec3 p = u_corner[gl_VertexID];
  v_position = p;
  v_uv = vec2(gl_VertexID & 1, gl_VertexID >> 1);
  gl_Position = vec4(dot(p, u_clip_x), dot(p, u_clip_y), 0.0, dot(p, u_clip_w));
}
