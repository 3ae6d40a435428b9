
layout(location = 1) out float o_distance;
layout(location = 2) out float o_id;
uniform float u_id;             // 1 + the target's index
uniform vec3 u_albedo;          // colour times sun colour
uniform vec3 u_to_sun;
uniform float u_sunlight;       // the share the clouds above let through (MODEL.md section 16)
uniform int u_smooth;           // 1: analytic ellipsoid normals, 0: facet normals
uniform mat3 u_normal_matrix;   // R S^-1
in vec3 v_position;
in vec3 v_body;
void main() {
  vec3 n = u_smooth != 0 ? u_normal_matrix * v_body : cross(dFdx(v_position), dFdy(v_position));
  n = normalize(n);
  n = facingViewer(n, v_position);
  vec3 colour = u_albedo * targetLight(u_sunlight, dot(n, u_to_sun));
  float distance = length(v_position);
  o_colour = vec4(applyAir(colour, v_position / distance, distance), 1.0);
  o_distance = distance;
  o_id = u_id;
}
