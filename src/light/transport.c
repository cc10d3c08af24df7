/* Light transport through the light-space grid, slice by slice from the sun (Nes §5.2.3). */
#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "common/parallel.h"
#include "light/light.h"

#define PI 3.14159265358979323846

/* The volume's sampling constants in float32, as the GPU holds them. */
struct beta_sampler {
    const float *beta;
    int n[3];
    float origin[3];
    float inv_spacing[3];
    /* A stretched grid's height mapping: the GPU's table (grid3_zmap_fill) when ZMAP is set,
     * else grid3_z_to_voxel on GRID; GRID NULL on a uniform grid. */
    const struct grid3 *grid;
    float *zmap;
    int zmap_n;
    float zmap_inv_height; /* 1 / the box's height, 1/m */
};

static void sampler_init(struct beta_sampler *s, const struct ext_volume *vol)
{
    memset(s, 0, sizeof(*s));
    s->beta = vol->beta;
    for (int a = 0; a < 3; a++) {
        s->n[a] = vol->grid.n[a];
        s->origin[a] = (float)vol->grid.origin[a];
        s->inv_spacing[a] = (float)(1.0 / vol->grid.spacing[a]);
    }
    if (grid3_stretched(&vol->grid))
        s->grid = &vol->grid;
}

/* The light map build samples heights through the table the GPU reads, so that both builds
 * see the same extinction.  False (logged) when out of memory. */
static bool sampler_use_zmap(struct beta_sampler *s)
{
    if (!s->grid)
        return true;
    s->zmap_n = grid3_zmap_entries(s->grid);
    s->zmap = malloc((size_t)s->zmap_n * sizeof(float));
    if (!s->zmap) {
        log_error("light map: out of memory for the height table");
        return false;
    }
    grid3_zmap_fill(s->grid, s->zmap_n, s->zmap, NULL);
    s->zmap_inv_height = (float)(1.0 / (s->grid->n[2] * s->grid->spacing[2]));
    return true;
}

/* Height P2 inside the box -> continuous voxel coordinate along z on a stretched grid. */
static float sampler_z(const struct beta_sampler *s, float p2)
{
    if (!s->zmap)
        return (float)grid3_z_to_voxel(s->grid, p2);
    /* As shaders/zmap.glsl reads the table, operation for operation. */
    float h = fminf(fmaxf((p2 - s->origin[2]) * s->zmap_inv_height, 0.0f), 1.0f);
    float f = h * (float)(s->zmap_n - 1);
    int i = (int)f;
    i = i > s->zmap_n - 2 ? s->zmap_n - 2 : i;
    float t = f - (float)i;
    return (s->zmap[i] + t * (s->zmap[i + 1] - s->zmap[i])) * (float)s->n[2];
}

/* Continuous voxel coordinate X (voxel units from the box minimum) -> lower voxel index and
 * weight of the upper one, clamped to the edge voxels. */
static int axis_weight(float x, int n, float *t)
{
    float f = x - 0.5f;
    if (n < 2 || f <= 0.0f) {
        *t = 0.0f;
        return 0;
    }
    if (f >= (float)(n - 1)) {
        *t = 1.0f;
        return n - 2;
    }
    int i = (int)f;
    *t = f - (float)i;
    return i;
}

static void sample_beta(const struct beta_sampler *s, const float p[3], float out[2])
{
    float x[3];
    for (int a = 0; a < 3; a++) {
        x[a] = (p[a] - s->origin[a]) * s->inv_spacing[a];
        if (!(x[a] >= 0.0f && x[a] <= (float)s->n[a])) { /* outside the box (or NaN) */
            out[0] = out[1] = 0.0f;
            return;
        }
    }
    if (s->grid) /* the box test above on the mean spacing, the weights on the levels */
        x[2] = sampler_z(s, p[2]);
    float t[3];
    int i0[3], di[3];
    for (int a = 0; a < 3; a++) {
        i0[a] = axis_weight(x[a], s->n[a], &t[a]);
        di[a] = s->n[a] > 1 ? 1 : 0;
    }
    size_t sx = (size_t)di[0], sy = (size_t)di[1] * (size_t)s->n[0];
    size_t sz = (size_t)di[2] * (size_t)s->n[0] * (size_t)s->n[1];
    size_t base = (size_t)i0[0] + (size_t)s->n[0] * ((size_t)i0[1] + (size_t)s->n[1] * i0[2]);
    for (int c = 0; c < 2; c++) {
        const float *b = s->beta + c;
        float c00 = b[2 * base] + t[0] * (b[2 * (base + sx)] - b[2 * base]);
        float c10 = b[2 * (base + sy)] + t[0] * (b[2 * (base + sy + sx)] - b[2 * (base + sy)]);
        float c01 = b[2 * (base + sz)] + t[0] * (b[2 * (base + sz + sx)] - b[2 * (base + sz)]);
        float c11 = b[2 * (base + sz + sy)] +
                    t[0] * (b[2 * (base + sz + sy + sx)] - b[2 * (base + sz + sy)]);
        float c0 = c00 + t[1] * (c10 - c00);
        float c1 = c01 + t[1] * (c11 - c01);
        float v = c0 + t[2] * (c1 - c0);
        out[c] = v >= 0.0f ? fminf(v, 1e30f) : 0.0f; /* NaN -> 0; Inf kept finite */
    }
}

void light_sample_beta(const struct ext_volume *vol, const float p[3], float out[2])
{
    struct beta_sampler s;
    sampler_init(&s, vol);
    sample_beta(&s, p, out);
}

void light_settings_defaults(struct light_settings *s)
{
    memset(s, 0, sizeof(*s));
    s->resolution[0] = s->resolution[1] = s->resolution[2] = 128;
    s->forward_angle_deg = 20.0;
    s->forward = true;
    s->peripheral = true;
    s->lateral = true;
    s->epsilon = 0.002;
    s->substeps = 0;
}

int light_auto_substeps(const struct light_grid *g, const struct grid3 *box)
{
    double cross = INFINITY;
    for (int a = 0; a < 3; a++) {
        if (fabs(g->w[a]) > 0.0)
            cross = fmin(cross, (a == 2 ? grid3_min_dz(box) : box->spacing[a]) / fabs(g->w[a]));
    }
    double m = ceil(g->step[2] / cross - 1e-9);
    return m < 1.0 ? 1 : m > 128.0 ? 128 : (int)m;
}

void light_settings_set_optics(struct light_settings *s, const struct optics_params *optics,
                               double forward_angle_deg)
{
    s->forward_angle_deg = forward_angle_deg;
    optics_forward_cp(optics, forward_angle_deg * (PI / 180.0), &s->cp);
}

void light_settings_one_phase(struct light_settings *s, bool ice)
{
    struct optics_cp *c = &s->cp;
    if (ice) {
        c->water_ctr = c->ice_ctr;
        c->water_per = c->ice_per;
        c->water_cs_g = c->ice_cs_g;
        c->water_gamma = c->ice_gamma;
    } else {
        c->ice_ctr = c->water_ctr;
        c->ice_per = c->water_per;
        c->ice_cs_g = c->water_cs_g;
        c->ice_gamma = c->water_gamma;
    }
}

bool light_settings_phases_equal(const struct light_settings *s)
{
    const struct optics_cp *c = &s->cp;
    return c->ice_ctr == c->water_ctr && c->ice_per == c->water_per &&
           c->ice_cs_g == c->water_cs_g && c->ice_gamma == c->water_gamma;
}

void light_grid_peripheral_taps(const struct light_grid *g, double r, float out[2])
{
    out[0] = (float)(r / g->step[0]);
    out[1] = (float)(r / (g->step[1] * (g->sheared ? fabs(g->w[2]) : 1.0)));
}

double light_peripheral_offset(double forward_angle_deg, double dz)
{
    /* Riley §4.4: the outer band runs from theta/4 to theta/2; its four samples are taken at
     * the band's middle angle, 3 theta / 8, one slice back. */
    return dz * tan(0.375 * forward_angle_deg * (PI / 180.0));
}

/* Bilinear lookup in node plane PL (n0 x n1) at node coordinates (x, y); nodes outside the
 * plane read as the incident light 1. */
static float plane_tap(const float *pl, int n0, int n1, float x, float y)
{
    float fx = floorf(x), fy = floorf(y);
    float tx = x - fx, ty = y - fy;
    int ix = (int)fx, iy = (int)fy;
    float v[2][2];
    for (int b = 0; b < 2; b++) {
        for (int a = 0; a < 2; a++) {
            int i = ix + a, j = iy + b;
            v[b][a] = (i < 0 || j < 0 || i >= n0 || j >= n1) ? 1.0f : pl[i + (size_t)n0 * j];
        }
    }
    float r0 = v[0][0] + tx * (v[0][1] - v[0][0]);
    float r1 = v[1][0] + tx * (v[1][1] - v[1][0]);
    return r0 + ty * (r1 - r0);
}

void light_map_finish(struct light_map *map)
{
    if (!map)
        return;
    free(map->light);
    free(map->diffuse);
    memset(map, 0, sizeof(*map));
}

/* The diffuse light that a slice of vertical optical depth TAU sends out of its sun-side end
 * (*SU) and its far end (*SD), times (1 + GT), when the beam deposits W in it with a source
 * fading as e^(-X t / TAU) from its sun side, a backward share SB and the coupling
 * GT = GAMMA TAU: the Eddington two-stream equations solved exactly with no diffuse light
 * entering the slice (docs/lightmap.md).  Their sum is (1 + GT) W: nothing is lost. */
static void slice_sources(float w, float x, float tau, float sb, float gamma, float *su,
                          float *sd)
{
    /* The share of the coupled term that leaves by the sun side: 1 / (1 - e^-x) - 1 / x (its
     * series below 0.1, where the two terms cancel in float32). */
    float a1;
    x = fminf(x, 1e8f);
    if (x < 0.1f)
        a1 = 0.5f + x * (1.0f / 12.0f) - x * x * x * (1.0f / 720.0f);
    else
        a1 = 1.0f / (1.0f - expf(-x)) - 1.0f / x;
    float gw = gamma * tau * w;
    *su = sb * w + gw * a1;
    *sd = (1.0f - sb) * w + gw * (1.0f - a1);
}

/* One slice of the beam (docs/lightmap.md, "Integrating a slice"): the per-slice equations of
 * Nes eq. 5.8-5.10 are the one-step form of dL/dtau = -(1 - CP_ctr) L + CP_per L_per; the
 * slice is integrated exactly, taking the peripheral light to decay as a beam in the same
 * medium does, exp(-(1 - CP_ctr - CP_per) tau).  The result no longer depends on how many
 * slices a path is cut into, and it equals Nes' form to first order in tau. */
static float beam_slice(float l_in, float l_per, float tau, float cpc, float cpp, bool fwd,
                        bool per)
{
    if (!fwd)
        return l_in * expf(-tau); /* Nes eq. 5.8 */
    float a = 1.0f - cpc;
    float ea = expf(-a * tau);
    if (!per)
        return l_in * ea;
    float ek = expf(-(a - cpp) * tau);
    return l_in * ea + l_per * (ek - ea);
}

void light_diffuse_terms_init(const struct light_settings *s, const double sun[3],
                              struct light_diffuse_terms *t)
{
    const struct optics_cp *c = &s->cp;
    const bool fwd = s->forward, per = s->forward && s->peripheral;
    double len = sqrt(sun[0] * sun[0] + sun[1] * sun[1] + sun[2] * sun[2]);
    double mu0 = len > 0.0 && isfinite(len) ? fmin(fabs(sun[2]) / len, 1.0) : 1.0;
    /* What the beam keeps: nothing with forward scattering off, the central cone (theta/4),
     * or the cone and the peripheral ring (theta/2). */
    double psi_min = !fwd ? 0.0 : (per ? 0.5 : 0.25) * s->forward_angle_deg * (PI / 180.0);
    const double ctr[2] = {c->water_ctr, c->ice_ctr}, ring[2] = {c->water_per, c->ice_per};
    const double csg[2] = {c->water_cs_g, c->ice_cs_g};
    const double gam[2] = {c->water_gamma, c->ice_gamma};
    for (int p = 0; p < 2; p++) {
        double loss = !fwd ? 1.0 : 1.0 - ctr[p] - (per ? ring[p] : 0.0);
        t->loss[p] = (float)fmax(loss, 1e-6);
        t->back[p] = (float)phase_cs_back_fraction(csg[p], psi_min, mu0);
        t->gamma[p] = (float)gam[p];
    }
    t->mu0 = (float)fmax(mu0, 1e-3);
}

float light_lateral_escape(float gamma, float rx, float ry)
{
    float tr = 4.0f * gamma / 3.0f; /* 1 - g: a transport mean free path is 1 / tr */
    return (rx > 0.0f ? rx * expf(-tr / rx) : 0.0f) + (ry > 0.0f ? ry * expf(-tr / ry) : 0.0f);
}

void light_lateral_rates_plane(const struct ext_volume *vol, int k, float *out)
{
    /* One row at a time, each run's width summed in the order shaders/light_lateral.comp
     * sums it, so both give the same floats. */
    const int *n = vol->grid.n;
    const size_t plane = (size_t)n[0] * n[1];
    for (int axis = 0; axis < 2; axis++) {
        const int len = n[axis], rows = n[1 - axis];
        const size_t stride = axis == 0 ? 1 : (size_t)n[0];
        const float step = (float)vol->grid.spacing[axis];
        for (int r = 0; r < rows; r++) {
            size_t base = axis == 0 ? (size_t)n[0] * r : (size_t)r;
            float *o = out + 2 * base + axis;
            const float *b = vol->beta + 2 * (plane * (size_t)k + base);
            int i = 0;
            while (i < len) {
                size_t v = stride * i;
                if (!(b[2 * v] + b[2 * v + 1] >= LIGHT_CLEAR_BETA)) { /* clear, or NaN */
                    o[2 * v] = 0.0f;
                    i++;
                    continue;
                }
                float w = 0.0f;
                int end = i;
                for (; end < len; end++) {
                    size_t e = stride * end;
                    float be = b[2 * e] + b[2 * e + 1];
                    if (!(be >= LIGHT_CLEAR_BETA))
                        break;
                    w += fminf(be, 1e30f) * step;
                }
                for (int m = i; m < end; m++) { /* w >= LIGHT_CLEAR_BETA step > 0 */
                    size_t e = stride * m;
                    o[2 * e] = fminf(b[2 * e] + b[2 * e + 1], 1e30f) / w;
                }
                i = end;
            }
        }
    }
}

struct rates_job {
    const struct ext_volume *vol;
    float *out;
};

static bool rates_planes(void *ctx, int share, size_t begin, size_t end)
{
    const struct rates_job *j = ctx;
    size_t plane = (size_t)j->vol->grid.n[0] * j->vol->grid.n[1];
    for (size_t k = begin; k < end; k++)
        light_lateral_rates_plane(j->vol, (int)k, j->out + 2 * plane * k);
    return true;
}

void light_lateral_rates(const struct ext_volume *vol, float *out)
{
    struct rates_job j = {.vol = vol, .out = out};
    parallel_for((size_t)vol->grid.n[2], 1, &j, rates_planes); /* a share of planes per CPU */
}

/* The terms of one slice, mixed by its ice share. */
struct slice_terms {
    float tau, loss, back, gamma; /* slant optical depth, beam loss rate, backward share,
                                     coupling */
    float refl, trans, keep, absorb, escape; /* the slice as a layer: reflectance R,
                                                transmittance T, 1 - R, 1 - R - T (each
                                                computed without cancellation), and the share
                                                of an even source's light out of its ends */
    float escape_rate, kt; /* lateral escape a; k times the vertical optical depth */
};

/* The slice as a layer of vertical optical depth TV with coupling G and lateral escape A:
 * the two-stream equations with gamma1 = G + A, gamma2 = G solved in closed form, written
 * with x = k TV (k^2 = A (2 G + A)), p = tanh(x) / x and q = (1 - sech x) / x^2 so that every
 * term stays finite and A = 0 is exact: R = G TV p / D, T = sech(x) / D with
 * D = 1 + (G + A) TV p; the absorptance 1 - R - T = (x^2 q + A TV p) / D; and the share of
 * a source spread evenly through the layer that leaves by its ends, (1 - R - T) / (A TV) =
 * ((2 G + A) TV q + p) / D (docs/lightmap.md, "Lateral escape"). */
static void slice_layer(float g, float a, float tv, struct slice_terms *t)
{
    float x = sqrtf(a * (2.0f * g + a)) * tv;
    t->escape_rate = a;
    t->kt = x;
    float p, q, sech;
    if (x < 1.0f) { /* through sinh(x/2), whose series keeps 1 - sech(x) to the last digit */
        float y = 0.5f * x, y2 = y * y;
        float shy = 1.0f + y2 * (1.0f / 6.0f) * (1.0f + y2 * (1.0f / 20.0f) *
                                                          (1.0f + y2 * (1.0f / 42.0f)));
        float sh = y * shy; /* sinh(x/2), shy = sinh(x/2) / (x/2) */
        float ch = 1.0f + 2.0f * sh * sh; /* cosh(x) */
        sech = 1.0f / ch;
        p = shy * sqrtf(1.0f + sh * sh) / ch; /* tanh(x) / x */
        q = shy * shy / (2.0f * ch);          /* (1 - sech x) / x^2 */
    } else {
        float e = expf(-x), e2 = e * e;
        sech = 2.0f * e / (1.0f + e2);
        p = (1.0f - e2) / (1.0f + e2) / x;
        q = (1.0f - sech) / (x * x);
    }
    float den = 1.0f + (g + a) * tv * p;
    t->refl = g * tv * p / den;
    t->trans = sech / den;
    t->keep = (1.0f + a * tv * p) / den;
    t->absorb = (x * x * q + a * tv * p) / den;
    t->escape = ((2.0f * g + a) * tv * q + p) / den;
}

static struct slice_terms slice_terms(const struct light_diffuse_terms *d, float tau,
                                      float f_ice, const float *lateral)
{
    struct slice_terms t;
    t.tau = fminf(tau, 1e8f); /* deeper is opaque all the same; keeps the sums finite */
    t.loss = d->loss[0] + f_ice * (d->loss[1] - d->loss[0]);
    float back = d->back[0] + f_ice * (d->back[1] - d->back[0]);
    t.back = fminf(fmaxf(back / t.loss, 0.0f), 1.0f);
    t.gamma = d->gamma[0] + f_ice * (d->gamma[1] - d->gamma[0]);
    float a = lateral ? light_lateral_escape(t.gamma, lateral[0], lateral[1]) : 0.0f;
    slice_layer(t.gamma, a, d->mu0 * t.tau, &t);
    return t;
}

/* (1 - e^-z) / z for z >= 0 (1 at 0), without the cancellation of small z. */
static float one_minus_exp_over(float z)
{
    if (z < 0.25f)
        return 1.0f - z * (1.0f / 2.0f) *
                          (1.0f - z * (1.0f / 3.0f) *
                                      (1.0f - z * (1.0f / 4.0f) *
                                                  (1.0f - z * (1.0f / 5.0f) *
                                                              (1.0f - z * (1.0f / 6.0f) *
                                                                          (1.0f - z / 7.0f)))));
    return (1.0f - expf(-z)) / z;
}

/* The diffuse light out of the slice's two ends for the beam D0 entering it.  Without escape
 * (or with so little that k tau_v < 0.01) slice_sources, scaled by the share an even source
 * would get out of the ends (off by at most (k tau_v)^2 / 2 for the real source).  Else the
 * exact answer for the exponential source S(t) = S0 e^-(c t), c tau_v = x: the light emitted
 * at depth t leaves by the sun side in the share
 * [s_u (k ch(k(tau - t)) + g1 sh(k(tau - t))) + s_d g2 sh(k(tau - t))] / D and by the far side
 * in [s_d (k ch(k t) + g1 sh(k t)) + s_u g2 sh(k t)] / D, D = k ch(k tau) + g1 sh(k tau)
 * (the layer's Green's function, from the R and T of its two parts), and the integrals over t
 * are sums of E(z) = (1 - e^-z) / z, written with e^(-k tau) factored out so that nothing
 * overflows (docs/lightmap.md, "Lateral escape"). */
static void column_slice(const struct light_diffuse_terms *d, const struct slice_terms *t,
                         float d0, float *su, float *sd)
{
    float x = t->loss * t->tau;
    float w = d->mu0 * d0 * (1.0f - expf(-x)); /* per unit horizontal area */
    float tv = d->mu0 * t->tau;
    if (t->kt < 0.01f) {
        slice_sources(w, x, tv, t->back, t->gamma, su, sd);
        float s = t->escape / (1.0f + t->gamma * tv);
        *su *= s;
        *sd *= s;
        return;
    }
    float kt = t->kt, g = t->gamma, g1 = g + t->escape_rate, k = kt / tv;
    float ek = expf(-kt);
    float ap = one_minus_exp_over(x + kt);                           /* E((c + k) tau) */
    float am = expf(-fminf(x, kt)) * one_minus_exp_over(fabsf(x - kt)); /* e^-k tau E((c-k)tau) */
    /* S0 tau / 2 times the four integrals, each over e^(k tau): S0 tau = W / E(x). */
    float h = 0.5f * w / one_minus_exp_over(x);
    float jch = h * (am + ek * ap), jsh = fmaxf(h * (am - ek * ap), 0.0f) / k;
    float ich = h * (ap + ek * am), ish = fmaxf(h * (ap - ek * am), 0.0f) / k;
    float den = 0.5f * (1.0f + ek * ek) + g1 * tv * one_minus_exp_over(2.0f * kt); /* D */
    float sb = t->back;
    *su = (sb * (ich + g1 * ish) + (1.0f - sb) * g * ish) / den;
    *sd = ((1.0f - sb) * (jch + g1 * jsh) + sb * g * jsh) / den;
}

void light_diffuse_column(int n, const float *beam, const float *tau, const float *f_ice,
                          const float *lateral, const struct light_diffuse_terms *d,
                          float *scratch, float *out)
{
    /* Adding method, from the far end toward the sun: k[l] = 1 - A_l with A_l the albedo of
     * everything beyond node l (kept as its complement: it is what thick columns need to
     * the last digit), g[l] the diffuse light coming back out of it when none goes in.  Then
     * from the sun's side: u the diffuse flux away from the sun's side. */
    float *k = scratch, *g = scratch + n;
    k[n - 1] = 1.0f; /* nothing beyond the last node sends light back */
    g[n - 1] = 0.0f;
    for (int l = n - 1; l >= 1; l--) {
        struct slice_terms t = slice_terms(d, tau[l], f_ice[l], lateral ? lateral + 2 * l : NULL);
        float su, sd;
        column_slice(d, &t, beam[l - 1], &su, &sd);
        float den = t.keep + k[l] * t.refl; /* 1 - R_slice A_l */
        g[l - 1] = su + t.trans * (g[l] + (1.0f - k[l]) * sd) / den;
        k[l - 1] = t.absorb + t.trans * (t.absorb + k[l] * (t.refl + t.trans)) / den;
    }
    float u = 0.0f; /* no diffuse light enters from the sun's side */
    out[0] = 2.0f * g[0];
    out[1] = -2.0f * g[0];
    for (int l = 1; l < n; l++) {
        struct slice_terms t = slice_terms(d, tau[l], f_ice[l], lateral ? lateral + 2 * l : NULL);
        float su, sd;
        column_slice(d, &t, beam[l - 1], &su, &sd);
        float den = t.keep + k[l] * t.refl;
        u = (t.trans * u + sd + t.refl * g[l]) / den;
        float v = (1.0f - k[l]) * u + g[l];
        out[2 * l] = 2.0f * (u + v);
        out[2 * l + 1] = 2.0f * (u - v);
    }
}

bool light_map_build(const struct ext_volume *vol, const double sun[3],
                     const struct light_settings *s, struct light_map *map)
{
    assert(vol && vol->beta && sun && s && map);
    float *reuse = map->light;
    size_t old_count = map->light ? (size_t)map->grid.n[0] * map->grid.n[1] * map->grid.n[2] : 0;
    map->light = NULL;
    if (!light_grid_init(&map->grid, sun, &vol->grid, s->resolution, s->grid)) {
        free(reuse);
        light_map_finish(map);
        return false;
    }
    const struct light_grid *g = &map->grid;
    const int n0 = g->n[0], n1 = g->n[1], n2 = g->n[2];
    size_t plane = (size_t)n0 * n1, count = plane * n2;
    if (reuse && old_count == count) {
        map->light = reuse;
    } else {
        free(reuse);
        map->light = malloc(count * sizeof(float));
        if (!map->light) {
            log_error("light map: out of memory for %d x %d x %d nodes", n0, n1, n2);
            light_map_finish(map);
            return false;
        }
    }

    struct beta_sampler bs;
    sampler_init(&bs, vol);
    if (!sampler_use_zmap(&bs)) {
        light_map_finish(map);
        return false;
    }
    map->substeps = s->substeps > 0 ? s->substeps : light_auto_substeps(g, &vol->grid);
    const int sub = map->substeps;
    const float dsub = (float)(g->step[2] / sub);
    const bool fwd = s->forward;
    const bool per = s->forward && s->peripheral;
    const float cpc_water = (float)s->cp.water_ctr, cpc_ice = (float)s->cp.ice_ctr;
    const float cpp_water = (float)s->cp.water_per, cpp_ice = (float)s->cp.ice_per;
    const double r = light_peripheral_offset(s->forward_angle_deg, g->step[2]);
    float taps[2];
    light_grid_peripheral_taps(g, r, taps);
    const float rx = taps[0], ry = taps[1];

    float *L = map->light;
    for (size_t c = 0; c < plane; c++)
        L[c] = 1.0f; /* node plane 0 touches the box only at its sun-most corner */
    /* With multiple scattering: each slice's optical depth and ice share, for the column pass. */
    float *slice = NULL, *rates = NULL;
    const bool lateral = s->multiple && s->lateral;
    struct beta_sampler rs = bs;
    free(map->diffuse);
    map->diffuse = NULL;
    if (s->multiple) {
        slice = calloc(4 * count, sizeof(float));
        map->diffuse = malloc(2 * count * sizeof(float));
        size_t voxels = (size_t)vol->grid.n[0] * vol->grid.n[1] * vol->grid.n[2];
        rates = lateral ? malloc(2 * voxels * sizeof(float)) : NULL;
        if (!slice || !map->diffuse || (lateral && !rates)) {
            free(slice);
            free(rates);
            log_error("light map: out of memory for the diffuse light of %d x %d x %d nodes",
                      n0, n1, n2);
            free(bs.zmap);
            light_map_finish(map);
            return false;
        }
    }

    if (rates) {
        light_lateral_rates(vol, rates);
        rs.beta = rates;
    }
    for (int k = 1; k < n2; k++) {
        const float *prev = L + plane * (size_t)(k - 1);
        float *cur = L + plane * (size_t)k;
        for (int j = 0; j < n1; j++) {
            for (int i = 0; i < n0; i++) {
                /* Segment from node plane k-1 to k: optical depth by the midpoint rule on SUB
                 * equal parts (one part, the segment midpoint, when the grids match). */
                float b[2] = {0.0f, 0.0f}, lat[2] = {0.0f, 0.0f};
                for (int m = 0; m < sub; m++) {
                    float kz = (float)(k - 1) + ((float)m + 0.5f) / (float)sub;
                    float p[3], bm[2];
                    for (int a = 0; a < 3; a++)
                        p[a] = g->origin[a] + (float)i * g->du[a] + (float)j * g->dv[a] +
                               kz * g->dw[a];
                    sample_beta(&bs, p, bm);
                    b[0] += bm[0];
                    b[1] += bm[1];
                    if (rates && bm[0] + bm[1] > 0.0f) { /* extinction times escape rate:
                                                            their ratio is the rate (0 where
                                                            every voxel around is clear) */
                        float rm[2];
                        sample_beta(&rs, p, rm);
                        lat[0] += rm[0];
                        lat[1] += rm[1];
                    }
                }
                float beta = b[0] + b[1]; /* sum over the parts: tau = beta dsub */
                float l_in = prev[i + (size_t)n0 * j];
                float tau = beta * dsub; /* tau >> 100: the exponentials underflow to 0, fine */
                float f_ice = beta > 0.0f ? b[0] / beta : 0.0f;
                float cpc = cpc_water + f_ice * (cpc_ice - cpc_water);
                float cpp = cpp_water + f_ice * (cpp_ice - cpp_water);
                float l_per = 0.0f;
                if (per && beta > 0.0f) {
                    float fi = (float)i, fj = (float)j;
                    l_per = 0.25f * (plane_tap(prev, n0, n1, fi + rx, fj) +
                                     plane_tap(prev, n0, n1, fi - rx, fj) +
                                     plane_tap(prev, n0, n1, fi, fj + ry) +
                                     plane_tap(prev, n0, n1, fi, fj - ry));
                }
                float l = beam_slice(l_in, l_per, tau, cpc, cpp, fwd, per);
                if (slice) {
                    size_t at = 4 * (i + (size_t)n0 * (j + (size_t)n1 * k));
                    slice[at] = tau;
                    slice[at + 1] = f_ice;
                    slice[at + 2] = beta > 0.0f ? lat[0] / beta : 0.0f;
                    slice[at + 3] = beta > 0.0f ? lat[1] / beta : 0.0f;
                }
                /* Nes eq. 5.11; never above the incident light, never negative. */
                cur[i + (size_t)n0 * j] = fminf(fmaxf(l, 0.0f), 1.0f);
            }
        }
    }
    free(rates);
    free(bs.zmap);
    if (slice) {
        float *col = malloc(9 * (size_t)n2 * sizeof(float));
        if (!col) {
            free(slice);
            log_error("light map: out of memory for a light column");
            light_map_finish(map);
            return false;
        }
        float *beam = col, *tau = col + n2, *fi = col + 2 * n2, *scratch = col + 3 * n2,
              *out = col + 5 * n2, *lat = col + 7 * n2;
        struct light_diffuse_terms terms;
        light_diffuse_terms_init(s, sun, &terms);
        for (size_t c = 0; c < plane; c++) {
            for (int k = 0; k < n2; k++) {
                beam[k] = L[c + plane * k];
                tau[k] = slice[4 * (c + plane * k)];
                fi[k] = slice[4 * (c + plane * k) + 1];
                lat[2 * k] = slice[4 * (c + plane * k) + 2];
                lat[2 * k + 1] = slice[4 * (c + plane * k) + 3];
            }
            light_diffuse_column(n2, beam, tau, fi, lateral ? lat : NULL, &terms, scratch,
                                 out);
            for (int k = 0; k < n2; k++) {
                map->diffuse[2 * (c + plane * k)] = out[2 * k];
                map->diffuse[2 * (c + plane * k) + 1] = out[2 * k + 1];
            }
        }
        free(col);
        free(slice);
    }
    return true;
}

size_t light_map_bytes(const struct light_map *m)
{
    return (size_t)m->grid.n[0] * m->grid.n[1] * m->grid.n[2] * sizeof(float);
}

int light_tex_node(float tex, int n, float *t)
{
    float x = tex * (float)n - 0.5f;
    if (!(x > 0.0f)) {
        *t = 0.0f;
        return 0;
    }
    if (x >= (float)(n - 1)) {
        *t = 1.0f;
        return n - 2;
    }
    int i = (int)x;
    *t = x - (float)i;
    return i;
}

static size_t node_index(const int *n, int i, int j, int k)
{
    return (size_t)i + (size_t)n[0] * ((size_t)j + (size_t)n[1] * (size_t)k);
}

static float sample_nodes(const struct light_map *m, const float *values, int stride,
                          const float tex[3]);

float light_map_sample(const struct light_map *m, const float tex[3])
{
    return sample_nodes(m, m->light, 1, tex);
}

void light_map_sample_diffuse(const struct light_map *m, const float tex[3], float out[2])
{
    out[0] = m->diffuse ? sample_nodes(m, m->diffuse, 2, tex) : 0.0f;
    out[1] = m->diffuse ? sample_nodes(m, m->diffuse + 1, 2, tex) : 0.0f;
}

static float sample_nodes(const struct light_map *m, const float *values, int stride,
                          const float tex[3])
{
    const int *n = m->grid.n;
    int i[3];
    float t[3];
    for (int a = 0; a < 3; a++)
        i[a] = light_tex_node(tex[a], n[a], &t[a]);
    float c[2][2];
    for (int dk = 0; dk < 2; dk++) {
        for (int dj = 0; dj < 2; dj++) {
            float a0 = values[stride * node_index(n, i[0], i[1] + dj, i[2] + dk)];
            float a1 = values[stride * node_index(n, i[0] + 1, i[1] + dj, i[2] + dk)];
            c[dk][dj] = a0 + t[0] * (a1 - a0);
        }
    }
    float c0 = c[0][0] + t[1] * (c[0][1] - c[0][0]);
    float c1 = c[1][0] + t[1] * (c[1][1] - c[1][0]);
    return c0 + t[2] * (c1 - c0);
}
