// Eye pass: one invocation per pixel marches the view ray front to back through the
// extinction volume and adds the sunlight single-scattered toward the eye (Nes eq. 5.18):
//   L = T(0,e) L_bg + sum_s T(0,s) (1 - T_s) P_v(psi) L_l(s)
// with L_l(s) read where the step's light is scattered on average (scattering_depth), not at
// the step's middle, and without MULTIPLE (1 - T_s) L_l(s) the exact integral over the step of
// a beam exponential between the step's ends (beam_step).
// Variants (#define): LIGHTMAP 0 = unshadowed sunlight; 1 = dense light volume;
// 2 = compressed deep light map.  GROUND_SHADOW 1 = the ground reads the light map too.
// OPAQUE 1 = opaque geometry was drawn first (render/opaque.c): rays stop at its distance and
// it is the background there.  PHASE_MIX 0 = one phase for every species (PHASE_ICE 1 the ice
// phase, 0 the water phase) instead of the beta-weighted mix (effects.phase off).
// TINT 1 = the scattered light takes a per-voxel colour (the species' tints).
// TEMPORAL 1 = temporal interpolation (effects.temporal): beta = mix(beta_k, beta_k+1,
// temporal_f) from a second extinction texture (the light map pair is LIGHTMAP_PAIR).
// MULTIPLE 1 = multiple scattering (effects.multiple): the light map's diffuse light (an
// Eddington field along the light) is scattered toward the eye beside the sun's; MULTIPLE 2
// the diffuse light volume's (effects.multiple = "volume") instead.
// LAYERS N (0 to 4) = N colour-mapped layers (docs/analysis.md): each step samples every
// layer's field (trilinear), classifies it by its colour map (post-classification) and either
// adds an emitting, absorbing medium of the map's colour (emit) or tints the clouds' scattered
// light (tint); see march_medium.  An emitting layer turns SKIP off (render.c).
// SLICES N (0 to 4) = N slices: planes through a field, composited where the ray crosses them
// (after the medium of the step that holds the crossing); they turn SKIP off too.
// SKIP 1 = empty-space skipping (render/cells.c): steps whose extinction sample lies in a
// macro cell holding nothing are leapt, exactly (they would add nothing and take nothing off);
// with TEMPORAL the cells hold the larger of both steps.  COUNT 1 = add what each ray did
// (extinction samples, light map reads, cells read, steps leapt) to the counters buffer.
// STRETCHED 1 = the volume is on the model's own levels (data/volume.h): heights reach the
// textures through vol_tex (zmap.glsl), and the automatic step follows the local level
// thickness instead of one voxel size.
// LOD 1 = a level of detail (render.lod): a step is at least lod_pixels pixels wide where it
// is, so that far cloud, whose voxels a pixel covers several of, is sampled at the picture's
// pace rather than the volume's (lod_make).
// BALLOT 1 (PASS 1, where the driver offers GL_ARB_shader_ballot and 64-bit integers): the rays
// left to PASS 2 are listed by a subgroup ballot, one atomic a subgroup, instead of through a
// work group's shared count between three barriers (render.h, renderer_set_ballot).
#if defined(BALLOT) && BALLOT
#extension GL_ARB_shader_ballot : require
#extension GL_ARB_gpu_shader_int64 : require
#endif
uniform vec2 mean_cosine;    // g of the ice and the water phase (MULTIPLE)

#include "bindings.h"
#include "common.glsl"
#include "lightmap_lookup.glsl"

#ifndef PHASE_MIX
#define PHASE_MIX 1
#endif
// The automatic step is taken in light-map-node parts where beta at its middle or its far end
// makes it optically thicker than this.
#ifndef THICK_STEP
#define THICK_STEP 0.3
#endif

// PASS 0: one pass marches every pixel (SKIP 0).  With SKIP 1 two: PASS 1 finds the rays
// that cross only empty cells and draws them (the background), listing the others, which
// PASS 2 marches, one invocation per listed ray (an indirect dispatch of the list's size).
#ifndef PASS
#define PASS 0
#endif
#if PASS == 2
layout(local_size_x = 64) in;
#else
layout(local_size_x = 8, local_size_y = 8) in;
#endif
#if PASS != 0
// The rays to march: PASS 2's indirect dispatch (work groups of 64), their count, and per
// ray its pixel (x | y << 16) and the float bits of the parameter up to which it is clear.
layout(std430, binding = BIND_EYE_BUF_RAYS) buffer ray_list {
    uint rays_groups[3];
    uint rays_count;
    uvec2 rays[];
};
#endif
#ifndef BALLOT
#define BALLOT 0
#endif
#if PASS == 1 && !BALLOT
shared uint group_count, group_base;
#endif

layout(rgba32f, binding = BIND_EYE_IMG_OUT) uniform writeonly image2D out_image;
// r: ice-phase beta, g: water-phase beta [1/m]; r: ice, g: water eye phase over psi in [0, pi]
layout(binding = BIND_EYE_TEX_BETA) uniform sampler3D beta_tex;
layout(binding = BIND_EYE_TEX_PHASE) uniform sampler1D phase_tex;
#ifndef STRETCHED
#define STRETCHED 0
#endif
#if STRETCHED
layout(binding = BIND_EYE_TEX_ZMAP) uniform sampler1D zmap_tex; // texelFetch only
#endif
#include "zmap.glsl"

uniform mat4 inv_proj;      // clip space -> view space (inverted in double)
uniform mat4 inv_view;      // view space -> world (metres)
uniform ivec2 image_size;
uniform ivec2 pixel_offset;  // this view's origin within a larger image (tiles), usually 0
uniform int row_offset;      // the first row of this dispatch (a band of rows), usually 0
uniform vec3 box_min;
uniform vec3 box_size;
uniform float step_len;      // metres; 0 = half the voxel crossing along each ray
uniform vec3 voxel_size;     // metres
uniform int max_steps;       // per ray: bounds the work whatever the step
uniform float termination;   // stop below this transmittance
uniform vec3 sun_dir;        // unit vector toward the sun
uniform vec3 sun_radiance;
uniform vec3 sky_radiance;
uniform vec3 ground_albedo;
uniform int ground_on;
uniform float phase_size;    // entries in phase_tex
uniform vec2 pixel_footprint; // a pixel's width at ray parameter t: x + y t, metres
#ifndef LOD
#define LOD 0
#endif
#if LOD
uniform float lod_pixels;    // a step is at least this many pixels wide (LOD)
uniform float lod_level_dz;  // the thinnest level's height, metres (uniform levels: voxel_size.z)
#endif

// World point P -> texture coordinate of the volume's 3-D textures (all on one grid).
vec3 vol_tex(vec3 p)
{
    vec3 u = (p - box_min) / box_size;
#if STRETCHED
    float n_z = box_size.z / voxel_size.z;
    u.z = zmap_voxel(p.z, box_min.z, n_z, u.z * n_z) / n_z;
#endif
    return u;
}

#ifndef OPAQUE
#define OPAQUE 0
#endif
#ifndef SKIP
#define SKIP 0
#endif
#ifndef COUNT
#define COUNT 0
#endif
#if SKIP
layout(std430, binding = BIND_EYE_BUF_CELLS) readonly buffer macro_cells {
    ivec4 cell_dims[16]; // cells along x, y, z and the level's first index
    ivec4 cell_header;   // levels, voxels per cell edge
    float cell_max[];
};
uniform vec3 cell_size;  // metres, a level-0 cell
#include "cells.glsl"
#endif
#if COUNT
// extinction samples, light map reads, cells read, steps leapt, rays, rays marched (PASS 2);
// each a 64-bit count (low word, high word)
layout(std430, binding = BIND_EYE_BUF_COUNTERS) buffer eye_counters {
    uint counts[12];
};
void count_add(int i, uint v)
{
    if (v == 0u)
        return;
    uint old = atomicAdd(counts[2 * i], v);
    if (old + v < old)
        atomicAdd(counts[2 * i + 1], 1u);
}
#endif
// What the ray did (COUNT); kept whether or not it is counted, the compiler drops it.
uint n_beta = 0u, n_light = 0u, n_cells = 0u, n_leapt = 0u;
#ifndef TINT
#define TINT 0
#endif
#if TINT
layout(binding = BIND_EYE_TEX_TINT) uniform sampler3D tint_tex; // rgb: colour of scattered light
#endif
#ifndef LAYERS
#define LAYERS 0
#endif
#ifndef SLICES
#define SLICES 0
#endif
#if LAYERS || SLICES
layout(binding = BIND_EYE_TEX_LAYER_LUT) uniform sampler2D layer_lut; // row i: rgb, alpha over x
uniform vec2 layer_lut_size; // entries per map, maps

// Colour map ROW at X in [0, 1] of its range.
vec4 colour_map(int row, float x)
{
    vec2 uv = vec2((x * (layer_lut_size.x - 1.0) + 0.5) / layer_lut_size.x,
                   (float(row) + 0.5) / layer_lut_size.y);
    return texture(layer_lut, uv);
}
#endif
#if LAYERS
layout(binding = BIND_EYE_TEX_LAYERS) uniform sampler3D layer_tex;   // channel i: layer i's field
uniform vec4 layer_lo;       // field value at the map's first entry
uniform vec4 layer_scale;    // 1 / (hi - lo)
uniform vec4 layer_strength; // emit: extinction at alpha 1 (1/m); tint: the tint's weight; 0 off
uniform vec4 layer_tint;     // 1: tint mode, 0: emit

// The layers at P: EMIT.rgb the emitting layers' sum of extinction times colour, EMIT.a their
// extinction (1/m); TINT the product of the tinting layers' colours.
void layers_at(vec3 p, out vec4 emit, out vec3 tint)
{
    vec4 s = texture(layer_tex, vol_tex(p));
    emit = vec4(0.0);
    tint = vec3(1.0);
    for (int i = 0; i < LAYERS; i++) {
        if (layer_strength[i] <= 0.0 || isnan(s[i]))
            continue;
        float x = clamp((s[i] - layer_lo[i]) * layer_scale[i], 0.0, 1.0);
        vec4 c = colour_map(i, x);
        if (layer_tint[i] > 0.5) {
            tint *= mix(vec3(1.0), c.rgb, clamp(c.a * layer_strength[i], 0.0, 1.0));
        } else {
            float sigma = c.a * layer_strength[i];
            emit += vec4(c.rgb * sigma, sigma);
        }
    }
}

// (1 - e^-x) / x, 1 at x = 0.
float absorbed_share(float x)
{
    return x < 1e-4 ? 1.0 - 0.5 * x : (1.0 - exp(-x)) / x;
}
#endif
#if SLICES
layout(binding = BIND_EYE_TEX_SLICES) uniform sampler3D slice_tex; // channel i: slice i's field
uniform vec4 slice_plane[4];  // normal . p = w, world metres
uniform vec4 slice_lo, slice_scale, slice_opacity; // opacity 0: off
uniform vec4 slice_contour;   // a line at every multiple of this many field units; 0: none
uniform int slice_row;        // the colour map of slice i is row slice_row + i
uniform vec4 slice_follow;    // 1: slice i is its level surface z = h(x, y), not its plane
uniform vec4 slice_values[6]; // component i of entry k: slice i's k-th contour value ...
uniform vec4 slice_value_count; // ... of this many
layout(binding = BIND_EYE_TEX_SLICE_SURFACES) uniform sampler2D slice_surface_tex; // channel i

// The height of slice I's surface above the point P's column (bilinear between the columns'
// centres, clamped at the edges).
float surface_z(int i, vec3 p)
{
    return texture(slice_surface_tex, (p.xy - box_min.xy) / box_size.xy)[i];
}

// Where the ray ORIGIN + t DIR first crosses slice I's surface in [T0, T1), or 1e30: the sign
// of g(t) = z(t) - h(x(t), y(t)) watched in steps of a quarter of the horizontal voxel (h is
// bilinear between columns, so g is smooth within a step), the crossing then halved down to
// a millionth of a step (docs/analysis.md).
float surface_crossing(int i, vec3 origin, vec3 dir, float t0, float t1)
{
    float horiz = length(dir.xy);
    float ds = 0.25 * min(voxel_size.x, voxel_size.y) / max(horiz, 0.25);
    int steps = int(min(ceil((t1 - t0) / ds), 16384.0));
    float ta = t0;
    vec3 pa = origin + dir * ta;
    float ga = pa.z - surface_z(i, pa);
    if (ga == 0.0)
        return ta;
    for (int n = 1; n <= steps; n++) {
        float tb = min(t0 + float(n) * ds, t1);
        vec3 pb = origin + dir * tb;
        float gb = pb.z - surface_z(i, pb);
        if (sign(gb) != sign(ga)) {
            for (int k = 0; k < 20; k++) {
                float tm = 0.5 * (ta + tb);
                vec3 pm = origin + dir * tm;
                float gm = pm.z - surface_z(i, pm);
                if (sign(gm) == sign(ga)) {
                    ta = tm;
                    ga = gm;
                } else {
                    tb = tm;
                }
            }
            return tb < t1 ? 0.5 * (ta + tb) : 1e30;
        }
        ta = tb;
        ga = gb;
    }
    return 1e30;
}
float slice_t[4];             // where this ray crosses each slice (1e30: not in the box)

// Composites slice I at P, ray parameter T, over RADIANCE and TRANS: its colour map's colour at
// the field's interpolated value, dark within a pixel of a contour (the field's distance to the
// nearest multiple over its gradient along the plane: lines two pixels wide on screen).
void slice_composite(int i, vec3 p, float t, inout vec3 radiance, inout float trans)
{
    vec3 u = vol_tex(p);
    float s = texture(slice_tex, u)[i];
    if (isnan(s))
        return;
    vec3 c = colour_map(slice_row + i,
                        clamp((s - slice_lo[i]) * slice_scale[i], 0.0, 1.0)).rgb;
    // Field units to the nearest line: a multiple of slice_contour, or a given value.
    float off = 1e30;
    if (slice_contour[i] > 0.0) {
        float v = s / slice_contour[i];
        off = abs(v - round(v)) * slice_contour[i];
    }
    for (int k = 0; k < 6; k++)
        if (float(k) < slice_value_count[i])
            off = min(off, abs(s - slice_values[k][i]));
    if (off < 1e30) {
        vec3 h = voxel_size / box_size;
#if STRETCHED
        // Vertically a level's thickness either side, in world heights.
        float dz = zmap_dz(p.z, box_min.z, voxel_size.z);
        vec3 gs = voxel_size;
        gs.z = dz;
        float gz = (texture(slice_tex, vol_tex(p + vec3(0, 0, dz)))[i] -
                    texture(slice_tex, vol_tex(p - vec3(0, 0, dz)))[i]);
#else
        vec3 gs = voxel_size;
        float gz = texture(slice_tex, u + vec3(0, 0, h.z))[i] -
                   texture(slice_tex, u - vec3(0, 0, h.z))[i];
#endif
        vec3 g = vec3(texture(slice_tex, u + vec3(h.x, 0, 0))[i] -
                          texture(slice_tex, u - vec3(h.x, 0, 0))[i],
                      texture(slice_tex, u + vec3(0, h.y, 0))[i] -
                          texture(slice_tex, u - vec3(0, h.y, 0))[i],
                      gz) / (2.0 * gs);
        vec3 n = slice_plane[i].xyz;
        if (slice_follow[i] > 0.0) { // the surface's normal, from its slopes
            vec2 e = voxel_size.xy;
            vec2 dh = vec2(surface_z(i, p + vec3(e.x, 0, 0)) - surface_z(i, p - vec3(e.x, 0, 0)),
                           surface_z(i, p + vec3(0, e.y, 0)) - surface_z(i, p - vec3(0, e.y, 0))) /
                      (2.0 * e);
            n = normalize(vec3(-dh, 1.0));
        }
        float grad = length(g - n * dot(n, g));
        float width = pixel_footprint.x + pixel_footprint.y * t; // a pixel there, metres
        if (grad > 0.0 && off < width * grad)
            c = vec3(0.02);
    }
    float a = slice_opacity[i];
    radiance += trans * a * c;
    trans *= 1.0 - a;
}

#endif
#if TEMPORAL
layout(binding = BIND_EYE_TEX_BETA_NEXT) uniform sampler3D beta_next_tex; // step k + 1, as beta_tex
#endif
#if OPAQUE
// the opaque geometry's radiance, and its distance along the ray from the near plane
layout(binding = BIND_EYE_TEX_OPAQUE_COLOR) uniform sampler2D opaque_color;
layout(binding = BIND_EYE_TEX_OPAQUE_DISTANCE) uniform sampler2D opaque_distance;
#endif

vec2 eye_phase(float cos_psi)
{
    float psi = acos(clamp(cos_psi, -1.0, 1.0));
    float u = (psi / PI * (phase_size - 1.0) + 0.5) / phase_size;
    return texture(phase_tex, u).rg;
}

// The share of the light entering a step of optical depth TAU that the step scatters out of
// a beam falling exponentially from NEAR at its near end to FAR at its far end (both floored
// at 1e-30): integral_0^tau e^-t NEAR e^-(kappa t / tau) dt with kappa = ln(NEAR / FAR)
// = tau (NEAR - FAR e^-tau) / (tau + kappa).  A constant beam gives
// NEAR (1 - e^-tau), the midpoint rule's value; no exponential overflows.
float beam_step(float near, float far, float tau)
{
    float a = max(near, 1e-30), b = max(far, 1e-30);
    float kappa = log(a / b); // within +-69
    tau = min(tau, 1e30);
    float z = tau + kappa;
    if (abs(z) < 1e-4)
        return a * tau * (1.0 - 0.5 * z);
    return tau * (a - b * exp(-tau)) / z;
}

// Where in a step of optical depth TAU its scattering happens on average, as a fraction of the
// step: the mean of t e^-t over [0, tau], 1/2 for a thin step, 1/tau for a thick one.
float scattering_depth(float tau)
{
    if (tau < 1e-3)
        return 0.5 - tau / 12.0;
    if (tau > 40.0)
        return 1.0 / tau;
    float e = exp(-tau);
    return 1.0 / tau - e / (1.0 - e);
}


#if STRETCHED
// The automatic step at height Z on the model's levels, for a ray rising 0.5 / PER_DZ per unit
// length: half the distance in which it crosses the level there, an eighth in levels thinner
// than the mean, whose linear pieces a step's one sample must resolve (a thin layer's optical
// depth to 1e-3; an eighth measured 0.04 % of e^-tau against half's 0.6 %).
float level_step(float z, float per_dz)
{
    float dz = zmap_dz(z, box_min.z, voxel_size.z);
    return dz * per_dz * (dz < voxel_size.z ? 0.25 : 1.0);
}
#endif

// beta at P: NaN and negative read as empty, infinity as the largest float, as in the light
// pass (docs/stability.md); with TEMPORAL the blend of the two time steps.
vec2 beta_at(vec3 p)
{
    n_beta++;
    vec3 u = vol_tex(p);
    vec2 b = texture(beta_tex, u).rg;
    b = vec2(b.x >= 0.0 ? min(b.x, 1e30) : 0.0, b.y >= 0.0 ? min(b.y, 1e30) : 0.0);
#if TEMPORAL
    vec2 bn = texture(beta_next_tex, u).rg;
    bn = vec2(bn.x >= 0.0 ? min(bn.x, 1e30) : 0.0, bn.y >= 0.0 ? min(bn.y, 1e30) : 0.0);
    b = mix(b, bn, temporal_f);
#endif
    return b;
}

// One step of the ray ORIGIN + t DIR over [TA, TA + DS] with beta B (ice phase, water phase)
// and the eye phases PHASE: adds what it scatters toward the eye to RADIANCE and takes its
// transmittance off TRANS.
// With LAYERS the step holds the layers' medium too, each at its value at the step's middle:
// the emitting layers add extinction sigma = sum alpha_i s_i and emission sum sigma_i c_i
// (Max 1995's emission-absorption model), the clouds' beta keeps its own light.  Over a step
// of constant coefficients the exact solution of dL/ds = -(beta + sigma) L + j is
// L += T (1 - e^-(tau + tau_l)) j / (beta + sigma): each medium's light takes its share of the
// step's extinction, and both are attenuated by the sum.  So the layers add
// T f(tau + tau_l) ds sum sigma_i c_i and the clouds' light is scaled by f(tau + tau_l) / f(tau),
// f(x) = (1 - e^-x) / x; the transmittance is multiplied by e^-(tau + tau_l).
void march_medium(vec3 origin, vec3 dir, float ta, float ds, vec2 b, vec2 phase,
                  inout vec3 radiance, inout float trans)
{
    float beta = b.r + b.g;
#if LAYERS
    vec4 emit;
    vec3 tint;
    float layer_trans = 1.0;
    layers_at(origin + dir * (ta + 0.5 * ds), emit, tint);
    if (emit.a > 0.0) {
        float tau_l = emit.a * ds, tau_c = max(beta, 0.0) * ds;
        float f_all = absorbed_share(tau_c + tau_l);
        radiance += trans * f_all * ds * emit.rgb;
        if (beta <= 0.0) {
            trans *= exp(-tau_l);
            return;
        }
        // The clouds' share, below, is scaled by f_all / f(tau); the layers' transmittance
        // is taken off after it.
        tint *= f_all / absorbed_share(tau_c);
        layer_trans = exp(-tau_l);
    }
#endif
    if (beta <= 0.0)
        return;
    float tau = beta * ds;
    float ts = transmittance(tau);
#if PHASE_MIX
    float pv = (b.r * phase.r + b.g * phase.g) / beta; // Nes eq. 5.12
#elif PHASE_ICE
    float pv = phase.r;
#else
    float pv = phase.g;
#endif
#if LIGHTMAP != 0
    n_light += 2u;
#endif
#if MULTIPLE
    vec3 q = origin + dir * (ta + scattering_depth(tau) * ds);
    float beam = lightmap_light(q);
    float g = (b.r * mean_cosine.x + b.g * mean_cosine.y) / beta;
#if MULTIPLE == 2
    float diffuse = volume_scattered(lightmap_volume(q), g, -dir);
#else
    float diffuse = diffuse_scattered(lightmap_diffuse(q), g,
                                      diffuse_mu_eye(dir, sun_dir, beam, g));
#endif
    float light = (1.0 - ts) * (pv * beam + diffuse);
#else
    float light = pv * beam_step(lightmap_light(origin + dir * ta),
                                 lightmap_light(origin + dir * (ta + ds)),
                                 tau);
#endif
#if !LAYERS
    vec3 tint = vec3(1.0);
#endif
#if TINT
    vec3 p = origin + dir * (ta + 0.5 * ds);
    tint *= texture(tint_tex, vol_tex(p)).rgb;
#endif
#if TINT || LAYERS
    radiance += trans * light * sun_radiance * tint;
#else
    radiance += trans * light * sun_radiance;
#endif
#if LAYERS
    trans *= ts * layer_trans;
#else
    trans *= ts;
#endif
}

// A step; with SLICES cut at the slices it crosses, nearest first: the medium up to a slice,
// the slice, the medium on (the step's one extinction sample B for every part).
void march_step(vec3 origin, vec3 dir, float ta, float ds, vec2 b, vec2 phase,
                inout vec3 radiance, inout float trans)
{
#if SLICES
    float t = ta, end = ta + ds;
    for (int k = 0; k < SLICES; k++) {
        int best = -1;
        float bt = end;
        for (int i = 0; i < SLICES; i++) {
            if (slice_t[i] >= t && slice_t[i] < bt) {
                best = i;
                bt = slice_t[i];
            }
        }
        if (best < 0)
            break;
        march_medium(origin, dir, t, bt - t, b, phase, radiance, trans);
        slice_composite(best, origin + dir * bt, bt, radiance, trans);
        slice_t[best] = 1e30; // drawn
        t = bt;
    }
    march_medium(origin, dir, t, end - t, b, phase, radiance, trans);
#else
    march_medium(origin, dir, ta, ds, b, phase, radiance, trans);
#endif
}

// STEP, or with a level of detail the width of LOD_PIXELS pixels at T if that is more, but
// not beyond CAP (lod_make says why).
float lod_grown(float step, float t, float cap)
{
#if LOD
    return max(step, min(lod_pixels * (pixel_footprint.x + pixel_footprint.y * t), cap));
#else
    return step;
#endif
}

#if LOD
// The steps of a ray with a level of detail.  From T0 it steps S (the plain march's step:
// the voxel rule's or render.step, fitted to the ray's length in the box) while that is at
// least LOD_PIXELS pixels' width there; from TU on, after NU steps of S, each step is that
// width at its start, A + B t (the footprint times lod_pixels): in perspective (B > 0) the
// steps grow geometrically, t_k+1 = (1 + B) t_k + A, in an orthographic view (B = 0) they
// are A each; from TG on, after NG steps, where that width reaches SMAX, steps of SMAX.  SMAX
// is half the ray's crossing of a voxel's height (or S, if more): the grown steps coarsen the
// sampling across the grid, never down its levels, so that a thin layer of cloud (a deck,
// an anvil, a cirrus sheet, one level thick) is still sampled twice on its way through.  Every
// step's start is a closed form of its index, so leaping to any step puts it where the march
// would have: skipping stays exact.
struct lod_lattice {
    float t0, s, a, b, tu, c, growth, smax, tg; // c = A / B, growth = ln(1 + B)
    int nu, ng;
};

lod_lattice lod_make(float t0, float s, float smax)
{
    lod_lattice l;
    l.t0 = t0;
    l.s = s;
    l.smax = max(smax, s);
    l.a = min(lod_pixels * pixel_footprint.x, l.smax);
    l.b = lod_pixels * pixel_footprint.y;
    l.c = 0.0;
    l.growth = 0.0;
    if (l.smax <= s) {
        l.nu = 1 << 30; // nothing may grow: the plain march throughout
    } else if (l.b > 0.0) {
        float tc = (s - l.a) / l.b; // the width reaches S here
        l.nu = int(clamp(ceil((tc - t0) / s), 0.0, 1073741823.0));
        l.c = l.a / l.b;
        float u = 1.0 + l.b; // ln(1 + B) without losing B's digits to the sum
        l.growth = u == 1.0 ? l.b : log(u) * l.b / (u - 1.0);
    } else {
        l.nu = l.a > s ? 0 : 1 << 30;
    }
    l.tu = t0 + float(l.nu) * s;
    l.ng = 1 << 30;
    l.tg = 1e30;
    if (l.b > 0.0 && l.nu < (1 << 30)) {
        // A grown step from t is B (t + C) long: SMAX from t = SMAX / B - C on.
        float q = (l.smax / l.b) / (l.tu + l.c);
        l.ng = l.nu + int(clamp(ceil(log(max(q, 1.0)) / l.growth), 0.0, 1073741823.0 - float(l.nu)));
        l.tg = (l.tu + l.c) * exp(float(l.ng - l.nu) * l.growth) - l.c;
    }
    return l;
}

// Where step K starts.
float lod_start(lod_lattice l, int k)
{
    if (k <= l.nu)
        return l.t0 + float(k) * l.s;
    if (l.b <= 0.0)
        return l.tu + float(k - l.nu) * l.a;
    if (k >= l.ng)
        return l.tg + float(k - l.ng) * l.smax;
    return (l.tu + l.c) * exp(float(k - l.nu) * l.growth) - l.c;
}

// The middle of step K (the plain march's arithmetic while K < NU).
float lod_middle(lod_lattice l, int k)
{
    if (k < l.nu)
        return l.t0 + (float(k) + 0.5) * l.s;
    float ta = lod_start(l, k);
    return ta + 0.5 * (lod_start(l, k + 1) - ta);
}

// The first step after step I whose middle lies at or beyond T (T beyond step I's middle):
// the closed form's inverse, then corrected for its rounding by the middles themselves, back
// while the step before has its middle at or beyond T too (a leap must not pass a step that
// may read cloud) and on while this one's lies before T.
int lod_first_from(lod_lattice l, int i, float t)
{
    int k;
    if (t < l.tu + 0.5 * l.s) {
        k = int(ceil((t - l.t0) / l.s - 0.5));
    } else if (l.b <= 0.0) {
        k = l.nu + int(ceil((t - l.tu) / l.a - 0.5));
    } else if (t >= l.tg + 0.5 * l.smax) {
        k = l.ng + int(ceil((t - l.tg) / l.smax - 0.5));
    } else {
        // middle of step k >= t  <=>  t_k >= (t - A/2) / (1 + B/2)
        float tk = (t - 0.5 * l.a) / (1.0 + 0.5 * l.b);
        k = l.nu + int(ceil(log(max((tk + l.c) / (l.tu + l.c), 1e-30)) / l.growth));
        k = min(k, l.ng);
    }
    k = max(k, i + 1);
    for (int n = 0; n < 2 && k > i + 1 && lod_middle(l, k - 1) >= t; n++)
        k--;
    for (int n = 0; n < 2 && lod_middle(l, k) < t; n++)
        k++;
    return k;
}
#endif

void main()
{
#if PASS == 2
    uint slot = gl_GlobalInvocationID.x;
    if (slot >= rays_count)
        return;
    uvec2 entry = rays[slot];
    ivec2 pix = ivec2(int(entry.x & 0xffffu), int(entry.x >> 16));
    bool inside = true;
#else
    ivec2 pix = ivec2(gl_GlobalInvocationID.xy) + ivec2(0, row_offset);
    bool inside = pix.x < image_size.x && pix.y < image_size.y;
#if PASS == 0
    if (!inside)
        return;
#endif
#endif
    vec2 ndc = (vec2(pix) + 0.5) / vec2(image_size) * 2.0 - 1.0;
    // Rays start at the near plane, so an eye inside the volume sees only what is in front.
    vec3 origin, dir;
    view_ray(inv_proj, inv_view, ndc, origin, dir);

    // Opaque ground at z = 0 ends the ray.
    float t_ground = 1e30;
    if (ground_on != 0 && dir.z < 0.0 && origin.z > 0.0)
        t_ground = -origin.z / dir.z;

    float t_opaque = 1e30;
#if OPAQUE
    if (inside)
        t_opaque = texelFetch(opaque_distance, pix, 0).r;
#endif

    vec2 t = ray_box(origin, dir, box_min, box_min + box_size);
    float t0 = max(t.x, 0.0);
    float t1 = min(t.y, min(t_ground, t_opaque));

    vec3 radiance = vec3(0.0);
    float trans = 1.0;
#if SLICES
    for (int i = 0; i < SLICES; i++) {
        float nd = dot(slice_plane[i].xyz, dir);
        slice_t[i] = 1e30;
        if (slice_opacity[i] > 0.0 && slice_follow[i] > 0.0) {
            if (t1 > t0)
                slice_t[i] = surface_crossing(i, origin, dir, t0, t1);
        } else if (slice_opacity[i] > 0.0 && abs(nd) > 1e-12) {
            float ts = (slice_plane[i].w - dot(slice_plane[i].xyz, origin)) / nd;
            if (ts >= t0 && ts < t1)
                slice_t[i] = ts;
        }
    }
#endif
#if SKIP
    vec3 inv_dir = 1.0 / dir_stand_in(dir);
    float nudge = 1e-3 * min(voxel_size.x, min(voxel_size.y, voxel_size.z));
#endif
#if PASS == 1
    // Empty-space skipping, first pass: a ray that crosses only cells holding nothing sees the
    // background as it is (every step would add nothing and take nothing off), and is done
    // here; the others go to the list that the second pass marches, each with the parameter
    // up to which it is known to be clear.  Packing them keeps a SIMD group's rays alike.
    float t_clear = t0, t_occupied;
    bool listed = false;
    if (inside && t1 > t0) {
        if (cells_all_clear(n_cells))
            t_clear = t1;
        else
            t_clear = cells_skip(origin, dir, inv_dir, t0, t1, box_min, cell_size, nudge,
                                 t_occupied, n_cells);
        listed = t_clear < t1;
    }
#if BALLOT
    // The subgroup's listed rays take consecutive slots: the lowest listed lane reserves them
    // all and the others read its base; a lane's slot follows the listed lanes below it.
    uint64_t vote = ballotARB(listed);
    uvec2 voted = unpackUint2x32(vote);
    uvec2 below = unpackUint2x32(vote & gl_SubGroupLtMaskARB);
    uint listed_n = uint(bitCount(voted.x) + bitCount(voted.y));
    uint rank = uint(bitCount(below.x) + bitCount(below.y));
    uint base = 0u;
    if (listed && rank == 0u) {
        base = atomicAdd(rays_count, listed_n);
        atomicMax(rays_groups[0], (base + listed_n + 63u) / 64u);
    }
    if (listed_n > 0u) { // the same in every lane of the subgroup
        uint leader = voted.x != 0u ? uint(findLSB(voted.x)) : 32u + uint(findLSB(voted.y));
        base = readInvocationARB(base, leader);
    }
    if (listed)
        rays[base + rank] = uvec2(uint(pix.x) | (uint(pix.y) << 16), floatBitsToUint(t_clear));
#else
    if (gl_LocalInvocationIndex == 0u)
        group_count = 0u;
    barrier();
    uint local = 0u;
    if (listed)
        local = atomicAdd(group_count, 1u);
    barrier();
    if (gl_LocalInvocationIndex == 0u && group_count > 0u) {
        group_base = atomicAdd(rays_count, group_count);
        atomicMax(rays_groups[0], (group_base + group_count + 63u) / 64u);
    }
    barrier();
    if (listed)
        rays[group_base + local] = uvec2(uint(pix.x) | (uint(pix.y) << 16),
                                         floatBitsToUint(t_clear));
#endif
#if COUNT
    if (listed)
        count_add(2, n_cells); // the others count theirs below
    if (inside)
        count_add(4, 1u);
#endif
    if (!inside || listed)
        return;
#else
    float cos_psi = dot(dir, sun_dir); // scattering angle between sunlight and the eye ray
    vec2 phase = eye_phase(cos_psi);
    if (t1 > t0) {
        float len = t1 - t0;
        float step = step_len;
        int parts = 1;
        if (step <= 0.0) {
            // Half the shortest distance the ray takes to cross one voxel along any axis: a
            // horizontal ray through a flat grid (Isabel: 4 km x 4 km x 200 m) takes steps
            // of the horizontal spacing, a vertical one of the vertical spacing.
            vec3 cross = voxel_size / max(abs(dir), vec3(1e-6));
            step = 0.5 * min(cross.x, min(cross.y, cross.z));
#if LIGHTMAP != 0
            // An optically thick step is taken in PARTS equal parts, as many as it takes to
            // stay within the distance in which the ray crosses one light map node: a sheared
            // map of a flat volume has node planes a fraction of a voxel apart
            // (docs/lightmap.md), and through a cloud top the step's one beta sample would
            // put its scattering far from where it happens.
            vec3 nodes = abs(mat3(light_world_to_tex) * dir) * vec3(light_n);
            // (A step within 0.1 % of one node is not cut: rounding must not halve it.)
            parts = int(ceil(0.999 * step * max(nodes.x, max(nodes.y, nodes.z))));
#endif
        }
        int n = clamp(int(ceil(len / step)), 1, max_steps);
        float ds = len / float(n);
        parts = clamp(parts, 1, max(max_steps / n, 1)); // every part of the ray within max_steps
        // Two light map reads a step in cloud, placed for a step of any optical depth
        // (docs/architecture.md, "The eye pass"): at the top of a thick cloud a step can hold
        // tens of optical depths, and a read at its middle would find the light deep below
        // where all of that step's light is scattered.  With the diffuse light (MULTIPLE) the
        // beam and the diffuse light are read where the step's scattering happens on average
        // (scattering_depth); without it the beam is read at the step's two ends and
        // integrated exactly as an exponential between them (beam_step).
#if SKIP
        // Empty-space skipping, second pass: [t0, t_clear) is known to lie in cells holding
        // nothing (the first pass found where), [t_clear, t_occupied) in an occupied level-0
        // cell; past that the cells are read again.  A step whose extinction sample (and, in
        // parts, far end) lies in a clear cell adds nothing, so leaping it changes no bit of
        // the picture.
        float t_clear = uintBitsToFloat(entry.y), t_occupied = t_clear;
#endif
#if STRETCHED
        if (step_len <= 0.0) {
            // On the model's levels each step follows the level it starts in (or the one it
            // would reach, if thinner; level_step), and is at most half the crossing of a
            // voxel of the mean spacing (voxel_size.z is the mean level: aloft, where the
            // model's levels are thicker, the step stays the uniform grid's, which cloud tops
            // need).  An optically thick step is cut to one light map node, as above.
            vec3 cross = voxel_size / max(abs(dir), vec3(1e-6));
            float step_xy = 0.5 * min(cross.x, min(cross.y, cross.z));
            float per_dz = 0.5 / max(abs(dir.z), 1e-6);
            float node = 1e30;
#if LIGHTMAP != 0
            vec3 nodes = abs(mat3(light_world_to_tex) * dir) * vec3(light_n);
            node = 1.0 / max(max(nodes.x, max(nodes.y, nodes.z)), 1e-30);
#endif
            float t = t0;
            for (int i = 0; i < max_steps; i++) {
                float left = t1 - t;
                if (left <= 1e-6 * len)
                    break;
                float za = origin.z + dir.z * t;
                // (A level of detail grows the step across the grid, never down its levels.)
                float d = min(lod_grown(step_xy, t, 1e30), level_step(za, per_dz));
                d = min(d, level_step(za + dir.z * d, per_dz));
                d = min(d, left);
#if SKIP
                // A step wholly in clear cells adds nothing: t goes over it as the plain march
                // would, without reading the volume.  (Not on to t_clear at once: the steps
                // follow the levels from where they start, and a leap would move every later
                // step's samples.)
                if (t + d > t_clear && t >= t_occupied)
                    t_clear = cells_skip(origin, dir, inv_dir, t, t1, box_min, cell_size, nudge,
                                         t_occupied, n_cells);
                if (t + d <= t_clear) {
                    n_leapt++;
                    t += d;
                    continue;
                }
#endif
                vec2 b = beta_at(origin + dir * (t + 0.5 * d));
                if (d > 1.001 * node) {
                    vec2 be = beta_at(origin + dir * (t + d));
                    if (max(b.r + b.g, be.r + be.g) * d > THICK_STEP) {
                        d = min(node, left);
                        b = vec2(-1.0);
                    }
                }
                if (b.x < 0.0)
                    b = beta_at(origin + dir * (t + 0.5 * d));
                march_step(origin, dir, t, d, b, phase, radiance, trans);
                t += d;
                if (trans < termination)
                    break;
            }
        } else
#endif
#if LOD
        if (parts <= 1) {
            // With a level of detail the steps follow the ray's lattice (lod_make): first the
            // plain march's steps of ds, its loop and arithmetic to the bit, while a pixel is
            // narrower than ds, then steps a few pixels wide, one exponential and one sample
            // each.  Two loops, not one: on a CPU rasteriser, which runs both sides of a branch
            // for a SIMD group, one loop for both made the plain steps 40 % dearer.  A grown
            // step is not cut in light map node parts where it is thick, as the automatic step
            // is: march_medium reads its light at the mean depth of its scattering, and the
            // cut changed the pictures by less than it cost (a loop that, on the same
            // rasteriser, costs its trip whether a ray takes it or not).
            // (A bound within 0.1 % of the plain step is no room to grow: the plain march.)
            float smax = 0.5 * lod_level_dz / max(abs(dir.z), 1e-6);
            lod_lattice l = lod_make(t0, ds, smax > 1.001 * step ? smax : 0.0);
            int n_plain = min(n, l.nu), k = n_plain;
            for (int i = 0; i < n_plain; i++) {
                float tm = t0 + (float(i) + 0.5) * ds;
#if SKIP
                if (tm < t_clear || tm >= t_occupied) {
                    if (tm >= t_clear)
                        t_clear = cells_skip(origin, dir, inv_dir, tm, t1, box_min, cell_size,
                                             nudge, t_occupied, n_cells);
                    if (t_clear > tm) {
                        int next = max(i + 1, int(ceil((t_clear - t0) / ds - 0.5)));
                        if (next >= n_plain) { // into the grown steps (whose loop leaps on
                            n_leapt += uint(n_plain - i); // to the step), or past the end
                            break;
                        }
                        n_leapt += uint(next - i);
                        i = next;
                        tm = t0 + (float(i) + 0.5) * ds;
                    }
                }
#endif
                march_step(origin, dir, t0 + float(i) * ds, ds, beta_at(origin + dir * tm),
                           phase, radiance, trans);
                if (trans < termination)
                    break;
            }
            float ta = lod_start(l, k);
            // (k counts the steps, leapt ones too: at most max_steps, as the plain march.)
            while (k < max_steps && n_plain < n && trans >= termination && ta < t1) {
                float tb = min(lod_start(l, k + 1), t1);
                float tm = ta + 0.5 * (tb - ta);
#if SKIP
                if (tm < t_clear || tm >= t_occupied) {
                    if (tm >= t_clear)
                        t_clear = cells_skip(origin, dir, inv_dir, tm, t1, box_min, cell_size,
                                             nudge, t_occupied, n_cells);
                    if (t_clear > tm) {
                        int next = lod_first_from(l, k, t_clear);
                        n_leapt += uint(next - k);
                        k = next;
                        ta = lod_start(l, k);
                        if (ta >= t1)
                            break;
                        tb = min(lod_start(l, k + 1), t1);
                        tm = ta + 0.5 * (tb - ta);
                    }
                }
#endif
                march_step(origin, dir, ta, tb - ta, beta_at(origin + dir * tm), phase, radiance,
                           trans);
                k++;
                ta = tb;
            }
        } else
#endif
        if (parts <= 1) {
            for (int i = 0; i < n; i++) {
                float tm = t0 + (float(i) + 0.5) * ds;
#if SKIP
                if (tm < t_clear || tm >= t_occupied) {
                    if (tm >= t_clear)
                        t_clear = cells_skip(origin, dir, inv_dir, tm, t1, box_min, cell_size,
                                             nudge, t_occupied, n_cells);
                    if (t_clear > tm) {
                        // On to the first step whose sample lies at or beyond t_clear.
                        int next = max(i + 1, int(ceil((t_clear - t0) / ds - 0.5)));
                        n_leapt += uint(min(next, n) - i);
                        i = next;
                        if (i >= n)
                            break;
                        tm = t0 + (float(i) + 0.5) * ds;
                    }
                }
#endif
                march_step(origin, dir, t0 + float(i) * ds, ds, beta_at(origin + dir * tm),
                           phase, radiance, trans);
                if (trans < termination)
                    break;
            }
        } else {
            // A step whose beta at its middle or its far end makes it optically thick is
            // taken one part at a time; clear air and thin cloud go at the voxel rule's pace.
            float fine = ds / float(parts);
            float t = t0;
#if LOD
            float cap = 0.5 * lod_level_dz / max(abs(dir.z), 1e-6); // lod_grown
            cap = cap > 1.001 * step ? cap : 0.0;
#else
            float cap = 0.0;
#endif
            for (int i = 0; i < max_steps; i++) {
                float left = t1 - t;
                if (left <= 0.01 * fine)
                    break;
                float d = min(lod_grown(ds, t, cap), left);
#if SKIP
                // Steps with both samples in clear cells are steps of d = min(ds, left) (with
                // a level of detail, grown to its width at t) that add nothing: t advances
                // over them exactly as it would, without reading the volume.
                if (t + d > t_clear && t >= t_occupied)
                    t_clear = cells_skip(origin, dir, inv_dir, t, t1, box_min, cell_size, nudge,
                                         t_occupied, n_cells);
                while (t + d <= t_clear && i < max_steps) {
                    t += d;
                    i++;
                    n_leapt++;
                    left = t1 - t;
                    d = min(lod_grown(ds, t, cap), left);
                    if (left <= 0.01 * fine)
                        break;
                }
                if (left <= 0.01 * fine || i >= max_steps)
                    break;
#endif
                vec2 b = beta_at(origin + dir * (t + 0.5 * d));
                vec2 be = beta_at(origin + dir * (t + d));
#if LOD
                // A grown step that is thick is the plain march's step first, then as thick
                // as that is, in its parts.
                if (d > ds && max(b.r + b.g, be.r + be.g) * d > THICK_STEP) {
                    d = min(ds, left);
                    b = beta_at(origin + dir * (t + 0.5 * d));
                    be = beta_at(origin + dir * (t + d));
                }
#endif
                if (max(b.r + b.g, be.r + be.g) * d > THICK_STEP) {
                    d = min(fine, left);
                    b = beta_at(origin + dir * (t + 0.5 * d));
                }
                march_step(origin, dir, t, d, b, phase, radiance, trans);
                t += d;
                if (trans < termination)
                    break;
            }
        }
        if (trans < termination)
            trans = 0.0;
    }
#endif

    vec3 background;
#if OPAQUE
    if (t_opaque < 1e29 && t_opaque <= t_ground) {
        background = texelFetch(opaque_color, pix, 0).rgb;
    } else
#endif
    if (t_ground < 1e29) {
        vec3 g = origin + dir * t_ground;
        // Lambertian ground.  sun_radiance is E / (4 pi) for a sun of irradiance E (so that
        // the volume's single scattering is T (1 - T_s) (4 pi p) sun_radiance), hence the
        // ground's rho E cos / pi = 4 rho sun_radiance cos; a uniform sky adds rho L_sky.
        float sun_light = max(sun_dir.z, 0.0) * ground_light(g);
        background = ground_albedo * (sun_radiance * (4.0 * sun_light + ground_diffuse(g, sun_dir.z)) +
                                      sky_radiance);
    } else {
        background = sky_radiance;
    }
    radiance += trans * background;
    imageStore(out_image, pix + pixel_offset, vec4(radiance, trans));
#if COUNT
    count_add(0, n_beta);
    count_add(1, n_light);
    count_add(2, n_cells);
    count_add(3, n_leapt);
#if PASS == 0
    count_add(4, 1u);
#endif
#if PASS != 1
    count_add(5, 1u);
#endif
#endif
}
