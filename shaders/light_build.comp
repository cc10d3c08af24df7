// Deep light map, dense: one node plane of the light-space grid per dispatch, swept from the
// sun (Nes §5.2.3, Riley §4.4).  Mirrors light_map_build() in src/light/transport.c operation
// for operation in float32; see docs/lightmap.md for the grid and what a node stores.
// Variants (#define, effects that are off are compiled out): FORWARD 0 = shadow only;
// PERIPHERAL 0 = no peripheral ring; PHASE_MIX 0 = both phases' CP are equal (one phase), so
// the ice share is not computed; MULTIPLE 1 = also store each slice's optical depth and ice
// share for the diffuse column pass (light_diffuse.comp); LATERAL 1 (with MULTIPLE) = and its
// lateral escape rates (light_lateral.comp), weighted by the extinction.

#include "bindings.h"
#include "common.glsl"

#ifndef FORWARD
#define FORWARD 1
#endif
#ifndef PERIPHERAL
#define PERIPHERAL 1
#endif
#ifndef PHASE_MIX
#define PHASE_MIX 1
#endif
#ifndef MULTIPLE
#define MULTIPLE 0
#endif
#ifndef LATERAL
#define LATERAL 0
#endif

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = BIND_BUILD_TEX_BETA) uniform sampler3D beta_tex;      // texelFetch only
layout(r32f, binding = BIND_BUILD_IMG_LIGHT) uniform image3D light_img; // node (i, j, k): light
#if MULTIPLE
// slice k-1..k: tau, ice share, lateral escape rates along x and y (0 without LATERAL)
layout(rgba32f, binding = BIND_BUILD_IMG_SLICE) uniform writeonly image3D slice_img;
#endif
#if MULTIPLE && LATERAL
// the volume grid: beta / w; texelFetch only
layout(binding = BIND_BUILD_TEX_RATES) uniform sampler3D rates_tex;
#endif

uniform ivec3 vol_n;
uniform vec3 vol_origin;
uniform vec3 vol_inv_spacing;
uniform ivec3 grid_n;
uniform vec3 g_origin, g_du, g_dv, g_dw;
uniform int plane;       // k
uniform int substeps;
uniform float dsub;      // metres per substep
uniform vec4 cp;         // water_ctr, ice_ctr, water_per, ice_per
uniform vec2 per_offset; // peripheral offset in node units along u and v

// Lower index and upper weight along one axis, clamped to the edge voxels (transport.c).
int axis_weight(float x, int n, out float t)
{
    float f = x - 0.5;
    if (n < 2 || f <= 0.0) {
        t = 0.0;
        return 0;
    }
    if (f >= float(n - 1)) {
        t = 1.0;
        return n - 2;
    }
    int i = int(f);
    t = f - float(i);
    return i;
}

// Trilinear in the volume's voxels with the CPU's weights; outside the box reads 0.  NaN and
// negative read as 0, infinity as 1e30.
vec2 sample_voxels(sampler3D tex, vec3 p)
{
    vec3 x = (p - vol_origin) * vol_inv_spacing;
    for (int a = 0; a < 3; a++) {
        if (!(x[a] >= 0.0 && x[a] <= float(vol_n[a])))
            return vec2(0.0);
    }
    vec3 t;
    ivec3 i0, d;
    for (int a = 0; a < 3; a++) {
        float ta;
        i0[a] = axis_weight(x[a], vol_n[a], ta);
        t[a] = ta;
        d[a] = vol_n[a] > 1 ? 1 : 0;
    }
    vec2 c000 = texelFetch(tex, i0, 0).rg, c100 = texelFetch(tex, i0 + ivec3(d.x, 0, 0), 0).rg;
    vec2 c010 = texelFetch(tex, i0 + ivec3(0, d.y, 0), 0).rg;
    vec2 c110 = texelFetch(tex, i0 + ivec3(d.x, d.y, 0), 0).rg;
    vec2 c001 = texelFetch(tex, i0 + ivec3(0, 0, d.z), 0).rg;
    vec2 c101 = texelFetch(tex, i0 + ivec3(d.x, 0, d.z), 0).rg;
    vec2 c011 = texelFetch(tex, i0 + ivec3(0, d.y, d.z), 0).rg;
    vec2 c111 = texelFetch(tex, i0 + d, 0).rg;
    vec2 c00 = c000 + t.x * (c100 - c000);
    vec2 c10 = c010 + t.x * (c110 - c010);
    vec2 c01 = c001 + t.x * (c101 - c001);
    vec2 c11 = c011 + t.x * (c111 - c011);
    vec2 c0 = c00 + t.y * (c10 - c00);
    vec2 c1 = c01 + t.y * (c11 - c01);
    vec2 v = c0 + t.z * (c1 - c0);
    return vec2(v.x >= 0.0 ? min(v.x, 1e30) : 0.0, v.y >= 0.0 ? min(v.y, 1e30) : 0.0);
}

// Bilinear tap in node plane k-1; nodes outside the plane read as the incident light 1.
float node(int i, int j, int k)
{
    if (i < 0 || j < 0 || i >= grid_n.x || j >= grid_n.y)
        return 1.0;
    return imageLoad(light_img, ivec3(i, j, k)).r;
}

float plane_tap(float x, float y, int k)
{
    float fx = floor(x), fy = floor(y);
    float tx = x - fx, ty = y - fy;
    int ix = int(fx), iy = int(fy);
    float v00 = node(ix, iy, k), v10 = node(ix + 1, iy, k);
    float v01 = node(ix, iy + 1, k), v11 = node(ix + 1, iy + 1, k);
    float r0 = v00 + tx * (v10 - v00);
    float r1 = v01 + tx * (v11 - v01);
    return r0 + ty * (r1 - r0);
}

void main()
{
    ivec2 ij = ivec2(gl_GlobalInvocationID.xy);
    if (ij.x >= grid_n.x || ij.y >= grid_n.y)
        return;
    int k = plane;
    if (k == 0) {
        imageStore(light_img, ivec3(ij, 0), vec4(1.0));
        return;
    }
    float fi = float(ij.x), fj = float(ij.y);
    vec2 b = vec2(0.0);
#if MULTIPLE && LATERAL
    vec2 lat = vec2(0.0);
#endif
    for (int m = 0; m < substeps; m++) {
        float kz = float(k - 1) + (float(m) + 0.5) / float(substeps);
        vec3 p = g_origin + fi * g_du + fj * g_dv + kz * g_dw;
        vec2 bm = sample_voxels(beta_tex, p);
        b += bm;
#if MULTIPLE && LATERAL
        if (bm.x + bm.y > 0.0) // else every voxel around p is clear, and so 0 here
            lat += sample_voxels(rates_tex, p); // extinction times rate: over beta, the rate
#endif
    }
    float beta = b.x + b.y;
    float l_in = imageLoad(light_img, ivec3(ij, k - 1)).r;
    float tau = beta * dsub;
    // The slice integrated exactly (transport.c, beam_slice; docs/lightmap.md): Nes eq.
    // 5.8-5.10 are the one-step form of the same equation.
#if PHASE_MIX || MULTIPLE
    float f_ice = beta > 0.0 ? b.x / beta : 0.0;
#endif
#if FORWARD
#if PHASE_MIX
    float cp_ctr = cp.x + f_ice * (cp.y - cp.x);
    float cp_per = cp.z + f_ice * (cp.w - cp.z);
#else
    float cp_ctr = cp.x, cp_per = cp.z;
#endif
    float a = 1.0 - cp_ctr;
    float ea = exp(-a * tau);
    float l = l_in * ea; // the central cone keeps CP(theta/4) of what the slice scatters
#if PERIPHERAL
    if (beta > 0.0) {
        float l_per = 0.25 * (plane_tap(fi + per_offset.x, fj, k - 1) +
                              plane_tap(fi - per_offset.x, fj, k - 1) +
                              plane_tap(fi, fj + per_offset.y, k - 1) +
                              plane_tap(fi, fj - per_offset.y, k - 1));
        l += l_per * (exp(-(a - cp_per) * tau) - ea); // the ring, from the neighbours
    }
#endif
#else
    float l = l_in * exp(-tau); // Nes eq. 5.8
#endif
#if MULTIPLE
#if LATERAL
    vec2 rates = beta > 0.0 ? lat / beta : vec2(0.0);
#else
    vec2 rates = vec2(0.0);
#endif
    imageStore(slice_img, ivec3(ij, k), vec4(tau, f_ice, rates));
#endif
    imageStore(light_img, ivec3(ij, k), vec4(clamp(l, 0.0, 1.0))); // Nes eq. 5.11
}
