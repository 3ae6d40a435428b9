
uniform int u_index;
in vec3 v_position;  // camera-relative point on the tessellated surface
in vec3 v_unit;      // the same point on the unit sphere
void main() {
  vec3 p = v_position;
#if defined(TILE_THRESHOLD) || defined(TILE_COLOUR)
  float it = solidValue(p, dFdx(p), dFdy(p));
#endif
#if defined(TILE_THRESHOLD)
  o_colour = vec4(0.0, 0.0, 0.0, it - u_thresholds.x);
#elif defined(TILE_LIMB)
  o_colour = vec4(0.0, 0.0, 0.0, (u_thresholds.y - u_thresholds.x) * (1.0 - limbG(u_index, p)));
#else
  vec3 n = normalize(gradientFromUnit(u_index, v_unit));
  n = facingViewer(n, p);
  float excess = limbExcess(it, u_thresholds.x, u_thresholds.y, limbG(u_index, p));
  o_colour = vec4(surfaceColour(u_index, n, p, p, it, 1.0 - opacityFromExcess(excess), length(p)), 0.0);
#endif
}
