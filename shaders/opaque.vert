// Opaque geometry (ground, terrain, coastlines, the menu, the wand) drawn before ray casting.
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_color;
layout(location = 3) in vec2 a_uv;

uniform mat4 view_proj;
uniform mat4 model;

out vec3 v_world;
out vec3 v_normal;
out vec4 v_color;
out vec2 v_uv;

void main()
{
    vec4 w = model * vec4(a_pos, 1.0);
    v_world = w.xyz;
    v_normal = mat3(model) * a_normal;
    v_color = a_color;
    v_uv = a_uv;
    gl_Position = view_proj * w;
}
