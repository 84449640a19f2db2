// Mesh vertices, rendered camera-relative (DESIGN.md "Precision").
// Positions are float offsets from their chunk's origin; u_offset = chunk origin − camera centre,
// computed in double on the CPU, so the float numbers here stay small at UTM coordinates.
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_colour;  // vertex colour, 0..1

uniform vec3 u_offset;   // chunk origin − render camera centre (world axes)
uniform mat3 u_R;        // render camera rotation, world → camera (x right, y down, z forward)
uniform mat4 u_P;        // camera coordinates → clip (libcore/render builds it from K)

out vec3 v_rel;          // world position − render camera centre
out vec3 v_colour;
out float v_depth;       // camera-space z of the render camera (metres)
invariant gl_Position;   // the depth pre-pass and the shading pass must agree exactly

void main() {
  v_rel = a_position + u_offset;
  vec3 x_cam = u_R * v_rel;
  v_colour = a_colour;
  v_depth = x_cam.z;
  gl_Position = u_P * vec4(x_cam, 1.0);
}
