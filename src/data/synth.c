/*
 * The procedural storm and the test scenes.  The storm is a sum of a few shapes (a tilted
 * cumulus tower with a domed top, a wind-sheared anvil lens, a rain shaft, satellite cumuli)
 * whose edges are displaced by seeded 3D gradient noise; every species is the product of a
 * shape's density and a vertical profile in kg/kg.  Shapes are given in physical heights and in
 * horizontal lengths scaled by min(extent_x, extent_y) / 60 km.
 */
#include "data/synth.h"

#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "common/log.h"
#include "common/parallel.h"

#define KM 1000.0
#define PI 3.14159265358979323846

/* Horizontal lengths below are for a 60 km wide box and scale with it. */
#define REFERENCE_WIDTH (60.0 * KM)

#define CLOUD_BASE (1.5 * KM)
#define SATELLITES_MAX 10
#define THREADS_MAX 64

/* ---- hashing and noise ---------------------------------------------------------------- */

static inline uint32_t scramble(uint32_t h)
{
    h ^= h >> 15;
    h *= 0x2c1b3c6dU;
    h ^= h >> 12;
    h *= 0x297a2d39U;
    h ^= h >> 15;
    return h;
}

/* Per-axis lattice multipliers (odd, unrelated). */
#define LATTICE_X 0x9e3779b1U
#define LATTICE_Y 0x6b43a9b5U
#define LATTICE_Z 0x3c6ef372U

static inline double fade(double t)
{
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

/* Dot product of the pseudo-random gradient at a lattice corner (chosen by H) with the
 * offset (dx, dy, dz) from that corner.  Gradient components are uniform in [-1, 1]. */
static inline double corner(uint32_t h, double dx, double dy, double dz)
{
    h = scramble(h);
    const double s = 2.0 / 1023.0;
    double gx = (double)(h & 1023U) * s - 1.0;
    double gy = (double)((h >> 10) & 1023U) * s - 1.0;
    double gz = (double)((h >> 20) & 1023U) * s - 1.0;
    return gx * dx + gy * dy + gz * dz;
}

static inline double lerp(double a, double b, double t)
{
    return a + (b - a) * t;
}

/* Gradient noise on the unit lattice: 0 at lattice points, smooth (C2) in between, roughly
 * in [-1, 1] with a standard deviation of about NOISE_SIGMA. */
static double gradient_noise(double x, double y, double z, uint32_t seed)
{
    double fx = floor(x), fy = floor(y), fz = floor(z);
    double tx = x - fx, ty = y - fy, tz = z - fz;
    uint32_t hx = (uint32_t)(int32_t)fx * LATTICE_X + seed;
    uint32_t hy = (uint32_t)(int32_t)fy * LATTICE_Y;
    uint32_t hz = (uint32_t)(int32_t)fz * LATTICE_Z;
    uint32_t h00 = hy + hz, h10 = h00 + LATTICE_Y, h01 = h00 + LATTICE_Z,
             h11 = h10 + LATTICE_Z;
    uint32_t x1 = hx + LATTICE_X;

    double c000 = corner(hx + h00, tx, ty, tz);
    double c100 = corner(x1 + h00, tx - 1.0, ty, tz);
    double c010 = corner(hx + h10, tx, ty - 1.0, tz);
    double c110 = corner(x1 + h10, tx - 1.0, ty - 1.0, tz);
    double c001 = corner(hx + h01, tx, ty, tz - 1.0);
    double c101 = corner(x1 + h01, tx - 1.0, ty, tz - 1.0);
    double c011 = corner(hx + h11, tx, ty - 1.0, tz - 1.0);
    double c111 = corner(x1 + h11, tx - 1.0, ty - 1.0, tz - 1.0);

    double u = fade(tx), v = fade(ty), w = fade(tz);
    double a = lerp(lerp(c000, c100, u), lerp(c010, c110, u), v);
    double b = lerp(lerp(c001, c101, u), lerp(c011, c111, u), v);
    return lerp(a, b, w);
}

/* Measured over many samples: standard deviation of gradient_noise, mean of |noise|, and the
 * standard deviation of the amplitude-weighted mean of |noise| over 3-6 octaves. */
#define NOISE_SIGMA 0.192
#define NOISE_MEAN_ABS 0.154
#define BILLOW_SIGMA 0.07

/* The normalised sums are clamped to these bounds (reached only in the far tails), so that
 * the reach of a displaced edge is known exactly and empty voxels can be skipped. */
#define SMOOTH_MAX 4.0
#define BILLOW_MIN -2.5
#define BILLOW_MAX 5.0

struct fbm {
    double smooth; /* signed sum of octaves: zero mean, unit standard deviation */
    double billow; /* sum of |octaves|, zero mean, unit standard deviation: rounded bulges
                      with sharp creases between them (cauliflower) */
};

/* Several octaves of gradient noise; one pass gives both the smooth and the billowy sum, so
 * the species that share a shape share one noise evaluation. */
static struct fbm fbm(double x, double y, double z, int octaves, uint32_t seed)
{
    double amp = 1.0, norm = 0.0, s = 0.0, b = 0.0, var = 0.0;
    for (int o = 0; o < octaves; o++) {
        double n = gradient_noise(x, y, z, seed + 0x51ed27U * (uint32_t)o);
        s += amp * n;
        b += amp * fabs(n);
        norm += amp;
        var += amp * amp;
        /* a lacunarity slightly off 2 keeps the octaves' lattices from lining up */
        x = x * 2.03 + 7.31;
        y = y * 2.03 - 3.17;
        z = z * 2.03 + 1.93;
        amp *= 0.5;
    }
    struct fbm r;
    r.smooth = fmax(-SMOOTH_MAX, fmin(SMOOTH_MAX, s / (sqrt(var) * NOISE_SIGMA)));
    r.billow = fmax(BILLOW_MIN, fmin(BILLOW_MAX, (b / norm - NOISE_MEAN_ABS) / BILLOW_SIGMA));
    return r;
}

/* ---- small helpers -------------------------------------------------------------------- */

static inline double clamp01(double x)
{
    return x < 0.0 ? 0.0 : x > 1.0 ? 1.0 : x;
}

/* 0 below E0, 1 above E1, smooth in between (E1 < E0 gives the mirrored step). */
static inline double smooth_step(double e0, double e1, double x)
{
    double t = clamp01((x - e0) / (e1 - e0));
    return t * t * (3.0 - 2.0 * t);
}

/* Uniform in [0, 1) from a counter-based generator: deterministic per (seed, index). */
static double random01(uint32_t seed, uint32_t index)
{
    uint32_t h = scramble(scramble(seed ^ 0xa5a5f00dU) + index * 0x9e3779b1U);
    return (double)(h >> 8) * (1.0 / 16777216.0);
}

/* ---- the storm as shapes -------------------------------------------------------------- */

struct satellite {
    double x, y;   /* centre at t (m) */
    double radius; /* m */
    double top;    /* m */
    double q;      /* peak cloud water, kg/kg */
};

struct storm {
    struct grid3 grid;
    double t;
    double scale_h;    /* horizontal scale: min(extent_x, extent_y) / 60 km */
    double centre[2];  /* storm centre at cloud base at time t */
    double shear[2];   /* unit vector downshear (the anvil streams this way) */

    /* noise: coordinates are (x - centre) / feature_h, (z - rise) / feature_v */
    double feature_h, feature_v, rise;
    uint32_t seed_tower, seed_anvil, seed_rain;
    int oct_tower, oct_anvil, oct_rain;

    /* tower */
    double tower_r;    /* radius at mid height, m */
    double tower_top;  /* m */
    double dome_h;     /* height of the rounded top, m */
    double tilt;       /* downshear displacement of the axis at 12 km, m */

    /* anvil: an elliptical lens centred downshear of the tower */
    double anvil_c[2];
    double anvil_r;    /* radius, m (stretched along the shear) */
    double anvil_bot, anvil_top; /* at its centre, m */

    /* rain shaft */
    double rain_c[2], rain_r, rain_q;
    double graupel_q;

    int n_sat;
    struct satellite sat[SATELLITES_MAX];
};

/* Displacement of the shape edges per standard deviation of noise, in units of the shape's
 * radius. */
#define TOWER_BILLOW 0.10
#define TOWER_SMOOTH 0.06
#define ANVIL_WOBBLE 0.12
#define ANVIL_MAMMATUS 0.15
#define RAIN_WOBBLE 0.15
#define ANVIL_TOP_WOBBLE 0.12

/* Farthest an anvil surface can move, in units of its half thickness. */
#define ANVIL_REACH_V \
    (1.0 + fmax(ANVIL_MAMMATUS * BILLOW_MAX, ANVIL_TOP_WOBBLE * SMOOTH_MAX))

/* Farthest a cumulus edge can move outwards (its nominal edge is at distance 1). */
#define CUMULUS_REACH (1.0 + TOWER_BILLOW * BILLOW_MAX + TOWER_SMOOTH * SMOOTH_MAX)

static void grid_from_desc(const struct synth_desc *d, struct grid3 *g)
{
    memset(g, 0, sizeof(*g)); /* uniform z */
    for (int a = 0; a < 3; a++) {
        g->n[a] = d->n[a];
        g->spacing[a] = d->extent_m[a] / d->n[a];
        g->origin[a] = 0.0;
    }
}

static int octaves_for(double feature_h, double feature_v, const struct grid3 *g)
{
    /* finest octave no finer than about 1.5 voxels on the coarsest axis */
    double dh = fmax(g->spacing[0], g->spacing[1]);
    double ratio = fmin(feature_h / (1.5 * dh), feature_v / (1.5 * g->spacing[2]));
    int oct = ratio > 1.0 ? 1 + (int)floor(log2(ratio)) : 1;
    return oct < 3 ? 3 : oct > 6 ? 6 : oct;
}

static void storm_setup(const struct synth_desc *d, struct storm *s)
{
    memset(s, 0, sizeof(*s));
    grid_from_desc(d, &s->grid);
    double t = d->time;
    double sh = fmin(d->extent_m[0], d->extent_m[1]) / REFERENCE_WIDTH;
    s->t = t;
    s->scale_h = sh;
    uint32_t seed = scramble(d->seed * 0x8f1bbcdcU + 0x12345U);
    s->seed_tower = scramble(seed + 1U);
    s->seed_anvil = scramble(seed + 2U);
    s->seed_rain = scramble(seed + 3U);

    /* The storm moves with the mean wind; the anvil streams downshear, within 40 degrees of
     * the motion. */
    double motion = 2.0 * PI * random01(seed, 0);
    double veer = (random01(seed, 1) - 0.5) * (80.0 * PI / 180.0);
    double mdir[2] = {cos(motion), sin(motion)};
    s->shear[0] = cos(motion + veer);
    s->shear[1] = sin(motion + veer);

    /* Over t in [0, 1] the centre drifts 6 km (scaled); the middle of the track sits upshear
     * of the box centre so that the grown anvil fits. */
    double drift = 6.0 * KM * sh;
    double anvil_r_max = 22.0 * KM * sh;
    double mid[2];
    for (int a = 0; a < 2; a++) {
        mid[a] = 0.5 * d->extent_m[a] - 0.12 * anvil_r_max * s->shear[a];
        s->centre[a] = mid[a] + (t - 0.5) * drift * mdir[a];
    }

    s->feature_h = 2.4 * KM * sh;
    s->feature_v = 2.4 * KM;
    s->rise = 2.5 * KM * t; /* billows climb through the tower as it grows */
    s->oct_tower = octaves_for(s->feature_h, s->feature_v, &s->grid);
    s->oct_anvil = octaves_for(2.5 * s->feature_h, 0.5 * s->feature_v, &s->grid);
    s->oct_rain = octaves_for(0.6 * s->feature_h, 3.0 * s->feature_v, &s->grid);
    if (s->oct_rain > 4)
        s->oct_rain = 4;

    s->tower_r = (3.6 + 1.0 * t) * KM * sh;
    s->tower_top = 9.5 * KM + 3.0 * KM * t;
    s->dome_h = 2.0 * KM;
    s->tilt = 1.5 * KM * sh;

    s->anvil_r = (6.0 + 16.0 * t) * KM * sh;
    s->anvil_bot = 8.6 * KM + 0.6 * KM * t;
    s->anvil_top = s->tower_top - 0.3 * KM;
    for (int a = 0; a < 2; a++)
        s->anvil_c[a] = s->centre[a] + 0.3 * s->anvil_r * s->shear[a];

    s->rain_r = 0.7 * s->tower_r;
    for (int a = 0; a < 2; a++)
        s->rain_c[a] = s->centre[a] + 0.4 * KM * sh * s->shear[a];
    s->rain_q = 2.6e-3 * (0.5 + 0.5 * t);
    s->graupel_q = 1.8e-3 * (0.6 + 0.4 * t);

    /* Fair-weather cumuli scattered around, away from the storm's track (the same ones at
     * every time); each grows and decays on its own phase and drifts with the storm. */
    int tries = 0;
    for (uint32_t i = 0; s->n_sat < 8 && tries < 64; tries++, i += 8) {
        double px = (0.06 + 0.88 * random01(seed, 100 + i)) * d->extent_m[0];
        double py = (0.06 + 0.88 * random01(seed, 101 + i)) * d->extent_m[1];
        double dx = px - mid[0], dy = py - mid[1];
        if (hypot(dx, dy) < 14.0 * KM * sh)
            continue;
        struct satellite *c = &s->sat[s->n_sat++];
        double phase = random01(seed, 102 + i);
        double life = sin(PI * clamp01(0.25 + 0.6 * t + 0.5 * (phase - 0.5)));
        c->x = px + (t - 0.5) * drift * mdir[0];
        c->y = py + (t - 0.5) * drift * mdir[1];
        c->radius = (1.0 + 1.3 * random01(seed, 103 + i)) * KM * sh;
        c->top = CLOUD_BASE + (0.8 + 2.4 * random01(seed, 104 + i)) * KM * (0.5 + 0.5 * life);
        c->q = (0.5e-3 + 0.5e-3 * random01(seed, 105 + i)) * (0.6 + 0.4 * life);
    }
}

/* Everything about one z level that does not depend on x and y. */
struct level {
    double z;
    bool tower;        /* the level is within reach of the tower */
    double axis[2];    /* tower axis */
    double inv_r;      /* 1 / tower radius at this height */
    double dome2;      /* squared vertical term of the domed top */
    double qc, qi, qs, qg_prof; /* species at full tower density, kg/kg */
    bool anvil;
    bool rain;
    double rain_q;     /* rain at full shaft density, kg/kg */
    bool sat_any;
    bool sat_on[SATELLITES_MAX];
    double sat_dome2[SATELLITES_MAX];
    double sat_q[SATELLITES_MAX];
};

static void level_setup(const struct storm *s, int k, struct level *L)
{
    memset(L, 0, sizeof(*L));
    double z = (k + 0.5) * s->grid.spacing[2];
    L->z = z;
    double reach_h = (CUMULUS_REACH - 1.0) * s->dome_h;
    double top = s->tower_top;

    L->tower = z > CLOUD_BASE - 200.0 && z < top + reach_h;
    if (L->tower) {
        double lean = s->tilt * clamp01((z - CLOUD_BASE) / (12.0 * KM - CLOUD_BASE));
        for (int a = 0; a < 2; a++)
            L->axis[a] = s->centre[a] + lean * s->shear[a];
        /* a tower slightly wider aloft */
        double r = s->tower_r * (0.8 + 0.35 * smooth_step(CLOUD_BASE, top, z));
        L->inv_r = 1.0 / r;
        double dz = fmax(0.0, z - (top - s->dome_h)) / s->dome_h;
        L->dome2 = dz * dz;
        /* cloud water grows adiabatically above the base, peaks mid-levels, and gives way to
         * ice where the tower glaciates */
        double up = 0.35 + 0.65 * smooth_step(CLOUD_BASE, 5.0 * KM, z);
        double glaciate = 1.0 - 0.85 * smooth_step(6.0 * KM, top, z);
        L->qc = 2.0e-3 * up * glaciate;
        L->qi = 0.4e-3 * smooth_step(7.2 * KM, 10.0 * KM, z);
        L->qs = 0.5e-3 * smooth_step(5.5 * KM, 8.5 * KM, z);
        double gz = (z - 6.5 * KM) / (1.4 * KM);
        L->qg_prof = s->graupel_q * exp(-gz * gz) * smooth_step(4.0 * KM, 4.8 * KM, z) *
                     (1.0 - smooth_step(8.2 * KM, 9.0 * KM, z));
    }

    double half = 0.5 * (s->anvil_top - s->anvil_bot);
    double mid = 0.5 * (s->anvil_top + s->anvil_bot);
    L->anvil = fabs(z - mid) < half * ANVIL_REACH_V;

    double rain_top = CLOUD_BASE + 1.5 * KM;
    L->rain = z < rain_top;
    if (L->rain) {
        double fall = 1.0 - smooth_step(CLOUD_BASE, rain_top, z);
        double evaporate = 0.85 + 0.15 * smooth_step(0.0, CLOUD_BASE, z);
        L->rain_q = s->rain_q * fall * evaporate;
    }

    for (int i = 0; i < s->n_sat; i++) {
        const struct satellite *c = &s->sat[i];
        double dome_base = CLOUD_BASE + 0.35 * (c->top - CLOUD_BASE);
        double dome_h = c->top - dome_base;
        if (z < CLOUD_BASE - 200.0 || z > c->top + (CUMULUS_REACH - 1.0) * dome_h)
            continue;
        double dz = fmax(0.0, z - dome_base) / dome_h;
        L->sat_on[i] = true;
        L->sat_any = true;
        L->sat_dome2[i] = dz * dz;
        L->sat_q[i] = c->q * (0.4 + 0.6 * smooth_step(CLOUD_BASE, c->top, z));
    }
}

/* Density of a cumuliform shape in [0, 1] from its normalised distance D (1 = nominal edge)
 * and the noise at the point: billows push the edge out and in. */
static inline double cumulus_density(double d, const struct fbm *n)
{
    double s = 1.0 - d + TOWER_BILLOW * n->billow + TOWER_SMOOTH * n->smooth;
    return smooth_step(0.0, 0.18, s);
}

static void storm_voxel(const struct storm *s, const struct level *L, double x, double y,
                        float *q)
{
    const double reach = CUMULUS_REACH;
    double qc = 0.0, qr = 0.0, qi = 0.0, qs = 0.0, qg = 0.0;
    double z = L->z;

    /* tower and satellites share one noise evaluation */
    double d_tower = INFINITY;
    if (L->tower) {
        double r = hypot(x - L->axis[0], y - L->axis[1]) * L->inv_r;
        d_tower = sqrt(r * r + L->dome2);
    }
    bool near_cumulus = d_tower < reach;
    for (int i = 0; i < s->n_sat && !near_cumulus; i++) {
        if (!L->sat_on[i])
            continue;
        double r = hypot(x - s->sat[i].x, y - s->sat[i].y) / s->sat[i].radius;
        near_cumulus = r * r + L->sat_dome2[i] < reach * reach;
    }
    if (near_cumulus) {
        struct fbm n = fbm((x - s->centre[0]) / s->feature_h, (y - s->centre[1]) / s->feature_h,
                           (z - s->rise) / s->feature_v, s->oct_tower, s->seed_tower);
        /* flat cloud base, gently rippled */
        double base = CLOUD_BASE + 60.0 * n.smooth;
        double base_f = smooth_step(base, base + 250.0, z);
        double inner = 0.8 + 0.2 * fmax(-2.5, fmin(1.0, n.smooth));
        if (d_tower < reach && base_f > 0.0) {
            double dens = cumulus_density(d_tower, &n) * base_f * inner;
            qc = L->qc * dens;
            qi = L->qi * dens;
            qs = L->qs * dens;
            /* graupel in the updraught core */
            qg = L->qg_prof * dens * (1.0 - smooth_step(0.3, 0.75, d_tower));
        }
        for (int i = 0; i < s->n_sat && base_f > 0.0; i++) {
            if (!L->sat_on[i])
                continue;
            double r = hypot(x - s->sat[i].x, y - s->sat[i].y) / s->sat[i].radius;
            double d = sqrt(r * r + L->sat_dome2[i]);
            if (d >= reach)
                continue;
            double c = L->sat_q[i] * cumulus_density(d, &n) * base_f * inner;
            qc = fmax(qc, c);
        }
    }

    /* the anvil: a lens, thick near the tower and thinning downshear, ice above snow */
    if (L->anvil) {
        double ox = x - s->anvil_c[0], oy = y - s->anvil_c[1];
        double along = (ox * s->shear[0] + oy * s->shear[1]) / (1.15 * s->anvil_r);
        double across = (oy * s->shear[0] - ox * s->shear[1]) / (0.85 * s->anvil_r);
        double da = sqrt(along * along + across * across);
        if (da < 1.0 + SMOOTH_MAX * ANVIL_WOBBLE) {
            double mid = 0.5 * (s->anvil_top + s->anvil_bot);
            double half0 = 0.5 * (s->anvil_top - s->anvil_bot);
            double half = half0 * fmax(0.25, 1.0 - 0.65 * da * da);
            double w = (z - mid) / half;
            if (fabs(w) < ANVIL_REACH_V) {
                /* fibrous: features stretched along the shear, flat in z */
                double fx = (ox * s->shear[0] + oy * s->shear[1]) / (2.5 * s->feature_h);
                double fy = (oy * s->shear[0] - ox * s->shear[1]) / (1.2 * s->feature_h);
                struct fbm n = fbm(fx, fy, z / (0.5 * s->feature_v), s->oct_anvil,
                                   s->seed_anvil);
                double horiz = smooth_step(0.0, 0.3, 1.0 - da + ANVIL_WOBBLE * n.smooth);
                /* mammatus-like bulges hang from the base */
                double bump = w < 0.0 ? ANVIL_MAMMATUS * n.billow : ANVIL_TOP_WOBBLE * n.smooth;
                double vert = smooth_step(0.0, 0.35, 1.0 - fabs(w) + bump);
                double dens = horiz * vert * (0.75 + 0.25 * fmax(-3.0, fmin(1.0, n.smooth))) *
                              (1.0 - 0.45 * clamp01(da));
                double ai = 0.45e-3 * dens * smooth_step(-0.8, 0.3, w);
                double as = 0.9e-3 * dens * (1.0 - smooth_step(-0.1, 0.8, w));
                qi = fmax(qi, ai);
                qs = fmax(qs, as);
            }
        }
    }

    /* the rain shaft under the core: vertical streaks */
    if (L->rain && L->rain_q > 0.0) {
        double rr = hypot(x - s->rain_c[0], y - s->rain_c[1]) / s->rain_r;
        if (rr < 1.0 + SMOOTH_MAX * RAIN_WOBBLE) {
            struct fbm n = fbm((x - s->centre[0]) / (0.6 * s->feature_h),
                               (y - s->centre[1]) / (0.6 * s->feature_h),
                               z / (3.0 * s->feature_v), s->oct_rain, s->seed_rain);
            double dens = smooth_step(0.0, 0.55, 1.0 - rr + RAIN_WOBBLE * n.smooth);
            qr = L->rain_q * dens * (0.78 + 0.22 * fmax(-3.0, fmin(1.0, n.smooth)));
        }
    }

    q[SPECIES_CLOUD] = (float)qc;
    q[SPECIES_RAIN] = (float)qr;
    q[SPECIES_ICE] = (float)qi;
    q[SPECIES_SNOW] = (float)qs;
    q[SPECIES_GRAUPEL] = (float)qg;
}

struct storm_job {
    const struct storm *storm;
    struct field_volume *out;
    int first, stride; /* z slices first, first + stride, ... */
};

static void storm_slices(const struct storm_job *job)
{
    const struct storm *s = job->storm;
    const struct grid3 *g = &s->grid;
    struct level L;
    for (int k = job->first; k < g->n[2]; k += job->stride) {
        level_setup(s, k, &L);
        if (!L.tower && !L.anvil && !L.rain && !L.sat_any)
            continue; /* the arrays are zero already */
        for (int j = 0; j < g->n[1]; j++) {
            double y = (j + 0.5) * g->spacing[1];
            size_t idx = grid3_index(g, 0, j, k);
            for (int i = 0; i < g->n[0]; i++, idx++) {
                double x = (i + 0.5) * g->spacing[0];
                float q[SPECIES_COUNT];
                storm_voxel(s, &L, x, y, q);
                for (int f = 0; f < SPECIES_COUNT; f++)
                    job->out->q[f][idx] = q[f];
            }
        }
    }
}

static void *storm_thread(void *arg)
{
    parallel_name_thread("anvil-synth");
    storm_slices(arg);
    return NULL;
}

/* ---- descriptions --------------------------------------------------------------------- */

void synth_desc_defaults(struct synth_desc *d)
{
    memset(d, 0, sizeof(*d));
    d->kind = SYNTH_STORM;
    d->n[0] = 128;
    d->n[1] = 128;
    d->n[2] = 64;
    d->extent_m[0] = 60.0 * KM;
    d->extent_m[1] = 60.0 * KM;
    d->extent_m[2] = 16.0 * KM;
    d->tau = 10.0;
    d->ice_phase = false;
    d->seed = 1;
    d->time = 0.5;
}

static const char *kind_name(enum synth_kind k)
{
    switch (k) {
    case SYNTH_STORM: return "storm";
    case SYNTH_SLAB: return "slab";
    case SYNTH_SPHERE: return "sphere";
    case SYNTH_EMPTY: return "empty";
    case SYNTH_VOXEL: return "voxel";
    }
    return "?";
}

static bool check_desc(const struct synth_desc *d)
{
    if ((unsigned)d->kind > (unsigned)SYNTH_VOXEL) {
        log_error("synthetic scene: unknown kind %d", (int)d->kind);
        return false;
    }
    const char *name = kind_name(d->kind);
    if (d->n[0] < 1 || d->n[0] > SYNTH_MAX_NXY || d->n[1] < 1 || d->n[1] > SYNTH_MAX_NXY ||
        d->n[2] < 1 || d->n[2] > SYNTH_MAX_NZ) {
        log_error("synthetic %s: size %dx%dx%d voxels; expected 1..%d x 1..%d x 1..%d", name,
                  d->n[0], d->n[1], d->n[2], SYNTH_MAX_NXY, SYNTH_MAX_NXY, SYNTH_MAX_NZ);
        return false;
    }
    for (int a = 0; a < 3; a++) {
        if (!isfinite(d->extent_m[a]) || d->extent_m[a] <= 0.0) {
            log_error("synthetic %s: extent %g x %g x %g m; expected positive finite lengths",
                      name, d->extent_m[0], d->extent_m[1], d->extent_m[2]);
            return false;
        }
    }
    if (d->kind == SYNTH_STORM && !(d->time >= 0.0 && d->time <= 1.0)) {
        log_error("synthetic storm: time %g; expected a value in [0, 1]", d->time);
        return false;
    }
    if (d->kind != SYNTH_STORM && d->kind != SYNTH_EMPTY &&
        !(isfinite(d->tau) && d->tau >= 0.0)) {
        log_error("synthetic %s: optical depth %g; expected a finite value >= 0", name, d->tau);
        return false;
    }
    return true;
}

/* ---- the storm ------------------------------------------------------------------------ */

static int online_cpus(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : n > THREADS_MAX ? THREADS_MAX : (int)n;
}

bool synth_storm_fields_threads(const struct synth_desc *d, int threads,
                                struct field_volume *out)
{
    memset(out, 0, sizeof(*out));
    if (!check_desc(d))
        return false;
    if (d->kind != SYNTH_STORM) {
        log_error("synthetic %s: not a storm; mass ratios exist only for the storm",
                  kind_name(d->kind));
        return false;
    }
    grid_from_desc(d, &out->grid);
    size_t count = grid3_count(&out->grid);
    for (int f = 0; f < SPECIES_COUNT; f++) {
        out->q[f] = calloc(count, sizeof(float));
        if (!out->q[f]) {
            log_error("out of memory for a %dx%dx%d synthetic storm (%zu MiB)", d->n[0],
                      d->n[1], d->n[2], (count * SPECIES_COUNT * sizeof(float)) >> 20);
            field_volume_finish(out);
            return false;
        }
    }

    struct storm s;
    storm_setup(d, &s);

    if (threads <= 0)
        threads = online_cpus();
    if (threads > d->n[2])
        threads = d->n[2];
    if (threads > THREADS_MAX)
        threads = THREADS_MAX;
    if (count < 65536)
        threads = 1;

    struct storm_job jobs[THREADS_MAX];
    pthread_t tid[THREADS_MAX];
    bool started[THREADS_MAX] = {false};
    for (int i = 0; i < threads; i++) {
        jobs[i] = (struct storm_job){.storm = &s, .out = out, .first = i, .stride = threads};
    }
    /* Thread 0's share runs here; a thread that fails to start has its share run here too. */
    for (int i = 1; i < threads; i++)
        started[i] = pthread_create(&tid[i], NULL, storm_thread, &jobs[i]) == 0;
    storm_slices(&jobs[0]);
    for (int i = 1; i < threads; i++) {
        if (started[i])
            pthread_join(tid[i], NULL);
        else
            storm_slices(&jobs[i]);
    }
    return true;
}

bool synth_storm_fields(const struct synth_desc *d, struct field_volume *out)
{
    return synth_storm_fields_threads(d, 0, out);
}

/* ---- test scenes as extinction -------------------------------------------------------- */

/* Fraction of the voxel centred at C with sides H that lies inside the ball (centre O,
 * radius R): exact 0 or 1 when the voxel is clear of the surface, else 4x4x4 samples. */
static double ball_fraction(const double c[3], const double h[3], const double o[3], double r)
{
    double d2 = 0.0, half_diag2 = 0.0;
    for (int a = 0; a < 3; a++) {
        double e = c[a] - o[a];
        d2 += e * e;
        half_diag2 += 0.25 * h[a] * h[a];
    }
    double d = sqrt(d2), half_diag = sqrt(half_diag2);
    if (d + half_diag <= r)
        return 1.0;
    if (d - half_diag >= r)
        return 0.0;
    const int m = 4;
    int inside = 0;
    for (int k = 0; k < m; k++) {
        double z = c[2] + ((k + 0.5) / m - 0.5) * h[2] - o[2];
        for (int j = 0; j < m; j++) {
            double y = c[1] + ((j + 0.5) / m - 0.5) * h[1] - o[1];
            for (int i = 0; i < m; i++) {
                double x = c[0] + ((i + 0.5) / m - 0.5) * h[0] - o[0];
                inside += x * x + y * y + z * z <= r * r;
            }
        }
    }
    return (double)inside / (m * m * m);
}

static void fill_sphere(const struct synth_desc *d, struct ext_volume *v, int channel)
{
    const struct grid3 *g = &v->grid;
    double o[3], r = 0.5 * fmin(d->extent_m[0], fmin(d->extent_m[1], d->extent_m[2]));
    for (int a = 0; a < 3; a++)
        o[a] = 0.5 * d->extent_m[a];
    double beta = d->tau / (2.0 * r);
    size_t idx = 0;
    for (int k = 0; k < g->n[2]; k++) {
        for (int j = 0; j < g->n[1]; j++) {
            for (int i = 0; i < g->n[0]; i++, idx++) {
                double c[3] = {(i + 0.5) * g->spacing[0], (j + 0.5) * g->spacing[1],
                               (k + 0.5) * g->spacing[2]};
                double f = ball_fraction(c, g->spacing, o, r);
                v->beta[2 * idx + channel] = (float)(beta * f);
            }
        }
    }
}

bool synth_extinction(const struct synth_desc *d, const struct optics_params *optics,
                      struct ext_volume *out)
{
    memset(out, 0, sizeof(*out));
    if (!check_desc(d))
        return false;

    if (d->kind == SYNTH_STORM) {
        struct field_volume fields;
        if (!synth_storm_fields(d, &fields))
            return false;
        struct optics_params defaults;
        if (!optics) {
            optics_params_defaults(&defaults);
            optics = &defaults;
        }
        struct species_select sel;
        species_select_defaults(&sel);
        bool ok = ext_volume_from_fields(&fields, optics, &sel, out);
        field_volume_finish(&fields);
        return ok;
    }

    struct grid3 g;
    grid_from_desc(d, &g);
    if (!ext_volume_init(out, &g))
        return false;
    int channel = d->ice_phase ? 0 : 1;
    size_t count = grid3_count(&g);
    switch (d->kind) {
    case SYNTH_SLAB: {
        float beta = (float)(d->tau / d->extent_m[2]);
        for (size_t i = 0; i < count; i++)
            out->beta[2 * i + channel] = beta;
        break;
    }
    case SYNTH_SPHERE:
        fill_sphere(d, out, channel);
        break;
    case SYNTH_VOXEL: {
        size_t i = grid3_index(&g, g.n[0] / 2, g.n[1] / 2, g.n[2] / 2);
        out->beta[2 * i + channel] = (float)(d->tau / g.spacing[2]);
        break;
    }
    case SYNTH_EMPTY:
    case SYNTH_STORM:
        break;
    }
    return true;
}
