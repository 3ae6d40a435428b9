#version 450 core
uniform vec2 u_polygon[8];  // convex polygon in normalised device coordinates, a triangle fan
void main() { gl_Position = vec4(u_polygon[gl_VertexID], 0.0, 1.0); }
