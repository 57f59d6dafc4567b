#version 300 es
// A minimal WebGL2 fragment shader using the sampler: paste
// runtime/probe_sample.glsl where the marker line is (GLSL ES has no
// #include; tests/test_runtime.sh does the paste and compiles the result).
// Diffuse indirect light = albedo / pi x irradiance from the volume.
precision highp float;

in vec3 v_world_position;   // in the volume's frame (original coordinates minus a chosen origin)
in vec3 v_world_normal;
uniform vec3 u_camera_position;
uniform vec3 u_albedo;
out vec4 frag_color;

// @PROBE_SAMPLE@

void main()
{
    vec3 n = normalize(v_world_normal);
    vec3 v = normalize(u_camera_position - v_world_position);
    vec3 e = pb_volume_irradiance(v_world_position, n, v);
    frag_color = vec4(u_albedo / 3.14159265 * e, 1.0);
}
