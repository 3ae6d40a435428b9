#version 450 core
layout(location = 0) in vec3 a_body;  // body coordinates before scaling
uniform mat3 u_model;                 // R S
uniform vec3 u_offset;                // centre - eye
uniform vec3 u_clip_x;                // right / (tan(vfov/2) aspect)
uniform vec3 u_clip_y;                // up / tan(vfov/2)
uniform vec3 u_clip_w;                // forward
out vec3 v_position;                  // camera-relative
out vec3 v_body;
void main() {
  v_body = a_body;
  v_position = u_model * a_body + u_offset;
  // Reversed, infinite depth: with clip z in [0, w], depth = near / w.
  gl_Position = vec4(dot(v_position, u_clip_x), dot(v_position, u_clip_y), 0.05,
                     dot(v_position, u_clip_w));
}
