/*
 * Synthetic scenes: the procedural storm's species, heights, growth and drift, determinism,
 * and the exact optical depths of the test scenes.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include "common/log.h"
#include "data/synth.h"

#define G_PER_KG 1e-3

static struct synth_desc storm_desc(int nx, int ny, int nz, double time, unsigned seed)
{
    struct synth_desc d;
    synth_desc_defaults(&d);
    d.kind = SYNTH_STORM;
    d.n[0] = nx;
    d.n[1] = ny;
    d.n[2] = nz;
    d.time = time;
    d.seed = seed;
    return d;
}

static double voxel_z(const struct grid3 *g, int k)
{
    return g->origin[2] + (k + 0.5) * g->spacing[2];
}

/* Mass-ratio statistics of one species. */
struct species_stats {
    double max;           /* kg/kg */
    double max_z;         /* height of the maximum, m */
    double sum;           /* sum over voxels */
    double lowest, highest; /* heights of the lowest and highest voxel above 1e-6 kg/kg */
    double centroid[3];   /* q-weighted mean position, m */
};

static double sum_between(const struct field_volume *v, int f, double z0, double z1)
{
    const struct grid3 *g = &v->grid;
    double s = 0.0;
    for (int k = 0; k < g->n[2]; k++) {
        double z = voxel_z(g, k);
        if (z < z0 || z >= z1)
            continue;
        for (int j = 0; j < g->n[1]; j++)
            for (int i = 0; i < g->n[0]; i++)
                s += v->q[f][grid3_index(g, i, j, k)];
    }
    return s;
}

static void stats(const struct field_volume *v, int f, struct species_stats *st)
{
    const struct grid3 *g = &v->grid;
    memset(st, 0, sizeof(*st));
    st->lowest = INFINITY;
    st->highest = -INFINITY;
    for (int k = 0; k < g->n[2]; k++) {
        for (int j = 0; j < g->n[1]; j++) {
            for (int i = 0; i < g->n[0]; i++) {
                double q = v->q[f][grid3_index(g, i, j, k)];
                assert_true(isfinite(q));
                assert_true(q >= 0.0);
                double p[3] = {(i + 0.5) * g->spacing[0], (j + 0.5) * g->spacing[1],
                               voxel_z(g, k)};
                if (q > st->max) {
                    st->max = q;
                    st->max_z = p[2];
                }
                st->sum += q;
                for (int a = 0; a < 3; a++)
                    st->centroid[a] += q * p[a];
                if (q > 1e-6) {
                    st->lowest = fmin(st->lowest, p[2]);
                    st->highest = fmax(st->highest, p[2]);
                }
            }
        }
    }
    if (st->sum > 0.0)
        for (int a = 0; a < 3; a++)
            st->centroid[a] /= st->sum;
}

/* Columns whose ice + snow above 8 km exceed 0.05 g/kg somewhere: the anvil's footprint. */
static int anvil_columns(const struct field_volume *v)
{
    const struct grid3 *g = &v->grid;
    int count = 0;
    for (int j = 0; j < g->n[1]; j++) {
        for (int i = 0; i < g->n[0]; i++) {
            for (int k = 0; k < g->n[2]; k++) {
                size_t idx = grid3_index(g, i, j, k);
                if (voxel_z(g, k) > 8000.0 &&
                    v->q[SPECIES_ICE][idx] + v->q[SPECIES_SNOW][idx] > 0.05 * G_PER_KG) {
                    count++;
                    break;
                }
            }
        }
    }
    return count;
}

/* Columns with cloud water above 0.1 g/kg at the level nearest height Z. */
static int cloud_columns_at(const struct field_volume *v, double z)
{
    const struct grid3 *g = &v->grid;
    int k = (int)(z / g->spacing[2]);
    int count = 0;
    for (int j = 0; j < g->n[1]; j++)
        for (int i = 0; i < g->n[0]; i++)
            count += v->q[SPECIES_CLOUD][grid3_index(g, i, j, k)] > 0.1 * G_PER_KG;
    return count;
}

static double total_condensate(const struct field_volume *v)
{
    double s = 0.0;
    for (int f = 0; f < SPECIES_COUNT; f++)
        s += sum_between(v, f, -INFINITY, INFINITY);
    return s;
}

static bool same_fields(const struct field_volume *a, const struct field_volume *b)
{
    size_t n = grid3_count(&a->grid);
    for (int f = 0; f < SPECIES_COUNT; f++)
        if (memcmp(a->q[f], b->q[f], n * sizeof(float)) != 0)
            return false;
    return true;
}

static void test_storm_deterministic(void **state)
{
    struct synth_desc d = storm_desc(64, 48, 32, 0.4, 11);
    struct field_volume a, b, c, one;
    assert_true(synth_storm_fields(&d, &a));
    assert_true(synth_storm_fields(&d, &b));
    assert_true(same_fields(&a, &b));
    /* the number of threads does not change a bit */
    assert_true(synth_storm_fields_threads(&d, 1, &one));
    assert_true(same_fields(&a, &one));
    assert_null(a.rho_air);
    assert_null(a.qvapor);
    for (int f = 0; f < SPECIES_COUNT; f++)
        assert_non_null(a.q[f]);
    assert_int_equal(a.grid.n[0], 64);
    assert_int_equal(a.grid.n[1], 48);
    assert_int_equal(a.grid.n[2], 32);
    assert_true(fabs(a.grid.spacing[0] - 60000.0 / 64) < 1e-9);
    assert_true(fabs(a.grid.spacing[2] - 16000.0 / 32) < 1e-9);
    assert_true(a.grid.origin[0] == 0.0 && a.grid.origin[1] == 0.0 && a.grid.origin[2] == 0.0);

    d.seed = 12;
    assert_true(synth_storm_fields(&d, &c));
    assert_false(same_fields(&a, &c));
    field_volume_finish(&a);
    field_volume_finish(&b);
    field_volume_finish(&c);
    field_volume_finish(&one);
    field_volume_finish(NULL);
}

static void check_storm_species(const struct field_volume *v)
{
    static const double lo[SPECIES_COUNT] = {1.0, 0.5, 0.1, 0.1, 0.5};  /* g/kg */
    static const double hi[SPECIES_COUNT] = {2.5, 3.0, 0.6, 1.2, 2.0};
    struct species_stats st[SPECIES_COUNT];
    for (int f = 0; f < SPECIES_COUNT; f++) {
        stats(v, f, &st[f]);
        assert_true(st[f].max >= lo[f] * G_PER_KG);
        assert_true(st[f].max <= hi[f] * G_PER_KG);
    }
    /* cloud water: base above 1 km, tower up to at least 9 km */
    assert_true(st[SPECIES_CLOUD].lowest > 1000.0);
    assert_true(st[SPECIES_CLOUD].highest > 9000.0);
    assert_true(sum_between(v, SPECIES_CLOUD, 0.0, 1000.0) == 0.0);
    /* ice mostly in the anvil above 8 km */
    double ice = st[SPECIES_ICE].sum;
    assert_true(sum_between(v, SPECIES_ICE, 8000.0, INFINITY) > 0.8 * ice);
    assert_true(st[SPECIES_ICE].max_z > 8000.0);
    /* snow in the upper cloud */
    assert_true(st[SPECIES_SNOW].centroid[2] > 7000.0);
    /* rain: reaches the ground, mostly below the 1.5 km cloud base, nothing above 3.5 km */
    double rain = st[SPECIES_RAIN].sum;
    assert_true(sum_between(v, SPECIES_RAIN, 0.0, 1500.0) > 0.5 * rain);
    assert_true(sum_between(v, SPECIES_RAIN, 3500.0, INFINITY) == 0.0);
    assert_true(st[SPECIES_RAIN].lowest < 600.0);
    /* graupel at mid levels */
    double graupel = st[SPECIES_GRAUPEL].sum;
    assert_true(sum_between(v, SPECIES_GRAUPEL, 4000.0, 9000.0) > 0.99 * graupel);
    assert_true(st[SPECIES_GRAUPEL].max_z > 5000.0 && st[SPECIES_GRAUPEL].max_z < 8000.0);
    /* graupel sits in the core: its centroid is near the rain shaft's */
    double dx = st[SPECIES_GRAUPEL].centroid[0] - st[SPECIES_RAIN].centroid[0];
    double dy = st[SPECIES_GRAUPEL].centroid[1] - st[SPECIES_RAIN].centroid[1];
    assert_true(hypot(dx, dy) < 0.1 * v->grid.n[0] * v->grid.spacing[0]);
    /* the anvil spreads much wider than the tower */
    int tower = cloud_columns_at(v, 5000.0);
    assert_true(tower > 0);
    assert_true(anvil_columns(v) > 3 * tower);
}

static void test_storm_species(void **state)
{
    struct synth_desc d = storm_desc(100, 100, 50, 0.5, 1);
    struct field_volume v;
    assert_true(synth_storm_fields(&d, &v));
    check_storm_species(&v);
    field_volume_finish(&v);

    const double times[] = {0.3, 0.6, 0.9};
    for (unsigned s = 0; s < 3; s++) {
        d = storm_desc(80, 80, 40, times[s], s + 2);
        assert_true(synth_storm_fields(&d, &v));
        check_storm_species(&v);
        field_volume_finish(&v);
    }
}

/* Isabel-like box: 2000 x 2000 km, 20 km high.  Heights stay physical, the storm scales
 * horizontally: it covers about the same fraction of the box as in the default scene. */
static void test_storm_large_extent(void **state)
{
    struct synth_desc d = storm_desc(100, 100, 50, 0.5, 1);
    struct field_volume small, large;
    assert_true(synth_storm_fields(&d, &small));
    d.extent_m[0] = d.extent_m[1] = 2000e3;
    d.extent_m[2] = 20e3;
    assert_true(synth_storm_fields(&d, &large));
    check_storm_species(&large);
    double ratio = (double)anvil_columns(&large) / anvil_columns(&small);
    assert_true(ratio > 0.5 && ratio < 2.0);
    /* nothing near the 20 km lid */
    assert_true(sum_between(&large, SPECIES_ICE, 15000.0, INFINITY) == 0.0);
    assert_true(sum_between(&large, SPECIES_CLOUD, 15000.0, INFINITY) == 0.0);
    field_volume_finish(&small);
    field_volume_finish(&large);
}

static void test_storm_grows_and_drifts(void **state)
{
    struct synth_desc d = storm_desc(100, 100, 50, 0.0, 5);
    struct field_volume v0, v1;
    assert_true(synth_storm_fields(&d, &v0));
    d.time = 1.0;
    assert_true(synth_storm_fields(&d, &v1));

    int a0 = anvil_columns(&v0), a1 = anvil_columns(&v1);
    assert_true(a1 > 2 * a0);
    assert_true(total_condensate(&v1) > 1.5 * total_condensate(&v0));

    /* the tower's top rises by about 3 km */
    struct species_stats c0, c1, r0, r1;
    stats(&v0, SPECIES_CLOUD, &c0);
    stats(&v1, SPECIES_CLOUD, &c1);
    assert_true(c1.highest - c0.highest > 2000.0);

    /* the rain shaft (under the core only) moves a few km */
    stats(&v0, SPECIES_RAIN, &r0);
    stats(&v1, SPECIES_RAIN, &r1);
    double move = hypot(r1.centroid[0] - r0.centroid[0], r1.centroid[1] - r0.centroid[1]);
    assert_true(move > 3000.0 && move < 10000.0);

    field_volume_finish(&v0);
    field_volume_finish(&v1);
}

static void test_storm_tiny_grids(void **state)
{
    int sizes[][3] = {{1, 1, 1}, {3, 2, 1}, {1, 1, 100}, {2, 500, 3}};
    for (size_t s = 0; s < sizeof(sizes) / sizeof(sizes[0]); s++) {
        struct synth_desc d = storm_desc(sizes[s][0], sizes[s][1], sizes[s][2], 1.0, 3);
        struct field_volume v;
        assert_true(synth_storm_fields(&d, &v));
        struct species_stats st;
        for (int f = 0; f < SPECIES_COUNT; f++)
            stats(&v, f, &st); /* finite, non-negative */
        field_volume_finish(&v);
    }
}

static void expect_refused(const struct synth_desc *d)
{
    unsigned errors = log_error_count();
    struct field_volume v;
    struct ext_volume e;
    if (d->kind == SYNTH_STORM) {
        assert_false(synth_storm_fields(d, &v));
        assert_null(v.q[0]);
        assert_int_equal(log_error_count(), errors + 1);
        errors = log_error_count();
    }
    assert_false(synth_extinction(d, NULL, &e));
    assert_null(e.beta);
    assert_int_equal(log_error_count(), errors + 1);
}

static void test_bad_descriptions(void **state)
{
    int bad_sizes[][3] = {{501, 10, 10}, {10, 501, 10}, {10, 10, 101}, {0, 10, 10},
                          {10, -1, 10}, {100000, 100000, 100000}};
    for (size_t s = 0; s < sizeof(bad_sizes) / sizeof(bad_sizes[0]); s++) {
        for (int kind = SYNTH_STORM; kind <= SYNTH_VOXEL; kind++) {
            struct synth_desc d = storm_desc(bad_sizes[s][0], bad_sizes[s][1],
                                             bad_sizes[s][2], 0.5, 1);
            d.kind = (enum synth_kind)kind;
            expect_refused(&d);
        }
    }
    assert_true(strstr(log_last_error(), "100000x100000x100000") != NULL);

    struct synth_desc d = storm_desc(8, 8, 8, 0.5, 1);
    d.extent_m[2] = 0.0;
    expect_refused(&d);
    d = storm_desc(8, 8, 8, 0.5, 1);
    d.extent_m[0] = NAN;
    expect_refused(&d);
    d = storm_desc(8, 8, 8, 1.5, 1);
    expect_refused(&d);
    d = storm_desc(8, 8, 8, NAN, 1);
    expect_refused(&d);
    d = storm_desc(8, 8, 8, -0.1, 1);
    expect_refused(&d);
    d = storm_desc(8, 8, 8, 0.5, 1);
    d.kind = SYNTH_SLAB;
    d.tau = -1.0;
    expect_refused(&d);
    d.tau = INFINITY;
    expect_refused(&d);
    d.kind = SYNTH_SPHERE;
    expect_refused(&d);
    /* mass ratios exist only for the storm */
    unsigned errors = log_error_count();
    struct field_volume v;
    assert_false(synth_storm_fields(&d, &v));
    assert_int_equal(log_error_count(), errors + 1);
}

static struct synth_desc test_desc(enum synth_kind kind, int nx, int ny, int nz, double ex,
                                   double ey, double ez, double tau, bool ice)
{
    struct synth_desc d;
    synth_desc_defaults(&d);
    d.kind = kind;
    d.n[0] = nx;
    d.n[1] = ny;
    d.n[2] = nz;
    d.extent_m[0] = ex;
    d.extent_m[1] = ey;
    d.extent_m[2] = ez;
    d.tau = tau;
    d.ice_phase = ice;
    return d;
}

static double column_tau(const struct ext_volume *v, int i, int j, int channel)
{
    const struct grid3 *g = &v->grid;
    double s = 0.0;
    for (int k = 0; k < g->n[2]; k++)
        s += (double)v->beta[2 * grid3_index(g, i, j, k) + channel] * g->spacing[2];
    return s;
}

static void test_slab(void **state)
{
    for (int ice = 0; ice < 2; ice++) {
        struct synth_desc d = test_desc(SYNTH_SLAB, 7, 5, 13, 3000.0, 2000.0, 5000.0, 3.7,
                                        ice);
        struct ext_volume v;
        assert_true(synth_extinction(&d, NULL, &v));
        int on = ice ? 0 : 1, off = 1 - on;
        for (int j = 0; j < 5; j++) {
            for (int i = 0; i < 7; i++) {
                assert_true(fabs(column_tau(&v, i, j, on) - 3.7) < 1e-6 * 3.7);
                assert_true(column_tau(&v, i, j, off) == 0.0);
            }
        }
        /* horizontally, optical depth is tau scaled by the path length */
        double row = 0.0;
        for (int i = 0; i < 7; i++)
            row += (double)v.beta[2 * grid3_index(&v.grid, i, 2, 6) + on] * v.grid.spacing[0];
        assert_true(fabs(row - 3.7 * 3000.0 / 5000.0) < 1e-6 * row);
        ext_volume_finish(&v);
    }
    /* extreme aspect ratio and very thick */
    struct synth_desc d = test_desc(SYNTH_SLAB, 500, 1, 1, 1e6, 10.0, 0.5, 1e4, false);
    struct ext_volume v;
    assert_true(synth_extinction(&d, NULL, &v));
    assert_true(fabs(column_tau(&v, 499, 0, 1) - 1e4) < 1e-6 * 1e4);
    ext_volume_finish(&v);
}

static void check_sphere(int n0, int n1, int n2, double ex, double ey, double ez, double tau)
{
    struct synth_desc d = test_desc(SYNTH_SPHERE, n0, n1, n2, ex, ey, ez, tau, false);
    struct ext_volume v;
    assert_true(synth_extinction(&d, NULL, &v));
    const struct grid3 *g = &v.grid;
    double r = 0.5 * fmin(ex, fmin(ey, ez));
    double beta = tau / (2.0 * r);

    /* through the centre: tau, within a voxel's worth at each end */
    double t = column_tau(&v, n0 / 2, n1 / 2, 1);
    assert_true(fabs(t - tau) <= 2.0 * beta * g->spacing[2] + 1e-9);
    assert_true(column_tau(&v, n0 / 2, n1 / 2, 0) == 0.0);

    /* no voxel above beta; voxels wholly outside the ball are exactly empty, wholly inside
     * exactly beta; the volume integral is the ball's */
    int partial = 0;
    double integral = 0.0, half_diag = 0.5 * sqrt(g->spacing[0] * g->spacing[0] +
                                                  g->spacing[1] * g->spacing[1] +
                                                  g->spacing[2] * g->spacing[2]);
    for (int k = 0; k < n2; k++) {
        for (int j = 0; j < n1; j++) {
            for (int i = 0; i < n0; i++) {
                double b = v.beta[2 * grid3_index(g, i, j, k) + 1];
                double x = (i + 0.5) * g->spacing[0] - 0.5 * ex;
                double y = (j + 0.5) * g->spacing[1] - 0.5 * ey;
                double z = (k + 0.5) * g->spacing[2] - 0.5 * ez;
                double dist = sqrt(x * x + y * y + z * z);
                assert_true(b >= 0.0 && b <= beta * (1 + 1e-6));
                if (dist - half_diag >= r)
                    assert_true(b == 0.0);
                if (dist + half_diag <= r)
                    assert_true(fabs(b - beta) <= 1e-6 * beta);
                partial += b > 0.0 && b < 0.99 * beta;
                integral += b * g->spacing[0] * g->spacing[1] * g->spacing[2];
            }
        }
    }
    double ball = beta * 4.0 / 3.0 * 3.14159265358979323846 * r * r * r;
    assert_true(fabs(integral - ball) < 0.01 * ball);
    /* surface voxels hold the fraction inside (supersampled), not all or nothing */
    assert_true(partial > 0);
    /* corners and a column beside the ball see nothing */
    assert_true(column_tau(&v, 0, 0, 1) == 0.0);
    assert_true(v.beta[2 * grid3_index(g, n0 - 1, n1 - 1, n2 - 1) + 1] == 0.0);
    ext_volume_finish(&v);
}

static void test_sphere(void **state)
{
    check_sphere(64, 64, 64, 10e3, 10e3, 10e3, 5.0);
    check_sphere(63, 63, 63, 10e3, 10e3, 10e3, 5.0);
    check_sphere(81, 41, 33, 20e3, 10e3, 8e3, 40.0); /* anisotropic box and voxels */
}

static void test_empty(void **state)
{
    struct synth_desc d = test_desc(SYNTH_EMPTY, 5, 6, 7, 1e3, 2e3, 3e3, 10.0, true);
    struct ext_volume v;
    assert_true(synth_extinction(&d, NULL, &v));
    for (size_t i = 0; i < 2 * grid3_count(&v.grid); i++)
        assert_true(v.beta[i] == 0.0f);
    assert_true(ext_volume_max_beta(&v) == 0.0);
    ext_volume_finish(&v);
}

static void test_single_voxel(void **state)
{
    int sizes[][3] = {{9, 8, 7}, {1, 1, 1}, {2, 2, 2}};
    for (size_t s = 0; s < 3; s++) {
        for (int ice = 0; ice < 2; ice++) {
            struct synth_desc d = test_desc(SYNTH_VOXEL, sizes[s][0], sizes[s][1],
                                            sizes[s][2], 9e3, 8e3, 3.5e3, 2.5, ice);
            struct ext_volume v;
            assert_true(synth_extinction(&d, NULL, &v));
            const struct grid3 *g = &v.grid;
            size_t want = 2 * grid3_index(g, g->n[0] / 2, g->n[1] / 2, g->n[2] / 2) +
                          (ice ? 0 : 1);
            int nonzero = 0;
            for (size_t i = 0; i < 2 * grid3_count(g); i++) {
                if (v.beta[i] != 0.0f) {
                    nonzero++;
                    assert_int_equal(i, want);
                }
            }
            assert_int_equal(nonzero, 1);
            double t = column_tau(&v, g->n[0] / 2, g->n[1] / 2, ice ? 0 : 1);
            assert_true(fabs(t - 2.5) < 1e-6 * 2.5);
            ext_volume_finish(&v);
        }
    }
}

static void test_storm_extinction(void **state)
{
    struct synth_desc d = storm_desc(48, 48, 32, 0.7, 9);
    struct ext_volume v;
    assert_true(synth_extinction(&d, NULL, &v));
    double ice = 0.0, water = 0.0;
    for (size_t i = 0; i < grid3_count(&v.grid); i++) {
        assert_true(isfinite(v.beta[2 * i]) && v.beta[2 * i] >= 0.0f);
        assert_true(isfinite(v.beta[2 * i + 1]) && v.beta[2 * i + 1] >= 0.0f);
        ice = fmax(ice, v.beta[2 * i]);
        water = fmax(water, v.beta[2 * i + 1]);
    }
    /* cloud droplets (0.01 mm) dominate: 3 rho q / (2 rho_w R) ~ 0.1-0.3 /m at 2 g/kg;
     * the ice phase (mm-sized particles) is orders of magnitude thinner */
    assert_true(water > 0.02 && water < 1.0);
    assert_true(ice > 1e-5 && ice < water);
    /* the converted storm equals the fields converted by hand */
    struct field_volume f;
    assert_true(synth_storm_fields(&d, &f));
    struct optics_params op;
    optics_params_defaults(&op);
    struct species_select sel;
    species_select_defaults(&sel);
    struct ext_volume w;
    assert_true(ext_volume_from_fields(&f, &op, &sel, &w));
    assert_memory_equal(v.beta, w.beta, 2 * grid3_count(&v.grid) * sizeof(float));
    field_volume_finish(&f);
    ext_volume_finish(&w);
    ext_volume_finish(&v);
}

/* The largest storm, on one thread (the budget is ~20 s; it takes a few). */
static void test_storm_full_size(void **state)
{
    struct synth_desc d = storm_desc(SYNTH_MAX_NXY, SYNTH_MAX_NXY, SYNTH_MAX_NZ, 1.0, 1);
    struct field_volume v;
    double t0 = time_now_ms();
    assert_true(synth_storm_fields_threads(&d, 1, &v));
    double ms = time_now_ms() - t0;
    printf("synth: 500x500x100 storm in %.0f ms on one thread (%zu MiB of mass ratios)\n", ms,
           (grid3_count(&v.grid) * SPECIES_COUNT * sizeof(float)) >> 20);
    check_storm_species(&v);
    field_volume_finish(&v);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_storm_deterministic),
        cmocka_unit_test(test_storm_species),
        cmocka_unit_test(test_storm_large_extent),
        cmocka_unit_test(test_storm_grows_and_drifts),
        cmocka_unit_test(test_storm_tiny_grids),
        cmocka_unit_test(test_bad_descriptions),
        cmocka_unit_test(test_slab),
        cmocka_unit_test(test_sphere),
        cmocka_unit_test(test_empty),
        cmocka_unit_test(test_single_voxel),
        cmocka_unit_test(test_storm_extinction),
        cmocka_unit_test(test_storm_full_size),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
