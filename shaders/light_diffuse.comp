// Deep light map, multiple scattering: the two-stream pass along every light column, one
// invocation per column, after light_build.comp has swept the beam (docs/lightmap.md,
// "Multiple scattering"): each column is solved as a plane-parallel atmosphere lit at mu0
// (the tilted independent column approximation).  Mirrors light_diffuse_column() in
// src/light/transport.c operation for operation in float32.  Variants: PHASE_MIX 0 when both
// phases' terms are equal (the ice share is then not read); LATERAL 1 when diffuse light
// escapes through the clouds' sides (the slices' escape rates are read).

#ifndef PHASE_MIX
#define PHASE_MIX 1
#endif
#ifndef LATERAL
#define LATERAL 0
#endif

#include "bindings.h"

layout(local_size_x = 8, local_size_y = 8) in;

// the beam at each node; slice k-1..k: tau, ice share, escape rates x, y; 1 - A, g;
// 2 (U + V), 2 (U - V)
#ifndef HALF
#define HALF 0
#endif
#if HALF // the dense map in half floats: the light read, the diffuse light written
layout(r16f, binding = BIND_DIFFUSE_IMG_LIGHT) uniform readonly image3D light_img;
#else
layout(r32f, binding = BIND_DIFFUSE_IMG_LIGHT) uniform readonly image3D light_img;
#endif
layout(rgba32f, binding = BIND_DIFFUSE_IMG_SLICE) uniform readonly image3D slice_img;
layout(rg32f, binding = BIND_DIFFUSE_IMG_ADDING) uniform image3D adding_img;
#if HALF
layout(rg16f, binding = BIND_DIFFUSE_IMG_DIFFUSE) uniform writeonly image3D diffuse_img;
#else
layout(rg32f, binding = BIND_DIFFUSE_IMG_DIFFUSE) uniform writeonly image3D diffuse_img;
#endif

uniform ivec3 grid_n;
uniform int base_y;     // the first row of columns of this dispatch (a build in pieces)
uniform vec2 loss;  // the beam's loss share: water, ice
uniform vec2 back;  // lost and heading up toward the sun's side: water, ice
uniform vec2 gamma; // Eddington coupling 3 (1 - g) / 4: water, ice
uniform float mu0;  // |sin(elevation)|, at least 1e-3

struct slice_terms {
    float tau, loss, back, gamma;
    float refl, trans, keep, absorb, escape; // R, T, 1 - R, 1 - R - T, share of an even
                                             // source's light out of its ends
    float escape_rate, kt;                   // a; k times the vertical optical depth
};

// light_lateral_escape(): the straight-flight rate of each axis, for runs narrower than a
// transport mean free path.
float lateral_escape(float g, vec2 r)
{
    float tr = 4.0 * g / 3.0;
    return (r.x > 0.0 ? r.x * exp(-tr / r.x) : 0.0) + (r.y > 0.0 ? r.y * exp(-tr / r.y) : 0.0);
}

// The slice as an absorbing layer (transport.c, slice_layer).
void slice_layer(float g, float a, float tv, inout slice_terms t)
{
    float x = sqrt(a * (2.0 * g + a)) * tv;
    t.escape_rate = a;
    t.kt = x;
    float p, q, sech;
    if (x < 1.0) { // through sinh(x/2), whose series keeps 1 - sech(x) to the last digit
        float y = 0.5 * x, y2 = y * y;
        float shy = 1.0 + y2 * (1.0 / 6.0) * (1.0 + y2 * (1.0 / 20.0) * (1.0 + y2 * (1.0 / 42.0)));
        float sh = y * shy;
        float ch = 1.0 + 2.0 * sh * sh;
        sech = 1.0 / ch;
        p = shy * sqrt(1.0 + sh * sh) / ch;
        q = shy * shy / (2.0 * ch);
    } else {
        float e = exp(-x), e2 = e * e;
        sech = 2.0 * e / (1.0 + e2);
        p = (1.0 - e2) / (1.0 + e2) / x;
        q = (1.0 - sech) / (x * x);
    }
    float den = 1.0 + (g + a) * tv * p;
    t.refl = g * tv * p / den;
    t.trans = sech / den;
    t.keep = (1.0 + a * tv * p) / den;
    t.absorb = (x * x * q + a * tv * p) / den;
    t.escape = ((2.0 * g + a) * tv * q + p) / den;
}

slice_terms terms(ivec3 c)
{
    vec4 sl = imageLoad(slice_img, c);
#if PHASE_MIX
    float fi = sl.y;
#else
    float fi = 0.0;
#endif
    slice_terms t;
    t.tau = min(sl.x, 1e8);
    t.loss = loss.x + fi * (loss.y - loss.x);
    float bk = back.x + fi * (back.y - back.x);
    t.back = min(max(bk / t.loss, 0.0), 1.0);
    t.gamma = gamma.x + fi * (gamma.y - gamma.x);
#if LATERAL
    float a = lateral_escape(t.gamma, sl.zw);
#else
    float a = 0.0;
#endif
    slice_layer(t.gamma, a, mu0 * t.tau, t);
    return t;
}

// (1 - e^-z) / z for z >= 0 (transport.c, one_minus_exp_over).
float one_minus_exp_over(float z)
{
    if (z < 0.25)
        return 1.0 - z * (1.0 / 2.0) *
                         (1.0 - z * (1.0 / 3.0) *
                                    (1.0 - z * (1.0 / 4.0) *
                                               (1.0 - z * (1.0 / 5.0) *
                                                          (1.0 - z * (1.0 / 6.0) *
                                                                     (1.0 - z / 7.0)))));
    return (1.0 - exp(-z)) / z;
}

// Diffuse light out of a slice's sun side (x) and far side (y) for the beam D0 entering it
// (transport.c, column_slice and slice_sources): an even source's share for thin slices,
// the exponential source through the layer's Green's function otherwise.
vec2 sources(float d0, slice_terms t)
{
    float x = t.loss * t.tau;
    float w = mu0 * d0 * (1.0 - exp(-x));
    float tv = mu0 * t.tau;
    if (t.kt < 0.01) {
        x = min(x, 1e8);
        float a1 = x < 0.1 ? 0.5 + x * (1.0 / 12.0) - x * x * x * (1.0 / 720.0)
                           : 1.0 / (1.0 - exp(-x)) - 1.0 / x;
        float gw = t.gamma * tv * w;
        vec2 s = vec2(t.back * w + gw * a1, (1.0 - t.back) * w + gw * (1.0 - a1));
        return s * (t.escape / (1.0 + t.gamma * tv));
    }
    float kt = t.kt, g = t.gamma, g1 = g + t.escape_rate, k = kt / tv;
    float ek = exp(-kt);
    float ap = one_minus_exp_over(x + kt);
    float am = exp(-min(x, kt)) * one_minus_exp_over(abs(x - kt));
    float h = 0.5 * w / one_minus_exp_over(x);
    float jch = h * (am + ek * ap), jsh = max(h * (am - ek * ap), 0.0) / k;
    float ich = h * (ap + ek * am), ish = max(h * (ap - ek * am), 0.0) / k;
    float den = 0.5 * (1.0 + ek * ek) + g1 * tv * one_minus_exp_over(2.0 * kt);
    float sb = t.back;
    return vec2((sb * (ich + g1 * ish) + (1.0 - sb) * g * ish) / den,
                ((1.0 - sb) * (jch + g1 * jsh) + sb * g * jsh) / den);
}

void main()
{
    ivec2 ij = ivec2(gl_GlobalInvocationID.xy) + ivec2(0, base_y);
    if (ij.x >= grid_n.x || ij.y >= grid_n.y)
        return;
    int n = grid_n.z;
    float k = 1.0, g = 0.0; // beyond the last node: nothing sends light back
    imageStore(adding_img, ivec3(ij, n - 1), vec4(k, g, 0.0, 0.0));
    for (int l = n - 1; l >= 1; l--) {
        slice_terms t = terms(ivec3(ij, l));
        vec2 s = sources(imageLoad(light_img, ivec3(ij, l - 1)).r, t);
        float den = t.keep + k * t.refl;
        g = s.x + t.trans * (g + (1.0 - k) * s.y) / den;
        k = t.absorb + t.trans * (t.absorb + k * (t.refl + t.trans)) / den;
        imageStore(adding_img, ivec3(ij, l - 1), vec4(k, g, 0.0, 0.0));
    }
    float u = 0.0; // no diffuse light enters from the sun's side
    imageStore(diffuse_img, ivec3(ij, 0), vec4(2.0 * g, -2.0 * g, 0.0, 0.0));
    for (int l = 1; l < n; l++) {
        slice_terms t = terms(ivec3(ij, l));
        vec2 s = sources(imageLoad(light_img, ivec3(ij, l - 1)).r, t);
        vec2 kg = imageLoad(adding_img, ivec3(ij, l)).rg;
        float den = t.keep + kg.x * t.refl;
        u = (t.trans * u + s.y + t.refl * kg.y) / den;
        float v = (1.0 - kg.x) * u + kg.y;
        imageStore(diffuse_img, ivec3(ij, l), vec4(2.0 * (u + v), 2.0 * (u - v), 0.0, 0.0));
    }
}
