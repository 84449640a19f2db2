// Projective texture mapping of one mesh fragment (thesis Alg. 1–5): the first projector, in
// rank order, that sees the point, is not masked there and is not occluded colours it; else the
// vertex colour. Without MVTM_PTM this is plain vertex-colour rendering.
in vec3 v_rel;
in vec3 v_colour;
in float v_depth;
layout(location = 0) out vec4 o_colour;
layout(location = 1) out uint o_source;  // projector rank, 254 = vertex colour

void main() {
  o_colour = vec4(v_colour, 1.0);
  o_source = 254u;
#ifdef MVTM_PTM
  for (int k = 0; k < MVTM_MAX_PROJECTORS; ++k) {
    if (k >= u_num_projectors) break;
    vec2 uv;
    float z;
    if (!ProjectInto(k, v_rel, 1.0, uv, z)) continue;
    if (!Usable(k, uv, z, false)) continue;
    o_colour = vec4(Sample(k, uv), 1.0);
    o_source = uint(k);
    break;
  }
#endif
}
