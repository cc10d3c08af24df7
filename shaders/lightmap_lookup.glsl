// Light arriving at a world point, as a fraction of the incident sunlight, read from the deep
// light map (docs/lightmap.md).
//   LIGHTMAP 0: no light map, every point sees the full sun (unshadowed single scattering).
//   LIGHTMAP 1: dense light volume, hardware trilinear lookup.
//   LIGHTMAP 2: compressed deep light map: per light column a list of (depth, light) nodes,
//               binary search and linear interpolation, bilinear across columns.
//   GROUND_SHADOW 1: the ground reads the light map too (else it sees the full sun).
//   LIGHTMAP_PAIR 1 (effects.temporal): two maps, of steps k and k + 1, bound side by side
//               (the second at the *_NEXT bindings of bindings.h, uniforms *_next); the
//               light is mix(L_k, L_k+1, temporal_f).
//   MULTIPLE 1 (effects.multiple): the map also holds the diffuse light of its two-stream
//               column pass, M = 2 (U + V) and N = 2 (U - V) (light.h, light_map.diffuse):
//               dense, an RG volume at BIND_LIGHTMAP_TEX_DIFFUSE (step k + 1: *_NEXT);
//               compressed, its columns of (depth, M, N) nodes after the light's in the same
//               two buffers; lightmap_diffuse() reads it (0 beside the light columns).
//   MULTIPLE 2 (effects.multiple = "volume"): the diffuse light is the 3-D volume instead
//               (light_volume.h): phi and the net flux F per cell over the volume box, an
//               RGBA volume at BIND_LIGHTMAP_TEX_DIFFUSE (step k + 1: *_NEXT) in either
//               storage; lightmap_volume() reads it (0 outside the box).

#include "bindings.h"

#ifndef LIGHTMAP
#define LIGHTMAP 0
#endif
#ifndef GROUND_SHADOW
#define GROUND_SHADOW 1
#endif
#ifndef TEMPORAL
#define TEMPORAL 0
#endif
#ifndef LIGHTMAP_PAIR
#define LIGHTMAP_PAIR 0
#endif
#ifndef MULTIPLE
#define MULTIPLE 0
#endif
#if TEMPORAL || LIGHTMAP_PAIR
uniform float temporal_f; // blend of step k + 1 into step k, in [0, 1]
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

#if LIGHTMAP_PAIR
uniform mat4 light_world_to_tex_next;
uniform ivec3 light_n_next;
#endif

#if LIGHTMAP == 1
layout(binding = BIND_LIGHTMAP_TEX_LIGHT) uniform sampler3D light_tex;
#if LIGHTMAP_PAIR
layout(binding = BIND_LIGHTMAP_TEX_LIGHT_NEXT) uniform sampler3D light_tex_next;
#endif

float lightmap_light(vec3 p)
{
    vec3 tex = (light_world_to_tex * vec4(p, 1.0)).xyz;
    float l = outside_light_columns(tex) ? 1.0 : texture(light_tex, tex).r;
#if LIGHTMAP_PAIR
    vec3 tn = (light_world_to_tex_next * vec4(p, 1.0)).xyz;
    float ln = outside_light_columns(tn) ? 1.0 : texture(light_tex_next, tn).r;
    l = mix(l, ln, temporal_f);
#endif
    return l;
}
#else
// first node and count per column; depth and light per node
layout(std430, binding = BIND_LIGHTMAP_BUF_COLUMNS) readonly buffer light_columns {
    uint columns[];
};
layout(std430, binding = BIND_LIGHTMAP_BUF_NODES) readonly buffer light_nodes {
    float nodes[];
};
#if LIGHTMAP_PAIR
layout(std430, binding = BIND_LIGHTMAP_BUF_COLUMNS_NEXT) readonly buffer light_columns_next {
    uint columns_next[];
};
layout(std430, binding = BIND_LIGHTMAP_BUF_NODES_NEXT) readonly buffer light_nodes_next {
    float nodes_next[];
};
// Map M's words: 0 the map of step k, 1 that of step k + 1.
#define COLUMN_WORD(M, I) ((M) == 0 ? columns[I] : columns_next[I])
#define NODE_WORD(M, I) ((M) == 0 ? nodes[I] : nodes_next[I])
#else
#define COLUMN_WORD(M, I) columns[I]
#define NODE_WORD(M, I) nodes[I]
#endif

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

float column_eval(int m, ivec3 n, int i, int j, float depth)
{
    uint col = uint(i + n.x * j);
    uint first = COLUMN_WORD(m, 2u * col), count = COLUMN_WORD(m, 2u * col + 1u);
    if (count == 0u)
        return 1.0;
    float v;
    if (!(depth > NODE_WORD(m, 2u * first))) {
        v = NODE_WORD(m, 2u * first + 1u);
    } else if (depth >= NODE_WORD(m, 2u * (first + count - 1u))) {
        v = NODE_WORD(m, 2u * (first + count - 1u) + 1u);
    } else {
        uint a = 0u, b = count - 1u; // nodes[a].depth <= depth < nodes[b].depth
        while (b - a > 1u) {
            uint mid = a + (b - a) / 2u;
            if (NODE_WORD(m, 2u * (first + mid)) <= depth)
                a = mid;
            else
                b = mid;
        }
        float d0 = NODE_WORD(m, 2u * (first + a)), d1 = NODE_WORD(m, 2u * (first + b));
        float v0 = NODE_WORD(m, 2u * (first + a) + 1u), v1 = NODE_WORD(m, 2u * (first + b) + 1u);
        v = v0 + (v1 - v0) * ((depth - d0) / (d1 - d0));
    }
    return clamp(v, 0.0, 1.0);
}

// Map M (grid N, world -> texture W) at P: bilinear across columns, linear along them.
float compressed_light(int m, mat4 w, ivec3 n, vec3 p)
{
    vec3 tex = (w * vec4(p, 1.0)).xyz;
    if (outside_light_columns(tex))
        return 1.0;
    float tx, ty;
    int i = tex_column(tex.x, n.x, tx);
    int j = tex_column(tex.y, n.y, ty);
    float depth = clamp(tex.z * float(n.z) - 0.5, 0.0, float(n.z - 1));
    float v00 = column_eval(m, n, i, j, depth), v10 = column_eval(m, n, i + 1, j, depth);
    float v01 = column_eval(m, n, i, j + 1, depth), v11 = column_eval(m, n, i + 1, j + 1, depth);
    float r0 = v00 + tx * (v10 - v00);
    float r1 = v01 + tx * (v11 - v01);
    return r0 + ty * (r1 - r0);
}

float lightmap_light(vec3 p)
{
    float l = compressed_light(0, light_world_to_tex, light_n, p);
#if LIGHTMAP_PAIR
    l = mix(l, compressed_light(1, light_world_to_tex_next, light_n_next, p), temporal_f);
#endif
    return l;
}
#endif
#endif

#if LIGHTMAP == 1 && MULTIPLE == 1
layout(binding = BIND_LIGHTMAP_TEX_DIFFUSE) uniform sampler3D diffuse_tex;
#if LIGHTMAP_PAIR
layout(binding = BIND_LIGHTMAP_TEX_DIFFUSE_NEXT) uniform sampler3D diffuse_tex_next;
#endif

vec2 lightmap_diffuse(vec3 p)
{
    vec3 tex = (light_world_to_tex * vec4(p, 1.0)).xyz;
    vec2 d = outside_light_columns(tex) ? vec2(0.0) : texture(diffuse_tex, tex).rg;
#if LIGHTMAP_PAIR
    vec3 tn = (light_world_to_tex_next * vec4(p, 1.0)).xyz;
    vec2 dn = outside_light_columns(tn) ? vec2(0.0) : texture(diffuse_tex_next, tn).rg;
    d = mix(d, dn, temporal_f);
#endif
    return d;
}
#elif LIGHTMAP == 2 && MULTIPLE == 1
// The diffuse light's columns follow the light's in the columns buffer (from word
// light_diffuse_columns on), its nodes (depth, M, N) the light's in the nodes buffer (from
// light_diffuse_nodes on): light_compressed_sample_diffuse.
uniform uint light_diffuse_columns, light_diffuse_nodes;
#if LIGHTMAP_PAIR
uniform uint light_diffuse_columns_next, light_diffuse_nodes_next;
#endif

vec2 diffuse_column_eval(int m, ivec3 n, int i, int j, float depth)
{
#if LIGHTMAP_PAIR
    uint cbase = m == 0 ? light_diffuse_columns : light_diffuse_columns_next;
    uint nbase = m == 0 ? light_diffuse_nodes : light_diffuse_nodes_next;
#else
    uint cbase = light_diffuse_columns, nbase = light_diffuse_nodes;
#endif
    uint col = uint(i + n.x * j);
    uint first = COLUMN_WORD(m, cbase + 2u * col), count = COLUMN_WORD(m, cbase + 2u * col + 1u);
    if (count == 0u)
        return vec2(0.0);
    uint at0 = nbase + 3u * first, last = nbase + 3u * (first + count - 1u);
    if (!(depth > NODE_WORD(m, at0)))
        return vec2(NODE_WORD(m, at0 + 1u), NODE_WORD(m, at0 + 2u));
    if (depth >= NODE_WORD(m, last))
        return vec2(NODE_WORD(m, last + 1u), NODE_WORD(m, last + 2u));
    uint a = 0u, b = count - 1u;
    while (b - a > 1u) {
        uint mid = a + (b - a) / 2u;
        if (NODE_WORD(m, at0 + 3u * mid) <= depth)
            a = mid;
        else
            b = mid;
    }
    uint pa = at0 + 3u * a, pb = at0 + 3u * b;
    float d0 = NODE_WORD(m, pa), d1 = NODE_WORD(m, pb);
    float f = (depth - d0) / (d1 - d0);
    vec2 v0 = vec2(NODE_WORD(m, pa + 1u), NODE_WORD(m, pa + 2u));
    vec2 v1 = vec2(NODE_WORD(m, pb + 1u), NODE_WORD(m, pb + 2u));
    return v0 + (v1 - v0) * f;
}

vec2 compressed_diffuse(int m, mat4 w, ivec3 n, vec3 p)
{
    vec3 tex = (w * vec4(p, 1.0)).xyz;
    if (outside_light_columns(tex))
        return vec2(0.0);
    float tx, ty;
    int i = tex_column(tex.x, n.x, tx);
    int j = tex_column(tex.y, n.y, ty);
    float depth = clamp(tex.z * float(n.z) - 0.5, 0.0, float(n.z - 1));
    vec2 v00 = diffuse_column_eval(m, n, i, j, depth);
    vec2 v10 = diffuse_column_eval(m, n, i + 1, j, depth);
    vec2 v01 = diffuse_column_eval(m, n, i, j + 1, depth);
    vec2 v11 = diffuse_column_eval(m, n, i + 1, j + 1, depth);
    vec2 r0 = v00 + tx * (v10 - v00);
    vec2 r1 = v01 + tx * (v11 - v01);
    return r0 + ty * (r1 - r0);
}

vec2 lightmap_diffuse(vec3 p)
{
    vec2 d = compressed_diffuse(0, light_world_to_tex, light_n, p);
#if LIGHTMAP_PAIR
    d = mix(d, compressed_diffuse(1, light_world_to_tex_next, light_n_next, p), temporal_f);
#endif
    return d;
}
#endif

#if LIGHTMAP != 0 && MULTIPLE == 2
layout(binding = BIND_LIGHTMAP_TEX_DIFFUSE) uniform sampler3D volume_tex;
uniform vec3 volume_box_min, volume_box_size;
#if LIGHTMAP_PAIR
layout(binding = BIND_LIGHTMAP_TEX_DIFFUSE_NEXT) uniform sampler3D volume_tex_next;
uniform vec3 volume_box_min_next, volume_box_size_next;
#endif

vec4 volume_at(sampler3D tex, vec3 lo, vec3 size, vec3 p)
{
    vec3 t = (p - lo) / size;
    bool inside = all(greaterThanEqual(t, vec3(0.0))) && all(lessThanEqual(t, vec3(1.0)));
    return inside ? texture(tex, t) : vec4(0.0);
}

// phi and F at P (light_volume_sample; cell centres at the texel centres).
vec4 lightmap_volume(vec3 p)
{
    vec4 f = volume_at(volume_tex, volume_box_min, volume_box_size, p);
#if LIGHTMAP_PAIR
    f = mix(f, volume_at(volume_tex_next, volume_box_min_next, volume_box_size_next, p),
            temporal_f);
#endif
    return f;
}

// light_volume_scattered: what the field F scatters toward the eye (TO_EYE, unit) through a
// phase of mean cosine G, |F| capped at 0.1 phi (LIGHT_VOLUME_ANISOTROPY).
float volume_scattered(vec4 f, float g, vec3 to_eye)
{
    float fd = dot(f.yzw, to_eye), fm = length(f.yzw);
    float cap = 0.1 * max(f.x, 0.0);
    if (fm > cap)
        fd = fm > 0.0 ? fd * (cap / fm) : 0.0;
    return max(f.x + 3.0 * g * fd, 0.0);
}
#endif

#if LIGHTMAP != 0 && MULTIPLE == 1
// The diffuse light scattered toward the eye by a phase of mean cosine G, as a multiple of the
// sun radiance scale: with the Eddington radiance I0 + I1 mu (mu the cosine with the axis of
// the diffuse light's anisotropy, diffuse_mu_eye) and the phase's first moment,
// I0 + g I1 mu_eye = (M + 1.5 g N mu_eye) E / 4 pi (never negative), where mu_eye is that
// cosine for the light heading to the eye.
float diffuse_scattered(vec2 d, float g, float mu_eye)
{
    return max(d.x + 1.5 * g * d.y * mu_eye, 0.0);
}

// mu_eye for the eye ray DIR (from the eye), the direction SUN_DIR toward the sun, the beam
// LIGHT at the point and the mean cosine G there (docs/lightmap.md, "The diffuse light seen"):
// light just scattered out of the beam still travels along the sunlight, light scattered many
// times flows along the vertical (down, away from the sun's side, when the sun is up).  The
// axis leans from the first to the second as the beam fades: by the weight LIGHT^(1 - g), the
// share of the light that has not yet crossed one transport mean free path (1 / (1 - g)
// optical depths) of the medium, exactly so when forward scattering is off and the beam is
// e^-tau.
float diffuse_mu_eye(vec3 dir, vec3 sun_dir, float light, float g)
{
    vec3 down = vec3(0.0, 0.0, sun_dir.z >= 0.0 ? -1.0 : 1.0);
    float w = pow(max(light, 1e-30), 1.0 - g);
    vec3 axis = w * (-sun_dir) + (1.0 - w) * down;
    float len = length(axis); // >= |sun_dir.z|: the two never point apart
    return len > 1e-6 ? dot(-dir, axis) / len : 0.0;
}
#endif

float ground_light(vec3 p)
{
#if LIGHTMAP != 0 && GROUND_SHADOW != 0
    return lightmap_light(p);
#else
    return 1.0;
#endif
}

// Diffuse light reaching the ground at P, as a multiple of the sun radiance scale: the
// Eddington field I0 + I1 mu (mu along the vertical away from the sun's side) gives an
// upward-facing surface the irradiance pi I0 +- (2 pi / 3) I1 = E (M +- N) / 4 (+ when the
// sun is up), so a Lambertian ground of albedo rho reflects rho sun_radiance (M +- N).
// With the volume (MULTIPLE 2) the irradiance from above is the P1 half-range flux
// E (phi / 4 - F_z / 2), so the ground reflects rho sun_radiance (phi - 2 F_z).
float ground_diffuse(vec3 p, float sun_z)
{
#if LIGHTMAP != 0 && GROUND_SHADOW != 0 && MULTIPLE == 2
    vec4 f = lightmap_volume(p);
    return max(f.x - 2.0 * f.w, 0.0);
#elif LIGHTMAP != 0 && GROUND_SHADOW != 0 && MULTIPLE
    vec2 d = lightmap_diffuse(p);
    return max(d.x + (sun_z >= 0.0 ? d.y : -d.y), 0.0);
#else
    return 0.0;
#endif
}
