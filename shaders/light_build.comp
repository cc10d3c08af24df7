// Deep light map, dense: the sweep from the sun (Nes §5.2.3, Riley §4.4) over the slices'
// optical depths and ice shares that light_slices.comp wrote.  Mirrors light_map_build() in
// src/light/transport.c operation for operation in float32; see docs/lightmap.md for the grid
// and what a node stores.  One invocation per light column: with the peripheral ring a plane
// reads its neighbours in the plane before, so a dispatch takes one plane (PLANES planes
// sweep down each column on their own otherwise: one dispatch for the whole map).
// Variants (#define, effects that are off are compiled out): FORWARD 0 = shadow only;
// PERIPHERAL 0 = no peripheral ring; PHASE_MIX 0 = both phases' CP are equal (one phase), so
// the ice share is not read; HALF 1 = the light is stored in half floats.

#include "bindings.h"

#ifndef FORWARD
#define FORWARD 1
#endif
#ifndef PERIPHERAL
#define PERIPHERAL 1
#endif
#ifndef PHASE_MIX
#define PHASE_MIX 1
#endif

layout(local_size_x = 8, local_size_y = 8) in;

#ifndef HALF
#define HALF 0
#endif
#if HALF // the dense map in half floats (renderer_set_half's light map)
layout(r16f, binding = BIND_BUILD_IMG_LIGHT) uniform image3D light_img;
#else
layout(r32f, binding = BIND_BUILD_IMG_LIGHT) uniform image3D light_img; // node (i, j, k): light
#endif
// slice k-1..k: tau, ice share (and, with multiple scattering, escape rates)
layout(binding = BIND_BUILD_TEX_SLICE) uniform sampler3D slice_tex; // texelFetch only

uniform ivec3 grid_n;
uniform int plane;       // the first plane k of this dispatch
uniform int planes;      // how many (1 with the peripheral ring)
uniform vec4 cp;         // water_ctr, ice_ctr, water_per, ice_per
uniform vec2 per_offset; // peripheral offset in node units along u and v

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
    float fi = float(ij.x), fj = float(ij.y);
    int k = plane;
    float l_in = 1.0;
    if (k == 0) {
        imageStore(light_img, ivec3(ij, 0), vec4(1.0));
        k = 1;
    } else {
        l_in = imageLoad(light_img, ivec3(ij, k - 1)).r;
    }
    for (int end = min(plane + planes, grid_n.z); k < end; k++) {
        vec2 sl = texelFetch(slice_tex, ivec3(ij, k), 0).rg;
        float tau = sl.x;
        // The slice integrated exactly (transport.c, beam_slice; docs/lightmap.md): Nes eq.
        // 5.8-5.10 are the one-step form of the same equation.
#if FORWARD
#if PHASE_MIX
        float f_ice = sl.y;
        float cp_ctr = cp.x + f_ice * (cp.y - cp.x);
        float cp_per = cp.z + f_ice * (cp.w - cp.z);
#else
        float cp_ctr = cp.x, cp_per = cp.z;
#endif
        float a = 1.0 - cp_ctr;
        float ea = exp(-a * tau);
        float l = l_in * ea; // the central cone keeps CP(theta/4) of what the slice scatters
#if PERIPHERAL
        if (tau > 0.0) {
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
        l_in = clamp(l, 0.0, 1.0);
        imageStore(light_img, ivec3(ij, k), vec4(l_in)); // Nes eq. 5.11
    }
}
