
layout(location = 0) in vec3 a_unit;
uniform int u_index;
uniform mat4 u_projection;  // the tile's off-axis frustum, from camera-relative world
out vec3 v_position;
out vec3 v_unit;
void main() {
  v_unit = a_unit;
  v_position = mat3(record(u_index, 11).xyz, record(u_index, 12).xyz,
                    record(u_index, 13).xyz) * a_unit + record(u_index, 14).xyz;
  gl_Position = u_projection * vec4(v_position, 1.0);
}
