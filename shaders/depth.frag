// Linear camera-space depth (metres), for baked depth maps and the occlusion pre-pass.
in vec3 v_rel;
in vec3 v_colour;
in float v_depth;
layout(location = 0) out float o_depth;

void main() { o_depth = v_depth; }
