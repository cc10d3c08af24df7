/*
 * reference/: the Monte Carlo reference against closed forms.  Every stochastic check
 * compares an estimate with its own standard error: |estimate - exact| < 5 sigma (plus half a
 * unit of the last digit of a tabulated value).  Seeds are fixed, so a run is reproducible;
 * the tolerance is what makes a wrong estimator fail and a right one pass for any seed.
 *
 * The plane-parallel cases use a single-voxel slab 10^4 thicknesses wide (laterally infinite
 * for every path that matters) and the image renderer's own estimator, reference_radiance,
 * with view rays aimed at the slab.  Lines starting "VALIDATION |" are the table in
 * docs/reference.md.
 */
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "data/volume.h"
#include "optics/optics.h"
#include "reference/reference.h"
#include "render/camera.h"
#include "testutil.h"

#define PI 3.14159265358979323846
#define NSIGMA 5.0

/* ---- helpers ----------------------------------------------------------------------------- */

struct stat {
    double n, mean, m2;
};

static void stat_add(struct stat *s, double v)
{
    s->n += 1.0;
    double d = v - s->mean;
    s->mean += d / s->n;
    s->m2 += d * (v - s->mean);
}

static double stat_err(const struct stat *s)
{
    return sqrt(s->m2 / (s->n * (s->n - 1.0)));
}

/* Checks |est - exact| < NSIGMA err + slack and prints a table row. */
static void check_close(const char *what, double exact, double est, double err, double n,
                        double slack)
{
    double dev = fabs(est - exact);
    printf("VALIDATION | %s | %.6g | %.6g | %.2g | %.0f | %.1f sigma\n", what, exact, est, err, n,
           err > 0.0 ? dev / err : 0.0);
    if (!(dev < NSIGMA * err + slack)) {
        fail_msg("%s: estimate %.6f +- %.6f, expected %.6f (%.1f sigma)", what, est, err, exact,
                 err > 0.0 ? dev / err : INFINITY);
    }
}

/* Homogeneous slab [0, H] in z, 10^4 H wide, optical thickness TAU, phase ICE or water. */
static void make_slab(struct ext_volume *v, double tau, double h, bool ice)
{
    double w = 1e4 * h;
    struct grid3 g = {.n = {1, 1, 1}, .spacing = {w, w, h}, .origin = {-0.5 * w, -0.5 * w, 0.0}};
    assert_true(ext_volume_init(v, &g));
    v->beta[ice ? 0 : 1] = (float)(tau / h);
}

static struct reference *make_ref(const struct ext_volume *v, enum reference_phase phase, double g,
                                  double albedo, double sun_elev_deg, double e, double sky)
{
    struct reference_desc d;
    reference_desc_defaults(&d);
    d.phase = phase;
    d.g_ice = d.g_water = g;
    d.albedo = albedo;
    double el = sun_elev_deg * PI / 180.0;
    d.sun_dir[0] = cos(el);
    d.sun_dir[1] = 0.0;
    d.sun_dir[2] = sin(el);
    for (int c = 0; c < 3; c++) {
        d.sun_irradiance[c] = e;
        d.sky[c] = sky;
    }
    struct reference *r = reference_create(v, &d);
    assert_non_null(r);
    return r;
}

/* Cosine-weighted direction into the slab from above (DOWN) or below. */
static void cosine_dir(struct reference_rng *rng, bool down, double d[3])
{
    double u = reference_rng_uniform(rng), phi = 2.0 * PI * reference_rng_uniform(rng);
    double s = sqrt(u);
    d[0] = s * cos(phi);
    d[1] = s * sin(phi);
    d[2] = (down ? -1.0 : 1.0) * sqrt(1.0 - u);
}

/* Mean over cosine-weighted view directions of pi I / SCALE (first channel): the
 * hemispherical flux leaving the top (DOWN) or bottom face per unit SCALE. */
static struct stat hemispherical(const struct reference *r, double h, bool down, long n,
                                 uint64_t seed, double scale)
{
    struct stat s = {0};
    struct reference_rng rng;
    reference_rng_seed(&rng, seed, 0);
    double o[3] = {0.0, 0.0, down ? 1.001 * h : -0.001 * h};
    for (long i = 0; i < n; i++) {
        double d[3], l[3];
        cosine_dir(&rng, down, d);
        reference_radiance(r, o, d, &rng, l, NULL);
        stat_add(&s, PI * l[0] / scale);
    }
    return s;
}

/* ---- random numbers and phase sampling --------------------------------------------------- */

static void test_rng(void **state)
{
    struct reference_rng a, b, c;
    reference_rng_seed(&a, 7, 3);
    reference_rng_seed(&b, 7, 3);
    reference_rng_seed(&c, 7, 4);
    int same_c = 0;
    struct stat s = {0};
    for (int i = 0; i < 100000; i++) {
        uint64_t x = reference_rng_next(&a), y = reference_rng_next(&b);
        assert_true(x == y);
        same_c += x == reference_rng_next(&c);
        double u = reference_rng_uniform(&a);
        reference_rng_uniform(&b);
        reference_rng_uniform(&c);
        assert_true(u >= 0.0 && u < 1.0);
        stat_add(&s, u);
    }
    assert_int_equal(same_c, 0);
    /* Uniform: mean 1/2, variance 1/12. */
    assert_true(fabs(s.mean - 0.5) < NSIGMA * sqrt(1.0 / 12.0 / s.n));
    assert_true(fabs(s.m2 / s.n - 1.0 / 12.0) < 0.002);
}

/* Chi-square of a histogram of sampled cosines in 40 equal bins of mu against the bin
 * probabilities from the cumulative phase, and the mean cosine against its closed form. */
static void check_sampler(bool cs, double g)
{
    enum { BINS = 40 };
    const long n = 400000;
    long count[BINS] = {0};
    struct reference_rng rng;
    reference_rng_seed(&rng, 11, (uint64_t)(g * 1000.0 + 5000.0) + (cs ? 100000 : 0));
    struct stat s = {0};
    for (long i = 0; i < n; i++) {
        double mu = cs ? reference_sample_cs(g, &rng) : reference_sample_hg(g, &rng);
        assert_true(mu >= -1.0 && mu <= 1.0);
        int k = (int)((mu + 1.0) * 0.5 * BINS);
        count[k < BINS ? k : BINS - 1]++;
        stat_add(&s, mu);
    }
    double chi2 = 0.0, total = 0.0;
    for (int k = 0; k < BINS; k++) {
        double lo = -1.0 + 2.0 * k / BINS, hi = -1.0 + 2.0 * (k + 1) / BINS;
        double p = cs ? phase_cs_cumulative(g, acos(lo)) - phase_cs_cumulative(g, acos(hi))
                      : phase_hg_cumulative(g, acos(lo)) - phase_hg_cumulative(g, acos(hi));
        total += p;
        double e = p * n;
        assert_true(e > 5.0);
        chi2 += (count[k] - e) * (count[k] - e) / e;
    }
    assert_true(fabs(total - 1.0) < 1e-9);
    double mc = cs ? phase_cs_mean_cosine(g) : g;
    printf("sampler %s g=%+.2f: chi2 %.1f (39 dof), <mu> %.5f +- %.5f (exact %.5f)\n",
           cs ? "CS" : "HG", g, chi2, s.mean, stat_err(&s), mc);
    /* 39 degrees of freedom: P(chi2 > 81) ~ 1e-4. */
    assert_true(chi2 < 81.0);
    assert_true(fabs(s.mean - mc) < NSIGMA * stat_err(&s));
}

static void test_sample_hg(void **state)
{
    const double gs[] = {-0.7, 0.0, 0.3, 0.9};
    for (size_t i = 0; i < sizeof gs / sizeof gs[0]; i++)
        check_sampler(false, gs[i]);
    /* Near g = 0 the rearranged inversion has no 1/g: still isotropic-like and finite. */
    struct reference_rng rng;
    reference_rng_seed(&rng, 1, 1);
    for (int i = 0; i < 1000; i++) {
        double mu = reference_sample_hg(1e-12, &rng);
        assert_true(isfinite(mu) && mu >= -1.0 && mu <= 1.0);
        mu = reference_sample_hg(0.99999, &rng); /* clamped to 0.999 */
        assert_true(isfinite(mu) && mu >= -1.0 && mu <= 1.0);
    }
}

static void test_sample_cs(void **state)
{
    const double gs[] = {-0.5, 0.0, 0.6, 0.9};
    for (size_t i = 0; i < sizeof gs / sizeof gs[0]; i++)
        check_sampler(true, gs[i]);
}

/* ---- extinction lookup ------------------------------------------------------------------- */

static void test_beta_lookup(void **state)
{
    struct ext_volume v;
    struct grid3 g = {.n = {3, 2, 2}, .spacing = {2.0, 1.0, 4.0}, .origin = {10.0, 0.0, 0.0}};
    assert_true(ext_volume_init(&v, &g));
    for (size_t i = 0; i < grid3_count(&g); i++) {
        v.beta[2 * i] = (float)i;
        v.beta[2 * i + 1] = (float)(2 * i + 1);
    }
    struct reference_desc d;
    reference_desc_defaults(&d);
    struct reference *r = reference_create(&v, &d);
    assert_non_null(r);
    double b[2];
    /* Voxel centre (1, 1, 0): index 4. */
    reference_beta(r, (double[]){13.0, 1.5, 2.0}, b);
    assert_true(fabs(b[0] - 4.0) < 1e-12 && fabs(b[1] - 9.0) < 1e-12);
    /* Half way between centres (1,0,0) and (2,0,0): indices 1 and 2. */
    reference_beta(r, (double[]){14.0, 0.5, 2.0}, b);
    assert_true(fabs(b[0] - 1.5) < 1e-12 && fabs(b[1] - 4.0) < 1e-12);
    /* Inside the box but beyond the last centre: clamp to edge. */
    reference_beta(r, (double[]){15.9, 0.1, 0.1}, b);
    assert_true(fabs(b[0] - 2.0) < 1e-12);
    /* Outside: zero. */
    reference_beta(r, (double[]){16.1, 0.5, 2.0}, b);
    assert_true(b[0] == 0.0 && b[1] == 0.0);
    reference_destroy(r);

    /* Bad volumes are refused with a message. */
    v.beta[3] = NAN;
    assert_null(reference_create(&v, &d));
    v.beta[3] = -1.0f;
    assert_null(reference_create(&v, &d));
    v.beta[3] = 0.0f;
    d.albedo = 1.5;
    assert_null(reference_create(&v, &d));
    reference_destroy(NULL);
    ext_volume_finish(&v);
}

/* ---- (a) direct transmittance ------------------------------------------------------------ */

static void test_slab_transmittance(void **state)
{
    const double taus[] = {0.5, 2.0, 8.0};
    for (size_t i = 0; i < 3; i++) {
        double h = 500.0;
        struct ext_volume v;
        make_slab(&v, taus[i], h, false);
        double tau = (double)v.beta[1] * h; /* as stored (float) */
        struct reference *r = make_ref(&v, REFERENCE_PHASE_HG, 0.0, 1.0, 90.0, 0.0, 0.0);
        struct reference_rng rng;
        reference_rng_seed(&rng, 3, i);
        /* Vertical and at mu = 0.5 (optical path tau / mu). */
        const double mus[] = {1.0, 0.5};
        for (int m = 0; m < 2; m++) {
            double mu = mus[m];
            double o[3] = {0.0, 0.0, 2.0 * h}, d[3] = {sqrt(1.0 - mu * mu), 0.0, -mu};
            double exact = exp(-tau / mu);
            /* Delta tracking: the fraction of flights that pass is a Bernoulli mean. */
            const long n = 400000;
            long pass = 0;
            for (long k = 0; k < n; k++) {
                double t;
                pass += !reference_free_flight(r, o, d, 0.0, INFINITY, &rng, &t);
            }
            double p = (double)pass / n;
            double err = sqrt(fmax(exact * (1.0 - exact), 1e-12) / n);
            char what[96];
            snprintf(what, sizeof what, "direct transmittance e^-tau/mu, tau=%g mu=%g (delta)", tau,
                     mu);
            check_close(what, exact, p, err, n, 0.0);
            /* Residual ratio tracking: homogeneous, so exact (no samples, no roulette). */
            double tr = reference_transmittance(r, o, d, 0.0, INFINITY, &rng);
            assert_true(fabs(tr - exact) < 1e-12 * exact);
        }
        reference_destroy(r);
        ext_volume_finish(&v);
    }
}

/* Layers across several bound blocks: beta piecewise linear in z between voxel centres,
 * constant in the half voxels at the faces, so tau along a vertical line is exact. */
static void test_layered_transmittance(void **state)
{
    const int nz = 37;
    const double dz = 40.0;
    struct ext_volume v;
    struct grid3 g = {.n = {1, 1, nz}, .spacing = {1e6, 1e6, dz}, .origin = {-5e5, -5e5, 0.0}};
    assert_true(ext_volume_init(&v, &g));
    double b[64];
    for (int k = 0; k < nz; k++) {
        b[k] = 0.002 * (1.0 + sin(0.7 * k)) + (k > 20 && k < 26 ? 0.01 : 0.0);
        v.beta[2 * k] = (float)(0.3 * b[k]);
        v.beta[2 * k + 1] = (float)(b[k] - (float)(0.3 * b[k]));
        b[k] = (double)v.beta[2 * k] + (double)v.beta[2 * k + 1];
    }
    double tau = 0.5 * dz * (b[0] + b[nz - 1]);
    for (int k = 0; k + 1 < nz; k++)
        tau += 0.5 * dz * (b[k] + b[k + 1]);
    struct reference *r = make_ref(&v, REFERENCE_PHASE_HG, 0.0, 1.0, 90.0, 0.0, 0.0);
    struct reference_rng rng;
    reference_rng_seed(&rng, 5, 0);
    const double mus[] = {1.0, -0.6};
    for (int m = 0; m < 2; m++) {
        double mu = mus[m];
        double o[3] = {3.0, -7.0, mu > 0 ? -10.0 : nz * dz + 10.0};
        double d[3] = {0.0, sqrt(1.0 - mu * mu), mu};
        double exact = exp(-tau / fabs(mu));
        const long n = 500000;
        struct stat delta = {0}, ratio = {0};
        for (long k = 0; k < n; k++) {
            double t;
            stat_add(&delta, reference_free_flight(r, o, d, 0.0, INFINITY, &rng, &t) ? 0.0 : 1.0);
            stat_add(&ratio, reference_transmittance(r, o, d, 0.0, INFINITY, &rng));
        }
        char what[96];
        snprintf(what, sizeof what, "layered transmittance, 5 blocks, mu=%g (delta)", fabs(mu));
        check_close(what, exact, delta.mean, stat_err(&delta), n, 0.0);
        snprintf(what, sizeof what, "layered transmittance, 5 blocks, mu=%g (ratio)", fabs(mu));
        check_close(what, exact, ratio.mean, stat_err(&ratio), n, 0.0);
        /* Ratio tracking is the better estimator here, or the bounds are loose. */
        assert_true(stat_err(&ratio) < stat_err(&delta));
    }
    reference_destroy(r);
    ext_volume_finish(&v);
}

/* ---- (b) semi-infinite isotropic medium, albedo 0.8 -------------------------------------- */

static void test_semi_infinite(void **state)
{
    /* tau = 100: diffusion through it decays as exp(-sqrt(3 (1 - a)) tau) ~ 1e-34. */
    const double h = 100.0, a = 0.8;
    struct ext_volume v;
    make_slab(&v, 100.0, h, true);

    /* Sun overhead, E = 1: total diffuse reflectance = mean pi I over cosine-weighted exits
     * = 1 - H(1) sqrt(1 - a) (Chandrasekhar). */
    struct reference *r = make_ref(&v, REFERENCE_PHASE_HG, 0.0, a, 90.0, 1.0, 0.0);
    const long n = 600000;
    struct stat s = hemispherical(r, h, true, n, 21, 1.0);
    check_close("semi-infinite reflectance, a=0.8, mu0=1 (1 - H(1) sqrt(1-a))", 0.28525, s.mean,
                stat_err(&s), n, 5e-6);

    /* Reflected pi I / E at exit mu = 0.5: (a/4) H(mu) H(mu0) / (mu + mu0), H from our own
     * solution of the H-equation (docs/reference.md). */
    struct reference_rng rng;
    reference_rng_seed(&rng, 22, 0);
    struct stat s2 = {0};
    double o[3] = {0.0, 0.0, 1.001 * h}, d[3] = {sqrt(0.75), 0.0, -0.5};
    for (long i = 0; i < n; i++) {
        double l[3];
        reference_radiance(r, o, d, &rng, l, NULL);
        stat_add(&s2, PI * l[0]);
    }
    check_close("semi-infinite pi I/E, a=0.8, mu0=1, mu=0.5 (H-function)", 0.301161, s2.mean,
                stat_err(&s2), n, 5e-7);
    reference_destroy(r);

    /* Uniform sky of radiance 1, no sun: reflected radiance averaged over cosine-weighted
     * exits is the reflectance for diffuse illumination, 1 - 2 sqrt(1 - a) int H mu dmu. */
    r = make_ref(&v, REFERENCE_PHASE_HG, 0.0, a, 90.0, 0.0, 1.0);
    s = hemispherical(r, h, true, n, 23, PI);
    check_close("semi-infinite reflectance, a=0.8, diffuse illumination", 0.34187, s.mean,
                stat_err(&s), n, 5e-6);
    reference_destroy(r);
    ext_volume_finish(&v);
}

/* ---- (c) finite isotropic slab, tau = 2, albedo 0.8 -------------------------------------- */

static void test_finite_slab_radiance(void **state)
{
    const double h = 250.0;
    struct ext_volume v;
    make_slab(&v, 2.0, h, false);
    struct reference *r = make_ref(&v, REFERENCE_PHASE_HG, 0.0, 0.8, 90.0, 1.0, 0.0);
    struct reference_rng rng;
    reference_rng_seed(&rng, 31, 0);
    const long n = 600000;
    struct stat s = {0};
    double o[3] = {0.0, 0.0, 1.001 * h}, d[3] = {0.0, -sqrt(0.75), -0.5};
    for (long i = 0; i < n; i++) {
        double l[3];
        reference_radiance(r, o, d, &rng, l, NULL);
        stat_add(&s, PI * l[0]);
    }
    check_close("slab tau=2, a=0.8: reflected pi I/E, mu0=1, mu=0.5 (van de Hulst T12)", 0.28616,
                s.mean, stat_err(&s), n, 5e-6);
    reference_destroy(r);
    ext_volume_finish(&v);
}

/* ---- (d) furnace: albedo 1 loses nothing ------------------------------------------------- */

static void test_furnace(void **state)
{
    /* Anisotropic CS, oblique sun: reflected + diffusely transmitted + direct = incident. */
    const double h = 300.0, tau = 2.0, elev = 60.0, g = 0.5;
    const double mu0 = sin(elev * PI / 180.0);
    struct ext_volume v;
    make_slab(&v, tau, h, true);
    struct reference *r = make_ref(&v, REFERENCE_PHASE_CS, g, 1.0, elev, 1.0, 0.0);
    const long n = 300000;
    struct stat up = hemispherical(r, h, true, n, 41, mu0);
    struct stat down = hemispherical(r, h, false, n, 42, mu0);
    double direct = exp(-tau / mu0);
    double total = up.mean + down.mean + direct;
    double err = sqrt(stat_err(&up) * stat_err(&up) + stat_err(&down) * stat_err(&down));
    printf("furnace: R %.5f + T_diffuse %.5f + T_direct %.5f\n", up.mean, down.mean, direct);
    check_close("furnace a=1, CS g=0.5, tau=2, sun 60 deg: R + T", 1.0, total, err, 2 * n, 0.0);
    reference_destroy(r);

    /* The same slab with half the light absorbed must lose some: the check can fail. */
    r = make_ref(&v, REFERENCE_PHASE_CS, g, 0.9, elev, 1.0, 0.0);
    up = hemispherical(r, h, true, n / 4, 43, mu0);
    down = hemispherical(r, h, false, n / 4, 44, mu0);
    assert_true(up.mean + down.mean + direct < 0.95);
    reference_destroy(r);
    ext_volume_finish(&v);
}

/* ---- single scattering: the renderer's convention ---------------------------------------- */

static void test_single_scattering(void **state)
{
    /* Reflected single scattering of a slab with sun at mu0, view at mu (both from above):
     * I = a E p(cos psi) mu0 / (mu + mu0) (1 - exp(-tau (1/mu + 1/mu0))).  Sun from the east
     * at 30 degrees, view going east and down at 60 degrees from the zenith: cos psi =
     * sun . d = +0.5 (forward-ish, which a sign error would turn into -0.5). */
    const double h = 100.0, tau = 0.7, a = 0.9;
    struct ext_volume v;
    make_slab(&v, tau, h, false);
    struct render_settings rs = {.sun_dir = {(float)cos(PI / 6.0), 0.0f, 0.5f},
                                 .sun_radiance = {0.25f, 0.5f, 1.0f}};
    struct optics_params op;
    optics_params_defaults(&op);
    struct reference_desc d;
    reference_desc_from_render(&rs, &op, &d);
    assert_true(fabs(d.sun_irradiance[2] - 4.0 * PI) < 1e-5);
    assert_true(fabs(d.g_water - phase_cs_g_for_mean_cosine(op.g_water)) < 1e-12);
    d.albedo = a;
    d.max_bounces = 1;
    struct reference *r = reference_create(&v, &d);
    assert_non_null(r);
    double mu = 0.5, mu0 = d.sun_dir[2];
    double o[3] = {0.0, 0.0, 1.5 * h}, dir[3] = {sqrt(0.75), 0.0, -0.5};
    double cos_psi = d.sun_dir[0] * dir[0] + d.sun_dir[2] * dir[2];
    double exact = a * 4.0 * PI * phase_cs(d.g_water, cos_psi) * mu0 / (mu + mu0) *
                   (1.0 - exp(-tau * (1.0 / mu + 1.0 / mu0)));
    struct reference_rng rng;
    reference_rng_seed(&rng, 51, 0);
    const long n = 200000;
    struct stat s = {0}, s0 = {0};
    for (long i = 0; i < n; i++) {
        double l[3];
        reference_radiance(r, o, dir, &rng, l, NULL);
        stat_add(&s, l[2]);
        stat_add(&s0, l[0]);
    }
    check_close("single scattering, CS g(0.86), tau=0.7, cos psi=0.5, sun_radiance=1", exact,
                s.mean, stat_err(&s), n, 0.0);
    /* Colour channels scale with sun_radiance. */
    assert_true(fabs(s0.mean - 0.25 * s.mean) < 1e-9 * s.mean);
    reference_destroy(r);
    ext_volume_finish(&v);
}

/* ---- images ------------------------------------------------------------------------------ */

static void make_cloud(struct ext_volume *v)
{
    struct grid3 g = {
        .n = {20, 17, 11}, .spacing = {100.0, 100.0, 80.0}, .origin = {-1000.0, -850.0, 200.0}};
    assert_true(ext_volume_init(v, &g));
    struct reference_rng rng;
    reference_rng_seed(&rng, 99, 0);
    for (size_t i = 0; i < grid3_count(&g); i++) {
        double u = reference_rng_uniform(&rng);
        v->beta[2 * i + (u < 0.5)] = (float)(u < 0.2 ? 0.0 : 0.02 * u);
    }
}

static void look(struct render_view *view, double ez)
{
    camera_look_at((double[]){-3000.0, -2500.0, ez}, (double[]){0.0, 0.0, 600.0},
                   (double[]){0.0, 0.0, 1.0}, 50.0, 1.0, 50000.0, 24, 16, view);
}

static void test_render_deterministic(void **state)
{
    struct ext_volume v;
    make_cloud(&v);
    struct reference_desc d;
    reference_desc_defaults(&d);
    d.g_ice = 0.5;
    d.g_water = 0.8;
    d.sun_dir[0] = 0.6;
    d.sun_dir[2] = 0.8;
    for (int c = 0; c < 3; c++) {
        d.sun_irradiance[c] = 10.0;
        d.sky[c] = 0.2;
        d.ground_albedo[c] = 0.3;
    }
    d.ground_on = true;
    struct reference *r = reference_create(&v, &d);
    assert_non_null(r);
    struct render_view view;
    look(&view, 1500.0);
    struct image m1, e1, m3, e3;
    struct reference_image_desc id = {.spp = 6, .threads = 1, .seed = 4};
    assert_true(reference_render(r, &view, &id, &m1, &e1));
    id.threads = 3;
    assert_true(reference_render(r, &view, &id, &m3, &e3));
    size_t bytes = (size_t)m1.width * m1.height * 4 * sizeof(float);
    assert_memory_equal(m1.rgba, m3.rgba, bytes);
    assert_memory_equal(e1.rgba, e3.rgba, bytes);
    assert_int_equal(image_count_nonfinite(&m1), 0);
    bool some_cloud = false;
    for (int i = 0; i < m1.width * m1.height; i++) {
        for (int c = 0; c < 4; c++) {
            assert_true(m1.rgba[4 * i + c] >= 0.0f && e1.rgba[4 * i + c] >= 0.0f);
        }
        assert_true(m1.rgba[4 * i + 3] <= 1.0f);
        some_cloud |= m1.rgba[4 * i + 3] < 1.0f;
    }
    assert_true(some_cloud);
    /* Another seed gives another image. */
    id.seed = 5;
    struct image m5, e5;
    assert_true(reference_render(r, &view, &id, &m5, &e5));
    assert_true(memcmp(m1.rgba, m5.rgba, bytes) != 0);
    image_finish(&m1);
    image_finish(&e1);
    image_finish(&m3);
    image_finish(&e3);
    image_finish(&m5);
    image_finish(&e5);
    reference_destroy(r);
    ext_volume_finish(&v);
}

/* An empty volume: sky above the horizon, and the Lambertian ground below it with the
 * closed form albedo (E cos(theta_s) / pi + sky) -- every sample exact. */
static void test_render_background(void **state)
{
    struct ext_volume v;
    make_cloud(&v);
    memset(v.beta, 0, grid3_count(&v.grid) * 2 * sizeof(float));
    struct reference_desc d;
    reference_desc_defaults(&d);
    d.sun_dir[0] = 0.6;
    d.sun_dir[2] = 0.8;
    const double e[3] = {3.0, 2.0, 1.0}, sky[3] = {0.1, 0.2, 0.4}, rho[3] = {0.9, 0.6, 0.7};
    for (int c = 0; c < 3; c++) {
        d.sun_irradiance[c] = e[c];
        d.sky[c] = sky[c];
        d.ground_albedo[c] = rho[c];
    }
    d.ground_on = true;
    struct reference *r = reference_create(&v, &d);
    assert_non_null(r);
    struct render_view view;
    look(&view, 400.0);
    struct image m, err;
    struct reference_image_desc id = {.spp = 3, .threads = 2, .seed = 1};
    assert_true(reference_render(r, &view, &id, &m, &err));
    int n_ground = 0, n_sky = 0;
    for (int i = 0; i < m.width * m.height; i++) {
        const float *px = m.rgba + 4 * i;
        bool ground = fabs(px[0] - sky[0]) > 1e-6;
        for (int c = 0; c < 3; c++) {
            double want = ground ? rho[c] * (e[c] * 0.8 / PI + sky[c]) : sky[c];
            assert_true(fabs(px[c] - want) < 1e-5 * want);
            assert_true(err.rgba[4 * i + c] < 1e-6);
        }
        assert_true(px[3] == 1.0f);
        n_ground += ground;
        n_sky += !ground;
    }
    /* The camera at 400 m looks slightly down: both appear, the ground in the lower rows. */
    assert_true(n_ground > 0 && n_sky > 0);
    assert_true(fabs(m.rgba[0] - sky[0]) > 1e-3); /* row 0 is the bottom */
    image_finish(&m);
    image_finish(&err);
    reference_destroy(r);
    ext_volume_finish(&v);
}

/* Optically very thick (column tau 10^4): finite, non-negative, and no more light leaves
 * than arrives. */
static void test_very_thick(void **state)
{
    const double h = 1000.0;
    struct ext_volume v;
    make_slab(&v, 1e4, h, false);
    struct reference *r = make_ref(&v, REFERENCE_PHASE_CS, 0.6, 0.95, 40.0, 1.0, 0.0);
    const long n = 20000;
    struct stat s = hemispherical(r, h, true, n, 61, sin(40.0 * PI / 180.0));
    struct stat t = hemispherical(r, h, false, n, 62, sin(40.0 * PI / 180.0));
    assert_true(isfinite(s.mean) && s.mean > 0.0 && s.mean < 1.0);
    assert_true(t.mean == 0.0);
    struct reference_rng rng;
    reference_rng_seed(&rng, 63, 0);
    double o[3] = {0.0, 0.0, 2.0 * h}, d[3] = {0.0, 0.0, -1.0};
    assert_true(reference_transmittance(r, o, d, 0.0, INFINITY, &rng) == 0.0);
    reference_destroy(r);
    ext_volume_finish(&v);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rng),
        cmocka_unit_test(test_sample_hg),
        cmocka_unit_test(test_sample_cs),
        cmocka_unit_test(test_beta_lookup),
        cmocka_unit_test(test_slab_transmittance),
        cmocka_unit_test(test_layered_transmittance),
        cmocka_unit_test(test_semi_infinite),
        cmocka_unit_test(test_finite_slab_radiance),
        cmocka_unit_test(test_furnace),
        cmocka_unit_test(test_single_scattering),
        cmocka_unit_test(test_render_deterministic),
        cmocka_unit_test(test_render_background),
        cmocka_unit_test(test_very_thick),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
