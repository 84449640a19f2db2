#extension GL_ARB_texture_gather : enable
// Included by ptm.frag: projectors and their images as texture arrays.
// Compile-time switches (the effects plan, see ptmrender --explain):
//   MVTM_MAX_PROJECTORS  N    projectors tried in rank order (1 = a single projector)
//   MVTM_OCCLUSION            compare with the projector's depth map (Alg. 2)
//   MVTM_MASKS                skip masked projector texels (the next projector is tried)
//   MVTM_SKYBOX               background from projectors, where their depth map is +inf
//   MVTM_EXPOSURE             bring each projector's samples to the workspace's common exposure
//   MVTM_BLEND                blend every projector that sees a point, weighted in the spirit of
//                             the unstructured lumigraph (angle, resolution, border feathering,
//                             soft occlusion), instead of taking the first one
//   MVTM_SEEN                 what the projectors' photos saw (densify's maps) in front of the
//                             mesh, on each pixel's ray, takes the pixel (SeenInto)
uniform int u_num_projectors;
uniform mat3 u_proj_R[MVTM_MAX_PROJECTORS];   // world → projector camera rotation
uniform vec3 u_proj_t[MVTM_MAX_PROJECTORS];   // R_k (C_render − C_k), double on the CPU
uniform vec4 u_proj_K[MVTM_MAX_PROJECTORS];   // fx fy cx cy (pixels)
uniform int u_proj_layer[MVTM_MAX_PROJECTORS]; // texture-array layer holding projector k
uniform vec2 u_proj_size;                     // projector image size (pixels)
uniform sampler2DArray u_images;              // RGB, row 0 = top
#if defined(MVTM_OCCLUSION) || defined(MVTM_SKYBOX)
uniform sampler2DArray u_depths;              // R32F linear depth, +inf = no surface
#endif
#ifdef MVTM_OCCLUSION
uniform float u_bias;                         // relative: occluded when z > d·(1 + bias)
#endif
#ifdef MVTM_MASKS
uniform sampler2DArray u_masks;               // R8, 1 = do not use this texel
#endif
#ifdef MVTM_EXPOSURE
uniform vec2 u_proj_exposure[MVTM_MAX_PROJECTORS];  // gain, offset/255 of I = gain·L + offset
#endif
#ifdef MVTM_BLEND
uniform float u_blend_power;   // p: weight ∝ (1 / (penalty + 1e-3 rad))^p; larger = sharper
uniform float u_feather;       // pixels over which a projector fades out towards its border
uniform float u_res_weight;    // R: penalty R·(1 − d_render/d_proj) rad (R/2 at twice as far)
uniform float u_soft;          // soft occlusion: visibility falls from 1 at z = d·(1 + bias)
                               // to 0 at z = d·(1 + bias + soft)
#endif

// Projects camera-relative point (or direction, w = 0) into projector k. Returns false when
// the point is behind the projector (reverse-projection rejection) or outside its image (clip
// test). uv: pixel coordinates, COLMAP convention (top-left pixel centre at 0.5, 0.5).
bool ProjectInto(int k, vec3 rel, float w, out vec2 uv, out float z, out vec3 x) {
  x = u_proj_R[k] * rel + w * u_proj_t[k];
  z = x.z;
  if (!(z > 1e-6 * max(1.0, length(x)))) return false;  // on or behind the projector plane
  uv = u_proj_K[k].xy * (x.xy / z) + u_proj_K[k].zw;
  return all(greaterThanEqual(uv, vec2(0.0))) && all(lessThan(uv, u_proj_size));
}
bool ProjectInto(int k, vec3 rel, float w, out vec2 uv, out float z) {
  vec3 x;
  return ProjectInto(k, rel, w, uv, z, x);
}

ivec3 Texel(int k, vec2 uv) {
  return ivec3(clamp(ivec2(floor(uv)), ivec2(0), ivec2(u_proj_size) - 1), u_proj_layer[k]);
}

#ifdef MVTM_OCCLUSION
// The farthest of the four depth texels around uv (the bilinear footprint): a surface seen at a
// grazing angle changes depth by metres per texel, and a single nearest texel would reject
// visible points on it.
float FootprintDepth(int k, vec2 uv) {
#ifdef GL_ARB_texture_gather
  vec4 q = textureGather(u_depths, vec3(uv / u_proj_size, float(u_proj_layer[k])));
  return max(max(q.x, q.y), max(q.z, q.w));
#else
  ivec2 base = ivec2(floor(uv - 0.5));
  float d = 0.0;
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      ivec2 t = clamp(base + ivec2(i, j), ivec2(0), ivec2(u_proj_size) - 1);
      d = max(d, texelFetch(u_depths, ivec3(t, u_proj_layer[k]), 0).r);
    }
  return d;
#endif
}
#endif

bool Usable(int k, vec2 uv, float z, bool sky) {
#ifdef MVTM_MASKS
  if (texelFetch(u_masks, Texel(k, uv), 0).r > 0.5) return false;
#endif
#ifdef MVTM_SKYBOX
  if (sky) {
    float d = texelFetch(u_depths, Texel(k, uv), 0).r;
    return isinf(d) || d > 1e30;                      // sky in the projector too
  }
#endif
#ifdef MVTM_OCCLUSION
  // Occluded only when all four depth texels around uv are nearer.
  float d = FootprintDepth(k, uv);
  if (!isinf(d) && z > d * (1.0 + u_bias)) return false;  // something nearer hides this point
#endif
  return true;
}

vec3 Sample(int k, vec2 uv) {
  vec3 c = texture(u_images, vec3(uv / u_proj_size, float(u_proj_layer[k]))).rgb;
#ifdef MVTM_EXPOSURE
  c = (c - u_proj_exposure[k].y) / u_proj_exposure[k].x;  // the radiance L, common frame
#endif
  return c;
}

// The first projector, in rank order, that sees camera-relative point `rel` (or direction,
// w = 0), or the sky point in that direction (sky: at infinity or at the sky distance), is not
// masked there and is not occluded (for the sky: the projector sees sky there too):
// true with its rank k and colour c; false when none does.
bool FirstProjector(vec3 rel, float w, bool sky, out int k, out vec3 c) {
  for (k = 0; k < MVTM_MAX_PROJECTORS; ++k) {
    if (k >= u_num_projectors) break;
    vec2 uv;
    float z;
    if (!ProjectInto(k, rel, w, uv, z)) continue;
    if (!Usable(k, uv, z, sky)) continue;
    c = Sample(k, uv);
    return true;
  }
  return false;
}

#ifdef MVTM_BLEND
// How much of projector k's sample at uv (depth z) to trust: 0 when masked, fading from 1 to 0
// as the point falls behind the projector's depth (soft occlusion).
float Visibility(int k, vec2 uv, float z) {
#ifdef MVTM_MASKS
  if (texelFetch(u_masks, Texel(k, uv), 0).r > 0.5) return 0.0;
#endif
#ifdef MVTM_OCCLUSION
  float d = FootprintDepth(k, uv);
  if (!isinf(d)) return 1.0 - smoothstep(d * (1.0 + u_bias), d * (1.0 + u_bias + u_soft), z);
#endif
  return 1.0;
}

// Every projector that sees camera-relative point `rel`, blended (Buehler et al. 2001 in spirit):
// weight = visibility · border feather · ((best + 1e-3) / (penalty + 1e-3))^p, penalty = the
// angle between the render ray and the projector's ray at the point + u_res_weight · how much
// farther the projector is, best = the least penalty (so weights stay in [0, 1] for any p). True
// with the colour and the rank of the heaviest projector; false when none sees the point.
bool BlendProjectors(vec3 rel, out int best, out vec3 c) {
  vec2 uv[MVTM_MAX_PROJECTORS];
  float trust[MVTM_MAX_PROJECTORS], pen[MVTM_MAX_PROJECTORS];
  float rn = length(rel), least = 1e30;
  for (int k = 0; k < MVTM_MAX_PROJECTORS; ++k) {
    trust[k] = 0.0;
    pen[k] = 0.0;
    if (k >= u_num_projectors) break;
    float z;
    vec3 x;
    if (!ProjectInto(k, rel, 1.0, uv[k], z, x)) continue;
    float v = Visibility(k, uv[k], z);
    if (!(v > 0.0)) continue;
    vec2 e = min(uv[k], u_proj_size - uv[k]);
    trust[k] = v * max(clamp(min(e.x, e.y) / u_feather, 0.0, 1.0), 1e-3);
    float xn = length(x);
    float cosa = dot(u_proj_R[k] * rel, x) / max(rn * xn, 1e-30);
    pen[k] = acos(clamp(cosa, -1.0, 1.0)) + u_res_weight * max(0.0, 1.0 - rn / xn);
    least = min(least, pen[k]);
  }
  float wsum = 0.0, wbest = 0.0;
  vec3 acc = vec3(0.0);
  best = -1;
  for (int k = 0; k < MVTM_MAX_PROJECTORS; ++k) {
    if (k >= u_num_projectors) break;
    if (!(trust[k] > 0.0)) continue;
    float w = trust[k] * pow((least + 1e-3) / (pen[k] + 1e-3), u_blend_power);
    acc += w * Sample(k, uv[k]);
    wsum += w;
    if (w > wbest) {
      wbest = w;
      best = k;
    }
  }
  if (!(wsum > 0.0)) return false;
  c = acc / wsum;
  return true;
}
#endif

#ifdef MVTM_SEEN
uniform sampler2DArray u_seens;  // RG32F: depth of what each projector's photo saw (densify),
                                 // +inf = none; its confidence 0..1
uniform float u_seen_front;      // relative: counts when nearer than the mesh's depth·(1 − this)
uniform float u_seen_jump;       // relative depth step between successive samples: an edge
uniform float u_seen_reach;      // pixels of parallax searched in front of the end, a sample
                                 // every 2
uniform int u_seen_projectors;   // the first projectors searched
uniform float u_seen_ground_conf;  // on the ground, seen depths of less confidence are none

// The render ray r (camera-relative: the point at render depth 1/w is r / w) from inverse depth
// w_end (its end: the mesh's point moved u_seen_front towards the camera, or the sky) towards
// the camera, through projector k's seen map. In projector k that point is (b + w·a) / w, with
// a = u_proj_t[k] (the render centre) and b = R_k r, so its image moves along a line:
// |uv(w) − uv(w_end)| = |g| (w − w_end) / ((b.z + w·a.z)(b.z + w_end·a.z)), g = f ⊙ (a.xy b.z −
// b.xy a.z). The march covers u_seen_reach pixels of that line from the end (less when the ray
// nears the projector's plane first), evenly in that offset p (w(p) = w_end + p e² / (g − p e
// a.z)), nearest first; where the ray's image hardly moves (near the epipole: less than 2 px),
// evenly in w instead. The first sample where the ray has passed behind the seen surface (the
// sample before it in front, no edge between them) is the hit, refined linearly in 1/w (the
// projector depth b.z/w + a.z is linear in it). True with the hit's inverse depth and colour,
// unless masked. On the `ground` only seen depths of confidence ≥ u_seen_ground_conf count: a
// wrong depth there (a repetitive road marking matched a period off) would tear the road.
bool SeenInto(int k, vec3 r, float w_end, bool ground, out float w_hit, out vec3 c) {
  vec3 a = u_proj_t[k], b = u_proj_R[k] * r;
  float e = b.z + w_end * a.z;
  if (!(e > 0.0)) return false;  // the end is behind the projector
  vec2 f = u_proj_K[k].xy;
  float g = length(f * (a.xy * b.z - b.xy * a.z));
  float len = u_seen_reach;
  int steps = max(1, int(ceil(len / 2.0)));
  float den = g - len * e * a.z;
  float w_near = den > 0.0 ? (len * e * b.z + g * w_end) / den : 1e30;
  if (a.z < 0.0) w_near = min(w_near, w_end + 0.9 * (-b.z / a.z - w_end));  // the plane
  w_near = min(w_near, w_end + 100.0 / max(length(a), 1e-20));  // 1 % of the baseline away
  if (w_end <= 0.0) w_end = 1e-6 * w_near;  // the sky at infinity: at a far end instead
  if (!(w_near > w_end)) return false;
  float p_near = g * (w_near - w_end) / ((b.z + w_near * a.z) * e);
  bool by_offset = p_near >= 2.0;
  float w_prev = 0.0, xz_prev = 0.0, d_prev = 0.0;
  bool before = false;  // the previous sample was in front of a seen surface
  for (int i = 0; i <= steps; ++i) {
    float s = float(i) / float(steps), p = p_near * (1.0 - s);
    float w = by_offset ? w_end + p * e * e / (g - p * e * a.z) : mix(w_near, w_end, s);
    vec2 uv;
    float z;  // the projector depth times w
    if (!ProjectInto(k, r, w, uv, z)) {
      before = false;
      continue;
    }
    vec2 seen = texelFetch(u_seens, Texel(k, uv), 0).rg;
    float xz = z / w, d = ground && seen.g < u_seen_ground_conf ? 1.0 / 0.0 : seen.r;
    if (isinf(d) || !(d > 0.0) || d > 1e30) {
      before = false;
      continue;
    }
    if (xz >= d) {
      if (!before || abs(d - d_prev) > u_seen_jump * d) return false;  // edge: none here
      float t = (d_prev - xz_prev) / ((xz - xz_prev) - (d - d_prev));
      w_hit = 1.0 / mix(1.0 / w_prev, 1.0 / w, clamp(t, 0.0, 1.0));
      vec3 x = b + w_hit * a;
      uv = clamp(f * (x.xy / x.z) + u_proj_K[k].zw, vec2(0.0), u_proj_size - 1e-3);
#ifdef MVTM_MASKS
      if (texelFetch(u_masks, Texel(k, uv), 0).r > 0.5) return false;  // a vehicle in front
#endif
      c = Sample(k, uv);
      return true;
    }
    before = true;
    w_prev = w;
    xz_prev = xz;
    d_prev = d;
  }
  return false;
}

// The nearest surface the first u_seen_projectors projectors saw on render ray r before inverse
// depth w_end (SeenInto; `ground`: the ray ends on the ground): true with the projector's rank
// and its colour there.
bool SeenSurface(vec3 r, float w_end, bool ground, out int k, out vec3 c) {
  float best = -1.0;
  for (int j = 0; j < MVTM_MAX_PROJECTORS; ++j) {
    if (j >= u_num_projectors || j >= u_seen_projectors) break;
    float w;
    vec3 cj;
    if (SeenInto(j, r, w_end, ground, w, cj) && w > best) {
      best = w;
      k = j;
      c = cj;
    }
  }
  return best > 0.0;
}
#endif
