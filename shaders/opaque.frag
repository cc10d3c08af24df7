// Opaque geometry: its radiance (lit by the sun through the light map and by the sky, or
// emissive) and its distance along the pixel's view ray, measured from the near plane the
// way shaders/raycast.comp measures it, so the ray stops exactly there.

#include "bindings.h"
#include "common.glsl"
#include "lightmap_lookup.glsl"

in vec3 v_world;
in vec3 v_normal;
in vec4 v_color;
in vec2 v_uv;

layout(location = 0) out vec4 out_color;
layout(location = 1) out float out_distance;

layout(binding = BIND_OPAQUE_TEX_MESH) uniform sampler2D mesh_texture;

uniform mat4 inv_proj; // clip -> view
uniform mat4 inv_view; // view -> world
uniform ivec2 image_size;
uniform vec3 sun_dir;
uniform vec3 sun_radiance;
uniform vec3 sky_radiance;
uniform int emissive; // 1: colour as is (menu, labels); 0: Lambertian, sun and sky
uniform int textured; // 1: colour times mesh_texture (text)

void main()
{
    vec4 c = v_color;
    if (textured != 0)
        c *= texture(mesh_texture, v_uv);
    if (c.a < 0.5)
        discard;
    vec3 radiance;
    if (emissive != 0) {
        radiance = c.rgb;
    } else {
        // As the ground in raycast.comp: rho (L_sun (4 cos L_l + diffuse) + L_sky).
        vec3 n = normalize(v_normal);
        float cos_sun = max(dot(n, sun_dir), 0.0);
        float sun = 4.0 * cos_sun * ground_light(v_world) + ground_diffuse(v_world, sun_dir.z);
        radiance = c.rgb * (sun_radiance * sun + sky_radiance);
    }
    vec2 ndc = gl_FragCoord.xy / vec2(image_size) * 2.0 - 1.0;
    vec3 origin, dir;
    view_ray(inv_proj, inv_view, ndc, origin, dir);
    out_distance = dot(v_world - origin, dir);
    // Depth linear in the distance: a window depth of (f+n)/(f-n) - 2fn/((f-n)z) with a 10 m
    // near plane resolves only ~1 km at 500 km, and lines on the terrain would fight with it;
    // float depth d / 1e9 m keeps ~7 digits relative at any distance.
    gl_FragDepth = clamp(out_distance * 1e-9, 0.0, 1.0);
    out_color = vec4(radiance, 1.0);
}
