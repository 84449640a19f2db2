// The second pass of a render, once per pixel over the surface gbuffer.frag stored (thesis
// Alg. 1–5). A surface pixel takes the first projector, in rank order, that sees the point, is
// not masked there and is not occluded; else its vertex colour. Without MVTM_PTM it is plain
// vertex-colour rendering.
//
// A pixel with no surface is background (§5.3.3). With MVTM_SKYBOX the view direction is
// projected into the projectors as a point at u_sky_distance along it (the scene's far end:
// far scenery beyond the mesh keeps some parallax), or at infinity (rotation only) when that is
// 0, so distant sky and far-away scenery come from the photographs; otherwise, and where no
// projector sees sky in that direction, a constant colour.
in vec2 v_ndc;
layout(location = 0) out vec4 o_colour;
layout(location = 1) out uint o_source;  // projector rank, 254 = vertex colour, 255 = background

uniform sampler2D u_depth;          // linear depth of the surface, +inf = none
uniform sampler2D u_vertex_colour;  // RGBA8
uniform vec3 u_background;          // 0..1
uniform mat3 u_Rt;                  // render camera → world rotation
uniform vec4 u_K;                   // render fx fy cx cy
uniform vec2 u_size;                // render size
#ifdef MVTM_SKYBOX
uniform float u_sky_distance;       // model units from the camera; 0 = at infinity
#endif
#ifdef MVTM_EXPOSURE
uniform vec2 u_render_exposure;     // gain, offset/255: the render camera's exposure
#endif

#ifdef MVTM_SEEN
// The camera-relative point x of the surface at pixel q (gl_FragCoord's rows: 0 at the bottom);
// false when q sees no surface.
bool SurfacePoint(ivec2 q, out vec3 x) {
  float z = texelFetch(u_depth, q, 0).r;
  if (isinf(z)) return false;
  vec2 pix = vec2(float(q.x) + 0.5, u_size.y - float(q.y) - 0.5);
  x = u_Rt * vec3((pix - u_K.zw) / u_K.xy * z, z);
  return true;
}

// The step s from point c (pixel p) to its neighbour at p + e or p − e, whichever sees a surface
// and is nearer to c (a depth edge does not tilt it); false when neither does (or both lie
// outside the image).
bool NeighbourStep(ivec2 p, ivec2 e, vec3 c, out vec3 s) {
  vec3 a, b;
  bool ha = all(lessThan(p + e, ivec2(u_size))) && SurfacePoint(p + e, a);
  bool hb = all(greaterThanEqual(p - e, ivec2(0))) && SurfacePoint(p - e, b);
  if (ha && (!hb || length(a - c) < length(c - b))) {
    s = a - c;
    return true;
  }
  s = c - b;
  return hb;
}

// True when the surface at pixel p (point c), turned towards the camera, faces the render
// camera's up within 37 degrees: the ground (not a ceiling above the camera). Its normal from
// the neighbours (NeighbourStep); false where that is undefined.
bool OnGround(ivec2 p, vec3 c) {
  vec3 dx, dy;
  if (!NeighbourStep(p, ivec2(1, 0), c, dx) || !NeighbourStep(p, ivec2(0, 1), c, dy))
    return false;
  vec3 n = cross(dx, dy);
  float ln = length(n);
  if (!(ln > 0.0) || isinf(ln)) return false;
  n /= ln;
  if (dot(n, c) > 0.0) n = -n;  // towards the camera
  return dot(n, u_Rt * vec3(0.0, -1.0, 0.0)) > 0.8;
}
#endif

// A projector's radiance L (common exposure) as the render camera records it.
vec3 Expose(vec3 c) {
#ifdef MVTM_EXPOSURE
  return u_render_exposure.x * c + u_render_exposure.y;
#else
  return c;
#endif
}

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  float z = texelFetch(u_depth, p, 0).r;
  int k;
  vec3 c;
  if (!isinf(z)) {
    o_colour = vec4(texelFetch(u_vertex_colour, p, 0).rgb, 1.0);
    o_source = 254u;
#ifdef MVTM_PTM
    vec2 pix = vec2(gl_FragCoord.x, u_size.y - gl_FragCoord.y);  // pixel centre, row 0 on top
    vec3 rel = u_Rt * vec3((pix - u_K.zw) / u_K.xy * z, z);       // point − camera centre
#ifdef MVTM_BLEND
    bool seen = BlendProjectors(rel, k, c);
#else
    bool seen = FirstProjector(rel, 1.0, false, k, c);
#endif
    if (seen) {
      o_colour = vec4(Expose(c), 1.0);
      o_source = uint(k);
    }
#ifdef MVTM_SEEN
    bool ground = u_seen_ground_conf > 0.0 && OnGround(p, rel);  // no floor: no need to know
    if (SeenSurface(rel / z, 1.0 / (z * (1.0 - u_seen_front)), ground, k, c)) {
      o_colour = vec4(Expose(c), 1.0);
      o_source = uint(k);
    }
#endif
#endif
    return;
  }
  o_colour = vec4(u_background, 1.0);
  o_source = 255u;
#if defined(MVTM_SKYBOX) || defined(MVTM_SEEN)
  vec2 pix = vec2((v_ndc.x + 1.0) * 0.5 * u_size.x, (1.0 - v_ndc.y) * 0.5 * u_size.y);
  vec3 dir = u_Rt * vec3((pix - u_K.zw) / u_K.xy, 1.0);
#endif
#ifdef MVTM_SEEN
  // No mesh here: anything a projector saw on the ray before the sky (a canopy, a pole's top).
#ifdef MVTM_SKYBOX
  float w_sky = u_sky_distance > 0.0 ? length(dir) / u_sky_distance : 0.0;
#else
  float w_sky = 0.0;
#endif
  if (SeenSurface(dir, w_sky, false, k, c)) {
    o_colour = vec4(Expose(c), 1.0);
    o_source = uint(k);
    return;
  }
#endif
#ifdef MVTM_SKYBOX
  bool sky = u_sky_distance > 0.0 ? FirstProjector(normalize(dir) * u_sky_distance, 1.0, true, k, c)
                                  : FirstProjector(dir, 0.0, true, k, c);
  if (sky) {
    o_colour = vec4(Expose(c), 1.0);
    o_source = uint(k);
  }
#endif
}
