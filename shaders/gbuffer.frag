// The first of the two passes of a render: what surface each pixel sees (the nearest fragment),
// for ptm.frag to texture once per pixel rather than once per fragment drawn.
in vec3 v_rel;
in vec3 v_colour;
in float v_depth;
layout(location = 0) out float o_depth;  // linear depth (ptm.frag finds the point from it)
layout(location = 1) out vec4 o_colour;  // vertex colour

void main() {
  o_depth = v_depth;
  o_colour = vec4(v_colour, 1.0);
}
