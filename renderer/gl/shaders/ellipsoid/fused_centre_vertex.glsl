
uniform int u_first;
flat out int v_index;
void main() {
  v_index = u_first + gl_InstanceID;
  vec4 rect = record(v_index, 10);
  vec2 corner = vec2(gl_VertexID & 1, gl_VertexID >> 1);  // triangle strip
  gl_Position = vec4(mix(rect.xy, rect.zw, corner), 0.0, 1.0);
}
