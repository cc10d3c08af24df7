// Deep light map, first pass: the extinction of every slice of the light-space grid, all at
// once (one invocation per node k >= 1: the slice from node plane k - 1 to plane k), which the
// sweep (light_build.comp) and the diffuse column pass (light_diffuse.comp) then read.
// Mirrors the extinction part of light_map_build() in src/light/transport.c operation for
// operation in float32: the midpoint rule on SUBSTEPS equal parts, each a trilinear sample
// between voxel centres with the CPU's weights, 0 outside the box.
// Variants: MULTIPLE 1 = also each slice's lateral escape rates (LATERAL 1), in an RGBA
// slice image (else RG: optical depth and ice share); SKIP 1 = a sample in an empty macro
// cell (render/cells.c) reads 0 without reading a voxel, exactly what the voxels would give;
// STRETCHED 1 = the volume's levels are the model's (zmap.glsl).

#include "bindings.h"

#ifndef MULTIPLE
#define MULTIPLE 0
#endif
#ifndef LATERAL
#define LATERAL 0
#endif
#ifndef SKIP
#define SKIP 0
#endif

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(binding = BIND_SLICES_TEX_BETA) uniform sampler3D beta_tex; // texelFetch only
#if MULTIPLE
// slice k-1..k: tau, ice share, lateral escape rates along x and y (0 without LATERAL)
layout(rgba32f, binding = BIND_SLICES_IMG_SLICE) uniform writeonly image3D slice_img;
#else
layout(rg32f, binding = BIND_SLICES_IMG_SLICE) uniform writeonly image3D slice_img;
#endif
#if MULTIPLE && LATERAL
// the volume grid: beta / w; texelFetch only
layout(binding = BIND_SLICES_TEX_RATES) uniform sampler3D rates_tex;
#endif
#if SKIP
layout(std430, binding = BIND_SLICES_BUF_CELLS) readonly buffer macro_cells
{
    ivec4 cell_dims[16]; // cells along x, y, z and the level's first index
    ivec4 cell_header;   // levels, voxels per cell edge
    float cell_max[];
};
#include "cells.glsl"
#endif
#ifndef STRETCHED
#define STRETCHED 0
#endif
#if STRETCHED
layout(binding = BIND_SLICES_TEX_ZMAP) uniform sampler1D zmap_tex; // texelFetch only
#endif
#include "zmap.glsl"

uniform ivec3 vol_n;
uniform vec3 vol_origin;
uniform vec3 vol_inv_spacing;
uniform ivec3 grid_n;
uniform vec3 g_origin, g_du, g_dv, g_dw;
uniform int substeps;
uniform int base_z; // the first slice of this dispatch (a build in pieces)
uniform float dsub; // metres per substep

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
// negative read as 0, infinity as 1e30.  CELLS: an empty macro cell reads 0 at once.
vec2 sample_voxels(sampler3D tex, vec3 p, bool cells)
{
    vec3 x = (p - vol_origin) * vol_inv_spacing;
    for (int a = 0; a < 3; a++) {
        if (!(x[a] >= 0.0 && x[a] <= float(vol_n[a])))
            return vec2(0.0);
    }
#if SKIP
    if (cells && cell_clear_at_voxel(x)) // cells are even in height (render/cells.c)
        return vec2(0.0);
#endif
    x.z = zmap_voxel(p.z, vol_origin.z, float(vol_n.z), x.z);
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

void main()
{
    ivec3 node = ivec3(gl_GlobalInvocationID) + ivec3(0, 0, base_z);
    int k = node.z + 1; // the slice ending at plane k
    if (node.x >= grid_n.x || node.y >= grid_n.y || k >= grid_n.z)
        return;
    float fi = float(node.x), fj = float(node.y);
    vec2 b = vec2(0.0);
#if MULTIPLE && LATERAL
    vec2 lat = vec2(0.0);
#endif
    for (int m = 0; m < substeps; m++) {
        float kz = float(k - 1) + (float(m) + 0.5) / float(substeps);
        vec3 p = g_origin + fi * g_du + fj * g_dv + kz * g_dw;
        vec2 bm = sample_voxels(beta_tex, p, true);
        b += bm;
#if MULTIPLE && LATERAL
        if (bm.x + bm.y > 0.0) // else every voxel around p is clear, and so 0 here
            lat += sample_voxels(rates_tex, p, false); // extinction times rate: over beta, the rate
#endif
    }
    float beta = b.x + b.y;
    float tau = beta * dsub;
    float f_ice = beta > 0.0 ? b.x / beta : 0.0;
#if MULTIPLE
#if LATERAL
    vec2 rates = beta > 0.0 ? lat / beta : vec2(0.0);
#else
    vec2 rates = vec2(0.0);
#endif
    imageStore(slice_img, ivec3(node.xy, k), vec4(tau, f_ice, rates));
#else
    imageStore(slice_img, ivec3(node.xy, k), vec4(tau, f_ice, 0.0, 0.0));
#endif
}
