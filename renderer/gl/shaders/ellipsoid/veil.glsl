
uniform vec4 u_veil;  // premultiplied colour, opacity
void main() { o_colour = u_veil; }
