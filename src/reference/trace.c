/*
 * reference/trace: Monte Carlo path tracing of the extinction volume: the bound grid, free
 * flights, transmittance and the radiance of one path.  See reference.h for what it computes
 * and docs/reference.md for the units and the validation.
 */
#include "reference/reference.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"

#define PI 3.14159265358979323846

/* Residual ratio tracking plays Russian roulette below this transmittance. */
#define TR_ROULETTE 0.1
/* Paths play Russian roulette once the largest throughput channel falls below this. */
#define PATH_ROULETTE 0.5

struct reference {
    struct reference_desc d;
    const struct ext_volume *vol;
    double box_min[3], box_max[3];
    double inv_spacing[3];
    size_t stride[3];   /* voxel index step along x, y, z */
    int nb[3];          /* blocks per axis */
    double block_m[3];  /* block edge, metres */
    float *bmax, *bmin; /* per block: bounds of the trilinear total extinction, 1/m */
};

/* ---- free paths ------------------------------------------------------------------------- */

/* Exponential with unit mean: the optical depth to the next event (Elek eq. 2.8). */
static inline double exp_sample(struct reference_rng *rng)
{
    return -log(1.0 - reference_rng_uniform(rng));
}


static double sample_phase(const struct reference *r, double g, struct reference_rng *rng)
{
    return r->d.phase == REFERENCE_PHASE_HG ? reference_sample_hg(g, rng)
                                            : reference_sample_cs(g, rng);
}

static double eval_phase(const struct reference *r, double g, double mu)
{
    return r->d.phase == REFERENCE_PHASE_HG ? phase_hg(g, mu) : phase_cs(g, mu);
}

/* ---- vectors ----------------------------------------------------------------------------- */

static inline double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void normalize3(double v[3])
{
    double l = sqrt(dot3(v, v));
    v[0] /= l;
    v[1] /= l;
    v[2] /= l;
}

/* Turns unit D to the direction at angle acos(MU) from it, azimuth PHI. */
static void turn(double d[3], double mu, double phi)
{
    double u[3], v[3];
    if (fabs(d[0]) > fabs(d[2])) {
        double l = sqrt(d[0] * d[0] + d[1] * d[1]);
        u[0] = -d[1] / l;
        u[1] = d[0] / l;
        u[2] = 0.0;
    } else {
        double l = sqrt(d[1] * d[1] + d[2] * d[2]);
        u[0] = 0.0;
        u[1] = -d[2] / l;
        u[2] = d[1] / l;
    }
    v[0] = d[1] * u[2] - d[2] * u[1];
    v[1] = d[2] * u[0] - d[0] * u[2];
    v[2] = d[0] * u[1] - d[1] * u[0];
    double s = sqrt(fmax(0.0, 1.0 - mu * mu));
    double cp = s * cos(phi), sp = s * sin(phi);
    for (int i = 0; i < 3; i++)
        d[i] = u[i] * cp + v[i] * sp + d[i] * mu;
    normalize3(d);
}

/* ---- the scene --------------------------------------------------------------------------- */

void reference_desc_defaults(struct reference_desc *d)
{
    memset(d, 0, sizeof(*d));
    d->phase = REFERENCE_PHASE_CS;
    d->albedo = 1.0;
    d->sun_dir[2] = 1.0;
    d->block = 8;
}

void reference_desc_from_render(const struct render_settings *s, const struct optics_params *optics,
                                struct reference_desc *d)
{
    reference_desc_defaults(d);
    d->phase = REFERENCE_PHASE_CS;
    d->g_ice = phase_cs_g_for_mean_cosine(optics->g_ice);
    d->g_water = phase_cs_g_for_mean_cosine(optics->g_water);
    double l = 0.0;
    for (int i = 0; i < 3; i++)
        l += (double)s->sun_dir[i] * s->sun_dir[i];
    l = sqrt(l);
    for (int i = 0; i < 3; i++) {
        d->sun_dir[i] = l > 0.0 ? s->sun_dir[i] / l : (i == 2);
        /* The eye pass adds T (1 - T_s) 4 pi p sun_radiance, i.e. int T beta p (4 pi
         * sun_radiance) ds in the limit of small steps; single scattering of a directional
         * source of irradiance E is int T beta p E T_sun ds (Elek eq. 2.11-2.12 with
         * L_in = p E T_sun).  docs/reference.md, "Units". */
        d->sun_irradiance[i] = 4.0 * PI * s->sun_radiance[i];
        d->sky[i] = s->sky[i];
        d->ground_albedo[i] = s->ground[i];
    }
    d->ground_on = s->ground_on;
}

static size_t block_index(const struct reference *r, int bx, int by, int bz)
{
    return (size_t)bx + (size_t)r->nb[0] * ((size_t)by + (size_t)r->nb[1] * (size_t)bz);
}

/* Bounds of the trilinear extinction over each block: a point in block b (voxel coordinates
 * [bB, (b+1)B]) interpolates voxel centres bB-1 ... (b+1)B, so each block takes the min and
 * max of the total extinction over its voxels and a one-voxel apron (clamped at the edges:
 * clamp-to-edge repeats the edge voxel).  Interpolation is a convex combination, so these
 * bound it. */
static void build_bounds(struct reference *r)
{
    const struct grid3 *g = &r->vol->grid;
    const float *beta = r->vol->beta;
    int B = r->d.block;
    for (int bz = 0; bz < r->nb[2]; bz++) {
        for (int by = 0; by < r->nb[1]; by++) {
            for (int bx = 0; bx < r->nb[0]; bx++) {
                int b0[3] = {bx, by, bz}, lo[3], hi[3];
                for (int a = 0; a < 3; a++) {
                    lo[a] = b0[a] * B - 1;
                    hi[a] = (b0[a] + 1) * B;
                    lo[a] = lo[a] < 0 ? 0 : lo[a];
                    hi[a] = hi[a] > g->n[a] - 1 ? g->n[a] - 1 : hi[a];
                }
                if (grid3_stretched(g)) { /* blocks are even in height, the levels are not */
                    double z0 = r->box_min[2] + bz * r->block_m[2];
                    grid3_z_voxel_range(g, z0, z0 + r->block_m[2], &lo[2], &hi[2]);
                }
                float mx = 0.0f, mn = INFINITY;
                for (int k = lo[2]; k <= hi[2]; k++) {
                    for (int j = lo[1]; j <= hi[1]; j++) {
                        for (int i = lo[0]; i <= hi[0]; i++) {
                            size_t v = grid3_index(g, i, j, k);
                            float s = beta[2 * v] + beta[2 * v + 1];
                            mx = s > mx ? s : mx;
                            mn = s < mn ? s : mn;
                        }
                    }
                }
                size_t b = block_index(r, bx, by, bz);
                r->bmax[b] = mx;
                r->bmin[b] = mn;
            }
        }
    }
}

struct reference *reference_create(const struct ext_volume *vol, const struct reference_desc *d)
{
    assert(vol && d);
    const struct grid3 *g = &vol->grid;
    size_t n = grid3_count(g);
    if (n == 0 || !vol->beta) {
        log_error("reference: the volume has no voxels");
        return NULL;
    }
    for (int a = 0; a < 3; a++) {
        if (!(g->spacing[a] > 0.0) || !isfinite(g->spacing[a]) || !isfinite(g->origin[a])) {
            log_error("reference: voxel spacing must be positive and finite");
            return NULL;
        }
    }
    if (!(d->albedo >= 0.0 && d->albedo <= 1.0)) {
        log_error("reference: albedo %g outside [0, 1]", d->albedo);
        return NULL;
    }
    if (!(fabs(dot3(d->sun_dir, d->sun_dir) - 1.0) < 1e-6)) {
        log_error("reference: the sun direction is not a unit vector");
        return NULL;
    }
    for (size_t i = 0; i < 2 * n; i++) {
        if (!(vol->beta[i] >= 0.0f) || !isfinite(vol->beta[i])) {
            log_error("reference: extinction of voxel %zu is %g (must be finite and >= 0)", i / 2,
                      (double)vol->beta[i]);
            return NULL;
        }
    }
    struct reference *r = calloc(1, sizeof(*r));
    if (!r)
        goto error_oom;
    r->d = *d;
    if (r->d.block <= 0)
        r->d.block = 8;
    r->vol = vol;
    size_t nblocks = 1;
    for (int a = 0; a < 3; a++) {
        r->box_min[a] = g->origin[a];
        r->box_max[a] = g->origin[a] + g->n[a] * g->spacing[a];
        r->inv_spacing[a] = 1.0 / g->spacing[a];
        r->stride[a] = a == 0 ? 1 : a == 1 ? (size_t)g->n[0] : (size_t)g->n[0] * g->n[1];
        r->nb[a] = (g->n[a] + r->d.block - 1) / r->d.block;
        r->block_m[a] = r->d.block * g->spacing[a];
        nblocks *= (size_t)r->nb[a];
    }
    r->bmax = malloc(nblocks * sizeof(float));
    r->bmin = malloc(nblocks * sizeof(float));
    if (!r->bmax || !r->bmin)
        goto error_bounds;
    build_bounds(r);
    return r;

error_bounds:
    reference_destroy(r);
error_oom:
    log_error("reference: out of memory");
    return NULL;
}

void reference_destroy(struct reference *ref)
{
    if (!ref)
        return;
    free(ref->bmax);
    free(ref->bmin);
    free(ref);
}

/* ---- extinction lookups and traversal ---------------------------------------------------- */

void reference_beta(const struct reference *r, const double p[3], double out[2])
{
    const struct grid3 *g = &r->vol->grid;
    size_t base = 0, step[3];
    double f[3];
    out[0] = out[1] = 0.0;
    for (int a = 0; a < 3; a++) {
        if (!(p[a] >= r->box_min[a] && p[a] <= r->box_max[a]))
            return;
        /* Continuous voxel coordinate with centres at integers, clamped to the edge centres;
         * the upper neighbour is one stride away (none along an axis of one voxel). */
        double u = (a < 2 || !grid3_stretched(g) ? (p[a] - g->origin[a]) * r->inv_spacing[a]
                                                  : grid3_z_to_voxel(g, p[a])) -
                   0.5;
        double top = g->n[a] - 1;
        u = u < 0.0 ? 0.0 : u > top ? top : u;
        int i = (int)u;
        if (i > g->n[a] - 2)
            i = g->n[a] >= 2 ? g->n[a] - 2 : 0;
        f[a] = u - i;
        step[a] = g->n[a] >= 2 ? r->stride[a] : 0;
        base += (size_t)i * r->stride[a];
    }
    /* Trilinear: along x, then y, then z. */
    const float *b = r->vol->beta + 2 * base;
    double acc[2][2][2];
    for (int k = 0; k < 2; k++) {
        for (int j = 0; j < 2; j++) {
            const float *q = b + 2 * (k * step[2] + j * step[1]);
            const float *q1 = q + 2 * step[0];
            acc[k][j][0] = q[0] + f[0] * ((double)q1[0] - q[0]);
            acc[k][j][1] = q[1] + f[0] * ((double)q1[1] - q[1]);
        }
    }
    for (int c = 0; c < 2; c++) {
        double y0 = acc[0][0][c] + f[1] * (acc[0][1][c] - acc[0][0][c]);
        double y1 = acc[1][0][c] + f[1] * (acc[1][1][c] - acc[1][0][c]);
        double v = y0 + f[2] * (y1 - y0);
        out[c] = v > 0.0 ? v : 0.0;
    }
}

static double beta_total(const struct reference *r, const double o[3], const double d[3], double t)
{
    double p[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]}, b[2];
    reference_beta(r, p, b);
    return b[0] + b[1];
}

/* Clips [*T0, *T1] to the box.  False when nothing is left.  A zero direction component
 * keeps the ray inside or outside that slab for good (no division by zero). */
static bool clip_box(const struct reference *r, const double o[3], const double d[3], double *t0,
                     double *t1)
{
    double lo = *t0, hi = *t1;
    for (int a = 0; a < 3; a++) {
        if (d[a] == 0.0) {
            if (o[a] < r->box_min[a] || o[a] > r->box_max[a])
                return false;
            continue;
        }
        double inv = 1.0 / d[a];
        double ta = (r->box_min[a] - o[a]) * inv, tb = (r->box_max[a] - o[a]) * inv;
        if (ta > tb) {
            double x = ta;
            ta = tb;
            tb = x;
        }
        lo = ta > lo ? ta : lo;
        hi = tb < hi ? tb : hi;
    }
    *t0 = lo;
    *t1 = hi;
    return hi > lo;
}

/* 3D DDA over the bound blocks (Amanatides & Woo), from parameter T on. */
struct dda {
    int idx[3], step[3];
    double t_next[3], t_delta[3];
};

static void dda_init(const struct reference *r, const double o[3], const double d[3], double t,
                     struct dda *s)
{
    for (int a = 0; a < 3; a++) {
        double p = o[a] + t * d[a] - r->box_min[a];
        int k = (int)floor(p / r->block_m[a]);
        k = k < 0 ? 0 : k >= r->nb[a] ? r->nb[a] - 1 : k;
        s->idx[a] = k;
        if (d[a] > 0.0) {
            s->step[a] = 1;
            s->t_next[a] = t + ((k + 1) * r->block_m[a] - p) / d[a];
            s->t_delta[a] = r->block_m[a] / d[a];
        } else if (d[a] < 0.0) {
            s->step[a] = -1;
            s->t_next[a] = t + (k * r->block_m[a] - p) / d[a];
            s->t_delta[a] = -r->block_m[a] / d[a];
        } else {
            s->step[a] = 0;
            s->t_next[a] = INFINITY;
            s->t_delta[a] = INFINITY;
        }
    }
}

/* The block the DDA is in, where the ray leaves it (at most T1) and through which axis. */
static void dda_segment(const struct reference *r, const struct dda *s, double t1, size_t *b,
                        double *end, int *axis)
{
    int a = 0;
    if (s->t_next[1] < s->t_next[a])
        a = 1;
    if (s->t_next[2] < s->t_next[a])
        a = 2;
    *axis = a;
    *end = s->t_next[a] < t1 ? s->t_next[a] : t1;
    *b = block_index(r, s->idx[0], s->idx[1], s->idx[2]);
}

static bool dda_advance(const struct reference *r, struct dda *s, int a)
{
    s->idx[a] += s->step[a];
    if (s->idx[a] < 0 || s->idx[a] >= r->nb[a])
        return false;
    s->t_next[a] += s->t_delta[a];
    return true;
}

/* Delta tracking over [t0, t1] already clipped to the box. */
static bool track(const struct reference *r, const double o[3], const double d[3], double t0,
                  double t1, struct reference_rng *rng, double *t_hit)
{
    struct dda s;
    dda_init(r, o, d, t0, &s);
    double t = t0;
    for (;;) {
        size_t b;
        double end;
        int axis;
        dda_segment(r, &s, t1, &b, &end, &axis);
        double mu = r->bmax[b];
        if (mu > 0.0 && end > t) {
            /* Elek Algorithm 1 with the block's majorant; leaving the block restarts the
             * exponential at its face (memoryless), so each block uses its own bound. */
            double tt = t;
            for (;;) {
                tt += exp_sample(rng) / mu; /* Elek eq. 2.8 */
                if (tt >= end)
                    break;
                if (reference_rng_uniform(rng) * mu < beta_total(r, o, d, tt)) {
                    *t_hit = tt;
                    return true;
                }
            }
        }
        t = end > t ? end : t;
        if (t >= t1 || !dda_advance(r, &s, axis))
            return false;
    }
}

bool reference_free_flight(const struct reference *ref, const double origin[3], const double dir[3],
                           double t0, double t1, struct reference_rng *rng, double *t_hit)
{
    if (!clip_box(ref, origin, dir, &t0, &t1))
        return false;
    return track(ref, origin, dir, t0, t1, rng, t_hit);
}

/* Residual ratio tracking over [t0, t1] already clipped: per block the lower bound is a
 * control extinction taken analytically (Elek eq. 2.6-2.7 on the constant part) and the
 * residual, bounded by max - min, is ratio-tracked.  A homogeneous block costs no samples. */
static double transmit(const struct reference *r, const double o[3], const double d[3], double t0,
                       double t1, struct reference_rng *rng)
{
    struct dda s;
    dda_init(r, o, d, t0, &s);
    double t = t0, tr = 1.0;
    for (;;) {
        size_t b;
        double end;
        int axis;
        dda_segment(r, &s, t1, &b, &end, &axis);
        if (end > t) {
            double lo = r->bmin[b], range = r->bmax[b] - lo;
            tr *= exp(-lo * (end - t));
            if (range > 0.0) {
                double tt = t;
                for (;;) {
                    tt += exp_sample(rng) / range;
                    if (tt >= end)
                        break;
                    double f = 1.0 - (beta_total(r, o, d, tt) - lo) / range;
                    tr *= f < 0.0 ? 0.0 : f > 1.0 ? 1.0 : f;
                    /* Roulette only where more samples would be spent: the analytic part
                     * of a homogeneous stretch stays exact. */
                    if (tr < TR_ROULETTE) {
                        double q = tr / TR_ROULETTE;
                        if (reference_rng_uniform(rng) >= q)
                            return 0.0;
                        tr = TR_ROULETTE;
                    }
                }
            }
            if (tr == 0.0)
                return 0.0;
        }
        t = end > t ? end : t;
        if (t >= t1 || !dda_advance(r, &s, axis))
            return tr;
    }
}

double reference_transmittance(const struct reference *ref, const double origin[3],
                               const double dir[3], double t0, double t1, struct reference_rng *rng)
{
    if (!clip_box(ref, origin, dir, &t0, &t1))
        return 1.0;
    return transmit(ref, origin, dir, t0, t1, rng);
}

/* Transmittance from P to the sun: the volume, and the ground when the sun is below it. */
static double sun_transmittance(const struct reference *r, const double p[3],
                                struct reference_rng *rng)
{
    const double *s = r->d.sun_dir;
    if (r->d.ground_on && s[2] < 0.0 && p[2] >= 0.0)
        return 0.0;
    double t0 = 0.0, t1 = INFINITY;
    if (!clip_box(r, p, s, &t0, &t1))
        return 1.0;
    return transmit(r, p, s, t0, t1, rng);
}

/* ---- path tracing ------------------------------------------------------------------------ */

static bool sun_on(const struct reference *r)
{
    const double *e = r->d.sun_irradiance;
    return e[0] > 0.0 || e[1] > 0.0 || e[2] > 0.0;
}

void reference_radiance(const struct reference *r, const double origin[3], const double dir[3],
                        struct reference_rng *rng, double out[3], bool *uncollided)
{
    double o[3] = {origin[0], origin[1], origin[2]};
    double d[3] = {dir[0], dir[1], dir[2]};
    double thr[3] = {1.0, 1.0, 1.0};
    const double *E = r->d.sun_irradiance;
    bool sun = sun_on(r);
    out[0] = out[1] = out[2] = 0.0;
    if (uncollided)
        *uncollided = false;
    for (long bounce = 0;; bounce++) {
        /* The ray ends at the ground (opaque plane z = 0 seen from above) or goes on. */
        double t_ground = INFINITY;
        if (r->d.ground_on && d[2] < 0.0 && o[2] > 0.0)
            t_ground = -o[2] / d[2];
        double t0 = 0.0, t1 = t_ground, t_hit = 0.0;
        bool hit = clip_box(r, o, d, &t0, &t1) && track(r, o, d, t0, t1, rng, &t_hit);
        if (bounce == 0 && uncollided)
            *uncollided = !hit;
        if (r->d.max_bounces > 0 && bounce >= r->d.max_bounces)
            return;

        if (hit) {
            double p[3] = {o[0] + t_hit * d[0], o[1] + t_hit * d[1], o[2] + t_hit * d[2]};
            double b[2];
            reference_beta(r, p, b);
            double sum = b[0] + b[1]; /* > 0: a real collision needs u mu < sum */
            for (int c = 0; c < 3; c++)
                thr[c] *= r->d.albedo; /* Elek eq. 2.1 */
            if (sun) {
                /* In-scattered sunlight (Elek eq. 2.12 with L = E T_sun in the sun's
                 * direction); the phase of the voxel is the beta-weighted mix (Nes eq. 5.12).
                 * Light travels along -sun_dir and leaves along -d: cos = sun_dir . d. */
                double mu = dot3(r->d.sun_dir, d);
                double ph = (b[0] * eval_phase(r, r->d.g_ice, mu) +
                             b[1] * eval_phase(r, r->d.g_water, mu)) /
                            sum;
                double ts = ph > 0.0 ? sun_transmittance(r, p, rng) : 0.0;
                for (int c = 0; c < 3; c++)
                    out[c] += thr[c] * ph * E[c] * ts;
            }
            /* Sampling a component with probability beta_f / beta and then its phase samples
             * the mix, so the throughput does not change. */
            double g = reference_rng_uniform(rng) * sum < b[0] ? r->d.g_ice : r->d.g_water;
            double mu = sample_phase(r, g, rng);
            turn(d, mu, 2.0 * PI * reference_rng_uniform(rng));
            memcpy(o, p, sizeof(o));
        } else if (t_ground < INFINITY) {
            /* Lambertian ground: BRDF albedo / pi; sun E cos(theta_s), then a cosine-weighted
             * bounce carries the albedo as its weight. */
            double p[3] = {o[0] + t_ground * d[0], o[1] + t_ground * d[1], 0.0};
            for (int c = 0; c < 3; c++)
                thr[c] *= r->d.ground_albedo[c];
            if (sun && r->d.sun_dir[2] > 0.0) {
                double ts = sun_transmittance(r, p, rng) * r->d.sun_dir[2] / PI;
                for (int c = 0; c < 3; c++)
                    out[c] += thr[c] * E[c] * ts;
            }
            double u = reference_rng_uniform(rng), phi = 2.0 * PI * reference_rng_uniform(rng);
            double s = sqrt(u);
            d[0] = s * cos(phi);
            d[1] = s * sin(phi);
            d[2] = sqrt(fmax(0.0, 1.0 - u));
            memcpy(o, p, sizeof(o));
        } else {
            for (int c = 0; c < 3; c++)
                out[c] += thr[c] * r->d.sky[c];
            return;
        }

        double m = fmax(thr[0], fmax(thr[1], thr[2]));
        if (!(m > 0.0))
            return;
        if (m < PATH_ROULETTE) {
            double q = m / PATH_ROULETTE;
            if (reference_rng_uniform(rng) >= q)
                return;
            for (int c = 0; c < 3; c++)
                thr[c] /= q;
        }
    }
}
