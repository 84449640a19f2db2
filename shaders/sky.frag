// Background where the render sees no surface (§5.3.3). With MVTM_SKYBOX the view direction is
// projected into the projectors as a point at infinity (rotation only), so distant sky and
// far-away scenery come from the photographs; otherwise, and where no projector sees sky in
// that direction, a constant colour.
in vec2 v_ndc;
layout(location = 0) out vec4 o_colour;
layout(location = 1) out uint o_source;  // projector rank, 255 = constant background

uniform vec3 u_background;   // 0..1
uniform mat3 u_Rt;           // render camera → world rotation
uniform vec4 u_K;            // render fx fy cx cy
uniform vec2 u_size;         // render size

void main() {
  o_colour = vec4(u_background, 1.0);
  o_source = 255u;
#ifdef MVTM_SKYBOX
  vec2 pix = vec2((v_ndc.x + 1.0) * 0.5 * u_size.x, (1.0 - v_ndc.y) * 0.5 * u_size.y);
  vec3 dir = u_Rt * vec3((pix - u_K.zw) / u_K.xy, 1.0);
  for (int k = 0; k < MVTM_MAX_PROJECTORS; ++k) {
    if (k >= u_num_projectors) break;
    vec2 uv;
    float z;
    if (!ProjectInto(k, dir, 0.0, uv, z)) continue;
    if (!Usable(k, uv, z, true)) continue;
    o_colour = vec4(Sample(k, uv), 1.0);
    o_source = uint(k);
    break;
  }
#endif
}
