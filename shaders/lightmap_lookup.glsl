// Light arriving at a world point, as a fraction of the incident sunlight, read from the deep
// light map (docs/lightmap.md).
//   LIGHTMAP 0: no light map, every point sees the full sun (unshadowed single scattering).
//   LIGHTMAP 1: dense light volume, hardware trilinear lookup.
//   LIGHTMAP 2: compressed deep light map: per light column a list of (depth, light) nodes,
//               binary search and linear interpolation, bilinear across columns.
//   GROUND_SHADOW 1: the ground reads the light map too (else it sees the full sun).

#ifndef LIGHTMAP
#define LIGHTMAP 0
#endif
#ifndef GROUND_SHADOW
#define GROUND_SHADOW 1
#endif

#if LIGHTMAP == 0
float lightmap_light(vec3 p)
{
    return 1.0;
}
#else
uniform mat4 light_world_to_tex;
uniform ivec3 light_n;

// The light grid's columns span the volume's projection across the light: a point beside
// them (the ground around the volume) has nothing between it and the sun.  Along the light,
// lookups clamp: beyond the far end the light is what left the volume.
bool outside_light_columns(vec3 tex)
{
    return tex.x < 0.0 || tex.x > 1.0 || tex.y < 0.0 || tex.y > 1.0;
}

#if LIGHTMAP == 1
layout(binding = 2) uniform sampler3D light_tex;

float lightmap_light(vec3 p)
{
    vec3 tex = (light_world_to_tex * vec4(p, 1.0)).xyz;
    if (outside_light_columns(tex))
        return 1.0;
    return texture(light_tex, tex).r;
}
#else
layout(std430, binding = 0) readonly buffer light_columns { uint columns[]; }; // first, count
layout(std430, binding = 1) readonly buffer light_nodes { float nodes[]; };    // depth, light

int tex_column(float tex, int n, out float t)
{
    float x = tex * float(n) - 0.5;
    if (!(x > 0.0)) {
        t = 0.0;
        return 0;
    }
    if (x >= float(n - 1)) {
        t = 1.0;
        return n - 2;
    }
    int i = int(x);
    t = x - float(i);
    return i;
}

float column_eval(int i, int j, float depth)
{
    uint col = uint(i + light_n.x * j);
    uint first = columns[2u * col], count = columns[2u * col + 1u];
    if (count == 0u)
        return 1.0;
    float v;
    if (!(depth > nodes[2u * first])) {
        v = nodes[2u * first + 1u];
    } else if (depth >= nodes[2u * (first + count - 1u)]) {
        v = nodes[2u * (first + count - 1u) + 1u];
    } else {
        uint a = 0u, b = count - 1u; // nodes[a].depth <= depth < nodes[b].depth
        while (b - a > 1u) {
            uint mid = a + (b - a) / 2u;
            if (nodes[2u * (first + mid)] <= depth)
                a = mid;
            else
                b = mid;
        }
        float d0 = nodes[2u * (first + a)], d1 = nodes[2u * (first + b)];
        float v0 = nodes[2u * (first + a) + 1u], v1 = nodes[2u * (first + b) + 1u];
        v = v0 + (v1 - v0) * ((depth - d0) / (d1 - d0));
    }
    return clamp(v, 0.0, 1.0);
}

float lightmap_light(vec3 p)
{
    vec3 tex = (light_world_to_tex * vec4(p, 1.0)).xyz;
    if (outside_light_columns(tex))
        return 1.0;
    float tx, ty;
    int i = tex_column(tex.x, light_n.x, tx);
    int j = tex_column(tex.y, light_n.y, ty);
    float depth = clamp(tex.z * float(light_n.z) - 0.5, 0.0, float(light_n.z - 1));
    float v00 = column_eval(i, j, depth), v10 = column_eval(i + 1, j, depth);
    float v01 = column_eval(i, j + 1, depth), v11 = column_eval(i + 1, j + 1, depth);
    float r0 = v00 + tx * (v10 - v00);
    float r1 = v01 + tx * (v11 - v01);
    return r0 + ty * (r1 - r0);
}
#endif
#endif

float ground_light(vec3 p)
{
#if LIGHTMAP != 0 && GROUND_SHADOW != 0
    return lightmap_light(p);
#else
    return 1.0;
#endif
}
