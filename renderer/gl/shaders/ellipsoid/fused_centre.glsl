
flat in int v_index;
void main() {
  vec3 r = viewRay();
  float s = hitEllipsoid(v_index, r);
  if (!hitShows(r, s, opaqueDistance(r) / length(r))) discard;
  o_colour = ellipsoidSurface(v_index, r, s);
}
