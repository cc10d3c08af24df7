/*
 * light: the CPU deep light map.  Grid frame and texture mapping, transport against closed
 * forms (slab, single voxel), the hard cases (empty, axis-aligned and grazing sun, optically
 * very thick), invariants (shadow monotone, forward >= shadow only, [0, 1]), the silver lining,
 * exact slices (no dependence on the slice count), the two-stream column pass of multiple
 * scattering (energy, slice count, an independent ODE solution, extreme depths, whole maps),
 * compression error bounds, and rebuild-on-change.
 */
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "data/synth.h"
#include "data/volume.h"
#include "light/light.h"
#include "optics/optics.h"
#include "testutil.h"

#define PI 3.14159265358979323846

/* ---- helpers ----------------------------------------------------------------------------- */

static void make_volume(struct ext_volume *v, int nx, int ny, int nz, double sx, double sy,
                        double sz)
{
    struct grid3 g = {.n = {nx, ny, nz}, .spacing = {sx, sy, sz}, .origin = {0.0, 0.0, 0.0}};
    assert_true(ext_volume_init(v, &g));
}

static void set_beta(struct ext_volume *v, int i, int j, int k, float ice, float water)
{
    size_t idx = grid3_index(&v->grid, i, j, k);
    v->beta[2 * idx] = ice;
    v->beta[2 * idx + 1] = water;
}

static void fill_uniform(struct ext_volume *v, float ice, float water)
{
    size_t n = grid3_count(&v->grid);
    for (size_t i = 0; i < n; i++) {
        v->beta[2 * i] = ice;
        v->beta[2 * i + 1] = water;
    }
}

/* A homogeneous ball of optical depth TAU along its diameter, radius 0.4 of the smallest box
 * side, centred in the box; voxel centres inside get the full extinction (water phase). */
static double fill_sphere(struct ext_volume *v, double tau)
{
    const struct grid3 *g = &v->grid;
    double ext[3], c[3];
    for (int a = 0; a < 3; a++) {
        ext[a] = g->n[a] * g->spacing[a];
        c[a] = 0.5 * ext[a];
    }
    double r = 0.4 * fmin(ext[0], fmin(ext[1], ext[2]));
    float beta = (float)(tau / (2.0 * r));
    for (int k = 0; k < g->n[2]; k++)
        for (int j = 0; j < g->n[1]; j++)
            for (int i = 0; i < g->n[0]; i++) {
                double x = (i + 0.5) * g->spacing[0] - c[0];
                double y = (j + 0.5) * g->spacing[1] - c[1];
                double z = (k + 0.5) * g->spacing[2] - c[2];
                if (x * x + y * y + z * z <= r * r)
                    set_beta(v, i, j, k, 0.0f, beta);
            }
    return r;
}

static uint32_t rng_state = 12345u;
static double rnd(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 17;
    rng_state ^= rng_state << 5;
    return (rng_state >> 8) * (1.0 / 16777216.0);
}

/* Blobby random medium of both phases, up to BMAX per metre. */
static void fill_random(struct ext_volume *v, float bmax)
{
    size_t n = grid3_count(&v->grid);
    for (size_t i = 0; i < n; i++) {
        double a = rnd(), b = rnd();
        v->beta[2 * i] = a > 0.5 ? (float)(bmax * (a - 0.5) * 2.0) : 0.0f;
        v->beta[2 * i + 1] = b > 0.6 ? (float)(bmax * (b - 0.6) * 2.5) : 0.0f;
    }
}

static void realistic_settings(struct light_settings *s, int n)
{
    struct optics_params op;
    optics_params_defaults(&op);
    light_settings_defaults(s);
    light_settings_set_optics(s, &op, 20.0);
    s->resolution[0] = s->resolution[1] = s->resolution[2] = n;
}

static void assert_all_in_unit(const struct light_map *m)
{
    size_t n = (size_t)m->grid.n[0] * m->grid.n[1] * m->grid.n[2];
    for (size_t i = 0; i < n; i++) {
        float l = m->light[i];
        if (!(isfinite(l) && l >= 0.0f && l <= 1.0f))
            fail_msg("node %zu holds %g", i, (double)l);
    }
}

static float map_min(const struct light_map *m)
{
    size_t n = (size_t)m->grid.n[0] * m->grid.n[1] * m->grid.n[2];
    float lo = 1.0f;
    for (size_t i = 0; i < n; i++)
        lo = fminf(lo, m->light[i]);
    return lo;
}

static bool inside_box(const struct grid3 *g, const double p[3], double margin)
{
    for (int a = 0; a < 3; a++) {
        double lo = g->origin[a], hi = lo + g->n[a] * g->spacing[a];
        if (p[a] < lo + margin || p[a] > hi - margin)
            return false;
    }
    return true;
}

/* ---- sun direction and grid ---------------------------------------------------------------- */

static void test_sun_direction(void **state)
{
    double d[3];
    light_sun_direction(0.0, 90.0, d);
    assert_true(d[0] == 0.0 && d[1] == 0.0 && d[2] == 1.0);
    light_sun_direction(90.0, 0.0, d);
    assert_true(d[0] == 1.0 && d[1] == 0.0 && d[2] == 0.0);
    light_sun_direction(180.0, 0.0, d);
    assert_true(d[0] == 0.0 && d[1] == -1.0 && d[2] == 0.0);
    light_sun_direction(-90.0, 0.0, d);
    assert_true(d[0] == -1.0 && d[1] == 0.0 && d[2] == 0.0);
    light_sun_direction(135.0, 30.0, d); /* south-east, 30 degrees up */
    assert_float_equal(d[0], sqrt(0.5) * cos(PI / 6), 1e-12);
    assert_float_equal(d[1], -sqrt(0.5) * cos(PI / 6), 1e-12);
    assert_float_equal(d[2], 0.5, 1e-12);
}

/* What every grid must do: nodes map to texel centres, the float32 frame the transport uses
 * agrees with the double one, and every box corner maps inside the texel-centre range. */
static void check_grid_mapping(const struct light_grid *g, const struct grid3 *box)
{
    const int *n = g->n;
    for (int t = 0; t < 20; t++) {
        int i = (int)(rnd() * n[0]), j = (int)(rnd() * n[1]), k = (int)(rnd() * n[2]);
        double p[3], tex[3];
        light_grid_node_world(g, i, j, k, p);
        light_grid_world_to_tex(g, p, tex);
        assert_float_equal(tex[0], (i + 0.5) / n[0], 2e-6);
        assert_float_equal(tex[1], (j + 0.5) / n[1], 2e-6);
        assert_float_equal(tex[2], (k + 0.5) / n[2], 2e-6);
        for (int a = 0; a < 3; a++) {
            double pf =
                g->origin[a] + (double)i * g->du[a] + (double)j * g->dv[a] + (double)k * g->dw[a];
            assert_float_equal(pf, p[a], 1e-2);
        }
    }
    for (int c = 0; c < 8; c++) {
        double p[3], tex[3];
        for (int a = 0; a < 3; a++)
            p[a] = box->origin[a] + ((c >> a) & 1) * box->n[a] * box->spacing[a];
        light_grid_world_to_tex(g, p, tex);
        for (int a = 0; a < 3; a++) {
            assert_true(tex[a] >= 0.5 / n[a] - 1e-6);
            assert_true(tex[a] <= 1.0 - 0.5 / n[a] + 1e-6);
        }
    }
}

static void test_grid_frame_and_mapping(void **state)
{
    struct grid3 box = {
        .n = {20, 30, 10}, .spacing = {200.0, 100.0, 50.0}, .origin = {-1000.0, 500.0, 0.0}};
    const double suns[][3] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},      {0, -1, 0},  {0, 0, 1},
                              {0, 0, -1}, {1, 1, 1},  {0.3, -2, 0.1}, {0, 0.2, 1}, {0, 0, 0}};
    for (size_t s = 0; s < sizeof suns / sizeof suns[0]; s++) {
        double sun[3];
        if (s + 1 == sizeof suns / sizeof suns[0])
            light_sun_direction(33.0, 1.0, sun); /* grazing */
        else
            memcpy(sun, suns[s], sizeof sun);
        struct light_grid g;
        const int n[3] = {9, 7, 11};
        assert_true(light_grid_init(&g, sun, &box, n, LIGHT_GRID_UPRIGHT));
        /* Orthonormal, right-handed, w = -sun. */
        double uu = 0, vv = 0, ww = 0, uv = 0, uw = 0, vw = 0, sl = 0;
        for (int a = 0; a < 3; a++) {
            uu += g.u[a] * g.u[a], vv += g.v[a] * g.v[a], ww += g.w[a] * g.w[a];
            uv += g.u[a] * g.v[a], uw += g.u[a] * g.w[a], vw += g.v[a] * g.w[a];
            sl += sun[a] * sun[a];
        }
        assert_float_equal(uu, 1.0, 1e-12);
        assert_float_equal(vv, 1.0, 1e-12);
        assert_float_equal(ww, 1.0, 1e-12);
        assert_float_equal(uv, 0.0, 1e-12);
        assert_float_equal(uw, 0.0, 1e-12);
        assert_float_equal(vw, 0.0, 1e-12);
        double cx[3] = {g.u[1] * g.v[2] - g.u[2] * g.v[1], g.u[2] * g.v[0] - g.u[0] * g.v[2],
                        g.u[0] * g.v[1] - g.u[1] * g.v[0]};
        for (int a = 0; a < 3; a++) {
            assert_float_equal(cx[a], g.w[a], 1e-12);
            assert_float_equal(g.w[a], -sun[a] / sqrt(sl), 1e-12);
            assert_true(isfinite(g.lo[a]) && g.step[a] > 0.0);
        }
        /* Nodes map to texel centres; every box corner maps inside the texel-centre range. */
        check_grid_mapping(&g, &box);
    }
}

static void test_grid_rejects_bad_input(void **state)
{
    struct grid3 box = {.n = {4, 4, 4}, .spacing = {1, 1, 1}};
    struct light_grid g;
    const int n[3] = {8, 8, 8}, bad[3] = {8, 1, 8};
    const double zero[3] = {0, 0, 0}, nan3[3] = {NAN, 0, 1}, up[3] = {0, 0, 1};
    unsigned errors = log_error_count();
    assert_false(light_grid_init(&g, zero, &box, n, LIGHT_GRID_AUTO));
    assert_false(light_grid_init(&g, nan3, &box, n, LIGHT_GRID_AUTO));
    assert_false(light_grid_init(&g, up, &box, bad, LIGHT_GRID_AUTO));
    struct grid3 flat = box;
    flat.spacing[2] = 0.0;
    assert_false(light_grid_init(&g, up, &flat, n, LIGHT_GRID_AUTO));
    assert_int_equal(log_error_count(), errors + 4);
}

static void test_peripheral_offset(void **state)
{
    assert_float_equal(light_peripheral_offset(20.0, 100.0), 100.0 * tan(7.5 * PI / 180.0),
                       1e-12);
    assert_float_equal(light_peripheral_offset(0.0, 100.0), 0.0, 0.0);
}

/* ---- transport ----------------------------------------------------------------------------- */

static void test_beta_sampling(void **state)
{
    struct ext_volume v;
    make_volume(&v, 4, 4, 4, 10.0, 10.0, 10.0);
    set_beta(&v, 1, 1, 1, 2.0f, 4.0f);
    float b[2];
    light_sample_beta(&v, (const float[3]){15.0f, 15.0f, 15.0f}, b); /* the voxel centre */
    assert_float_equal(b[0], 2.0f, 1e-6);
    assert_float_equal(b[1], 4.0f, 1e-6);
    light_sample_beta(&v, (const float[3]){20.0f, 15.0f, 15.0f}, b); /* halfway to the next */
    assert_float_equal(b[1], 2.0f, 1e-6);
    light_sample_beta(&v, (const float[3]){20.0f, 20.0f, 20.0f}, b);
    assert_float_equal(b[1], 0.5f, 1e-6);
    /* Clamp to edge inside the box, zero outside. */
    fill_uniform(&v, 0.0f, 3.0f);
    light_sample_beta(&v, (const float[3]){0.0f, 1.0f, 39.0f}, b);
    assert_float_equal(b[1], 3.0f, 1e-6);
    light_sample_beta(&v, (const float[3]){40.0f, 40.0f, 40.0f}, b); /* the far corner */
    assert_float_equal(b[1], 3.0f, 1e-6);
    light_sample_beta(&v, (const float[3]){-0.01f, 20.0f, 20.0f}, b);
    assert_true(b[0] == 0.0f && b[1] == 0.0f);
    light_sample_beta(&v, (const float[3]){20.0f, 20.0f, 40.5f}, b);
    assert_true(b[1] == 0.0f);
    light_sample_beta(&v, (const float[3]){NAN, 20.0f, 20.0f}, b);
    assert_true(b[1] == 0.0f);
    ext_volume_finish(&v);
}

static void test_empty_volume_all_ones(void **state)
{
    struct ext_volume v;
    make_volume(&v, 8, 8, 8, 100.0, 100.0, 100.0);
    struct light_settings s;
    realistic_settings(&s, 16);
    struct light_map m = {0};
    double suns[3][3] = {{0, 0, 1}, {1, 0, 0}, {0.4, -0.3, 0.8}};
    for (int t = 0; t < 3; t++) {
        assert_true(light_map_build(&v, suns[t], &s, &m));
        size_t n = (size_t)16 * 16 * 16;
        for (size_t i = 0; i < n; i++)
            assert_true(m.light[i] == 1.0f);
    }
    light_map_finish(&m);
    light_map_finish(&m); /* finished twice and NULL are fine */
    light_map_finish(NULL);
    ext_volume_finish(&v);
}

/* Slab lit from straight above, nodes aligned with the slab: L_k = exp(-beta k dz) exactly. */
static void test_slab_closed_form_overhead(void **state)
{
    struct ext_volume v;
    make_volume(&v, 16, 16, 20, 200.0, 200.0, 50.0); /* 1 km thick */
    const float beta = 0.005f;                       /* tau = 5 through the slab */
    fill_uniform(&v, 0.0f, beta);
    struct light_settings s;
    light_settings_defaults(&s);
    s.forward = false;
    s.resolution[0] = s.resolution[1] = 8;
    s.resolution[2] = 21; /* dz = 50 m */
    struct light_map m = {0};
    assert_true(light_map_build(&v, (const double[3]){0, 0, 1}, &s, &m));
    assert_float_equal(m.grid.step[2], 50.0, 1e-9);
    for (int k = 0; k < 21; k++) {
        double expect = exp(-0.005 * 50.0 * k);
        for (int j = 0; j < 8; j++)
            for (int i = 0; i < 8; i++)
                assert_float_equal(light_map_node(&m, i, j, k), expect, 2e-6 + 1e-5 * expect);
    }
    light_map_finish(&m);
    ext_volume_finish(&v);
}

/* Slab lit at 60 degrees elevation: light at depth d is exp(-beta d) up to one light step of
 * path, d = (H - z) / sin(elevation). */
static void test_slab_closed_form_oblique(void **state)
{
    struct ext_volume v;
    make_volume(&v, 64, 64, 20, 200.0, 200.0, 50.0);
    const double beta = 0.004, H = 1000.0;
    fill_uniform(&v, 0.0f, (float)beta);
    struct light_settings s;
    light_settings_defaults(&s);
    s.forward = false;
    s.resolution[0] = s.resolution[1] = 48;
    s.resolution[2] = 64;
    double sun[3];
    light_sun_direction(30.0, 60.0, sun);
    struct light_map m = {0};
    assert_true(light_map_build(&v, sun, &s, &m));
    double el = 60.0 * PI / 180.0, dw = m.grid.step[2];
    int checked = 0;
    for (int k = 0; k < 64; k++)
        for (int j = 0; j < 48; j++)
            for (int i = 0; i < 48; i++) {
                double p[3];
                light_grid_node_world(&m.grid, i, j, k, p);
                if (!inside_box(&v.grid, p, 1.0))
                    continue;
                double d = (H - p[2]) / sin(el);
                double top[3];
                for (int a = 0; a < 3; a++)
                    top[a] = p[a] + d * sun[a];
                if (!inside_box(&v.grid, (double[3]){top[0], top[1], 0.5 * H}, 1.0))
                    continue; /* the sunward ray leaves through a side wall */
                float l = light_map_node(&m, i, j, k);
                assert_true(l >= exp(-beta * (d + dw)) - 1e-6);
                assert_true(l <= exp(-beta * fmax(d - dw, 0.0)) + 1e-6);
                checked++;
            }
    assert_true(checked > 1000);
    light_map_finish(&m);
    ext_volume_finish(&v);
}

/* One voxel: shadow strictly behind it (the four light columns its trilinear footprint
 * touches, below its centre), exactly exp(-tau/4) there, exactly 1 everywhere else. */
static void test_single_voxel(void **state)
{
    struct ext_volume v;
    make_volume(&v, 9, 9, 9, 100.0, 100.0, 100.0);
    const double tau = 2.0;
    set_beta(&v, 4, 4, 4, 0.0f, (float)(tau / 100.0));
    for (int fwd = 0; fwd < 2; fwd++) {
        struct light_settings s;
        realistic_settings(&s, 10); /* nodes on voxel faces, 100 m apart */
        s.forward = fwd;
        struct light_map m = {0};
        assert_true(light_map_build(&v, (const double[3]){0, 0, 1}, &s, &m));
        int shadowed = 0;
        for (int k = 0; k < 10; k++)
            for (int j = 0; j < 10; j++)
                for (int i = 0; i < 10; i++) {
                    double p[3];
                    light_grid_node_world(&m.grid, i, j, k, p);
                    bool behind =
                        fabs(p[0] - 450.0) < 100.0 && fabs(p[1] - 450.0) < 100.0 && p[2] < 450.0;
                    float l = light_map_node(&m, i, j, k);
                    if (!behind) {
                        assert_true(l == 1.0f);
                        continue;
                    }
                    shadowed++;
                    double t = exp(-0.25 * tau);
                    if (fwd)
                        assert_true(l > t + 1e-3 && l < 1.0f);
                    else
                        assert_float_equal(l, t, 1e-6);
                }
        assert_int_equal(shadowed, 4 * 5);
        light_map_finish(&m);
    }
    ext_volume_finish(&v);
}

/* Sun exactly along each axis (also from below) and at 1 degree elevation: finite, [0, 1],
 * and a real shadow. */
static void test_axis_and_grazing_sun(void **state)
{
    struct ext_volume v;
    make_volume(&v, 24, 20, 16, 300.0, 300.0, 100.0);
    fill_sphere(&v, 8.0);
    struct light_settings s;
    realistic_settings(&s, 24);
    double suns[8][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    light_sun_direction(0.0, 1.0, suns[6]);
    light_sun_direction(247.0, 1.0, suns[7]);
    struct light_map m = {0};
    for (int t = 0; t < 8; t++) {
        assert_true(light_map_build(&v, suns[t], &s, &m));
        assert_all_in_unit(&m);
        assert_true(map_min(&m) < 0.5f);
    }
    light_map_finish(&m);
    ext_volume_finish(&v);
}

/* Whole column tau 1e4, per light sample tau ~ 300: no NaN/Inf, within [0, 1]; shadow only
 * reaches 0; forward scattering keeps light finite and monotone along the light too. */
static void test_very_thick(void **state)
{
    struct ext_volume v;
    make_volume(&v, 8, 8, 32, 100.0, 100.0, 31.25); /* 1 km */
    fill_uniform(&v, 4.0f, 6.0f);                   /* beta 10 /m: tau 1e4 */
    struct light_settings s;
    realistic_settings(&s, 8);
    s.resolution[2] = 33; /* dz 31.25 m: tau 312.5 per sample */
    double suns[2][3] = {{0, 0, 1}, {0.5, 0.2, 0.7}};
    for (int t = 0; t < 2; t++) {
        for (int fwd = 0; fwd < 2; fwd++) {
            s.forward = fwd;
            struct light_map m = {0};
            assert_true(light_map_build(&v, suns[t], &s, &m));
            assert_all_in_unit(&m);
            if (t == 0 && !fwd) {
                for (int k = 1; k < 33; k++)
                    for (int c = 0; c < 64; c++) {
                        float a = m.light[c + 64 * (k - 1)], b = m.light[c + 64 * k];
                        assert_true(b <= a);
                    }
                assert_true(light_map_node(&m, 4, 4, 32) == 0.0f);
            }
            light_map_finish(&m);
        }
    }
    ext_volume_finish(&v);
}

/* Shadow only: never increases along the light, for a random medium and an oblique sun. */
static void test_shadow_monotone(void **state)
{
    struct ext_volume v;
    make_volume(&v, 24, 24, 24, 250.0, 250.0, 100.0);
    fill_random(&v, 0.01f);
    struct light_settings s;
    realistic_settings(&s, 32);
    s.forward = false;
    double sun[3];
    light_sun_direction(200.0, 35.0, sun);
    struct light_map m = {0};
    assert_true(light_map_build(&v, sun, &s, &m));
    assert_all_in_unit(&m);
    size_t plane = 32 * 32;
    for (int k = 1; k < 32; k++)
        for (size_t c = 0; c < plane; c++)
            assert_true(m.light[c + plane * k] <= m.light[c + plane * (k - 1)]);
    assert_true(map_min(&m) < 0.2f);
    light_map_finish(&m);
    ext_volume_finish(&v);
}

/* Forward scattering on is at least as bright as off, everywhere; strictly brighter inside the
 * medium (Nes Fig. 5.4: the low-albedo model is too dark inside). */
static void test_forward_at_least_shadow(void **state)
{
    struct ext_volume v;
    make_volume(&v, 24, 24, 24, 250.0, 250.0, 100.0);
    fill_random(&v, 0.01f);
    struct light_settings s;
    realistic_settings(&s, 32);
    double sun[3];
    light_sun_direction(120.0, 50.0, sun);
    struct light_map on = {0}, off = {0}, central = {0};
    assert_true(light_map_build(&v, sun, &s, &on));
    s.peripheral = false;
    assert_true(light_map_build(&v, sun, &s, &central));
    s.forward = false;
    assert_true(light_map_build(&v, sun, &s, &off));
    size_t n = (size_t)32 * 32 * 32, shadowed = 0, brighter = 0;
    for (size_t i = 0; i < n; i++) {
        assert_true(on.light[i] >= central.light[i]);
        assert_true(central.light[i] >= off.light[i]);
        if (off.light[i] < 0.9f) {
            shadowed++;
            brighter += on.light[i] > 1.2f * off.light[i];
        }
    }
    print_message("forward on > 1.2 x off at %zu of %zu shadowed nodes\n", brighter, shadowed);
    assert_true(shadowed > n / 4);
    assert_true(brighter > shadowed * 3 / 4);
    light_map_finish(&on);
    light_map_finish(&central);
    light_map_finish(&off);
    ext_volume_finish(&v);
}

/* Peripheral scattering carries light sideways into a shadow: behind an opaque column the
 * nodes near its edge get light from their lit neighbours, which central scattering cannot
 * give. */
static void test_peripheral_spreads_light(void **state)
{
    struct ext_volume v;
    make_volume(&v, 32, 32, 32, 100.0, 100.0, 100.0);
    for (int k = 8; k < 32; k++)
        for (int j = 0; j < 32; j++)
            for (int i = 0; i < 16; i++)
                set_beta(&v, i, j, k, 0.0f, 0.05f); /* tau 5 per voxel: opaque half space */
    struct light_settings s;
    realistic_settings(&s, 33);
    s.forward_angle_deg = 60.0; /* wide ring: offset 0.41 node per slice */
    struct light_map per = {0}, ctr = {0};
    assert_true(light_map_build(&v, (const double[3]){0, 0, 1}, &s, &per));
    s.peripheral = false;
    assert_true(light_map_build(&v, (const double[3]){0, 0, 1}, &s, &ctr));
    /* Sun overhead: u = y, v = x, node (i, j, k) at y = 100 i, x = 100 j, z = 3200 - 100 k.
     * Plane k = 24 is the block's bottom face, 2.4 km below its top; j = 15 is one node inside
     * the edge at x = 1600 m, j = 4 deep inside. */
    float edge_per = light_map_node(&per, 16, 15, 24), deep_per = light_map_node(&per, 16, 4, 24);
    float edge_ctr = light_map_node(&ctr, 16, 15, 24), deep_ctr = light_map_node(&ctr, 16, 4, 24);
    assert_true(edge_per > deep_per * 1.5f + 1e-6f);
    assert_true(edge_per > edge_ctr);
    assert_float_equal(edge_ctr, deep_ctr, 1e-6 + 1e-3 * deep_ctr);
    light_map_finish(&per);
    light_map_finish(&ctr);
    ext_volume_finish(&v);
}

/* Silver lining.  A dense sphere (tau 20 along its diameter) in front of the sun.  For an
 * observer behind it looking at the sun along -w, each light column sends
 * R = sum_s T(s -> observer) (1 - T_s) L_l(s)  (Nes eq. 5.18 with the phase constant near
 * psi = 0).  Through the centre the light map is dark where the sphere is thin to the
 * observer and vice versa, so R is small; near the rim both are moderate, so R peaks there:
 * the rim is brighter than the centre.  The cloud also shadows the ground below it. */
static void test_silver_lining(void **state)
{
    struct ext_volume v;
    make_volume(&v, 48, 48, 48, 100.0, 100.0, 100.0);
    double radius = fill_sphere(&v, 20.0);
    struct light_settings s;
    realistic_settings(&s, 49);
    struct light_map m = {0}, off = {0};
    assert_true(light_map_build(&v, (const double[3]){0, 0, 1}, &s, &m));
    s.forward = false;
    assert_true(light_map_build(&v, (const double[3]){0, 0, 1}, &s, &off));
    const int n = 49, jc = 24;
    double profile[49], exit_light[49];
    for (int i = 0; i < n; i++) {
        double tr = 1.0, r = 0.0;
        exit_light[i] = 1.0;
        for (int k = n - 1; k >= 1; k--) { /* from the observer's side back toward the sun */
            double pm[3];
            light_grid_node_world(&m.grid, i, jc, k - 0.5, pm);
            float b[2];
            light_sample_beta(&v, (const float[3]){(float)pm[0], (float)pm[1], (float)pm[2]}, b);
            double ts = exp(-(double)(b[0] + b[1]) * m.grid.step[2]);
            double l = 0.5 * (light_map_node(&m, i, jc, k - 1) + light_map_node(&m, i, jc, k));
            r += tr * (1.0 - ts) * l;
            tr *= ts;
        }
        profile[i] = r;
        /* Light leaving the sphere: the last node plane of the column inside the medium. */
        for (int k = 1; k < n; k++) {
            double pm[3];
            light_grid_node_world(&m.grid, i, jc, k - 0.5, pm);
            float b[2];
            light_sample_beta(&v, (const float[3]){(float)pm[0], (float)pm[1], (float)pm[2]}, b);
            if (b[1] > 0.0f)
                exit_light[i] = light_map_node(&m, i, jc, k);
        }
    }
    /* Node i sits at x = 100 i: the centre column is i = 24; the rim at 24 +- radius/100. */
    int best = 24;
    for (int i = 24; i < n; i++)
        if (profile[i] > profile[best])
            best = i;
    double rim_r = (best - 24) * 100.0;
    print_message("silver lining: centre R %.3g, peak R %.3g at %.0f m of radius %.0f m\n",
                  profile[24], profile[best], rim_r, radius);
    assert_true(rim_r >= 0.7 * radius && rim_r <= radius + 100.0);
    assert_true(profile[best] > 10.0 * profile[24]);
    assert_true(profile[n - 1] == 0.0); /* clear sky beside the sphere scatters nothing */
    /* The light that gets through: the rim passes more than the centre. */
    assert_true(exit_light[best] > 5.0 * exit_light[24]);
    /* Forward scattering lets light deeper in (Nes Fig. 5.4 is the "off" case). */
    assert_true(light_map_node(&m, 24, 24, 24) > 1.5f * light_map_node(&off, 24, 24, 24));
    /* Ground shadow: the bottom of the box below the sphere is dark, the far corner is lit. */
    float tex_c[3], tex_o[3];
    double pc[3] = {2400.0, 2400.0, 0.0}, po[3] = {50.0, 50.0, 0.0}, t[3];
    light_grid_world_to_tex(&m.grid, pc, t);
    for (int a = 0; a < 3; a++)
        tex_c[a] = (float)t[a];
    light_grid_world_to_tex(&m.grid, po, t);
    for (int a = 0; a < 3; a++)
        tex_o[a] = (float)t[a];
    assert_true(light_map_sample(&m, tex_c) < 0.1f);
    assert_true(light_map_sample(&m, tex_o) == 1.0f);
    light_map_finish(&m);
    light_map_finish(&off);
    ext_volume_finish(&v);
}

/* A flat, wide volume at low sun: a light slice is far longer than the light needs to cross
 * one voxel layer.  Automatic sub-steps follow a finely sub-stepped reference; one extinction
 * sample per slice does not. */
static void test_substeps_flat_volume(void **state)
{
    struct ext_volume v;
    make_volume(&v, 40, 40, 10, 2000.0, 2000.0, 200.0); /* 80 km x 80 km x 2 km */
    for (int k = 0; k < 10; k++)
        for (int j = 0; j < 40; j++)
            for (int i = 0; i < 40; i++)
                set_beta(&v, i, j, k, 0.0f, (k >= 2 && k <= 4) ? 1e-3f : 0.0f); /* a layer */
    struct light_settings s;
    light_settings_defaults(&s);
    s.forward = false;
    s.grid = LIGHT_GRID_UPRIGHT; /* planes across the light: the case that needs sub-steps */
    s.resolution[0] = s.resolution[1] = s.resolution[2] = 24;
    double sun[3];
    light_sun_direction(200.0, 20.0, sun);
    struct light_map ref = {0}, aut = {0}, one = {0}, two = {0};
    s.substeps = 128;
    assert_true(light_map_build(&v, sun, &s, &ref));
    s.substeps = 0;
    assert_true(light_map_build(&v, sun, &s, &aut));
    s.substeps = 1;
    assert_true(light_map_build(&v, sun, &s, &one));
    assert_int_equal(aut.substeps, light_auto_substeps(&aut.grid, &v.grid));
    assert_true(aut.substeps > 4);
    s.substeps = 2 * aut.substeps;
    assert_true(light_map_build(&v, sun, &s, &two));
    double err_auto = 0.0, err_one = 0.0, err_two = 0.0;
    size_t n = (size_t)24 * 24 * 24;
    for (size_t i = 0; i < n; i++) {
        err_auto = fmax(err_auto, fabs(aut.light[i] - ref.light[i]));
        err_one = fmax(err_one, fabs(one.light[i] - ref.light[i]));
        err_two = fmax(err_two, fabs(two.light[i] - ref.light[i]));
    }
    print_message("flat volume: max error with %d auto sub-steps %.3g, twice as many %.3g, one "
                  "sample per slice %.3g\n",
                  aut.substeps, err_auto, err_two, err_one);
    assert_true(err_auto < 0.25);
    assert_true(err_one > 3.0 * err_auto);
    assert_true(err_two < 0.6 * err_auto);
    /* Matching grids need one sample per slice. */
    struct light_grid g;
    struct grid3 cube = {.n = {32, 32, 32}, .spacing = {100, 100, 100}};
    assert_true(light_grid_init(&g, (const double[3]){0, 0, 1}, &cube, (const int[3]){33, 33, 33},
                                LIGHT_GRID_AUTO));
    assert_int_equal(light_auto_substeps(&g, &cube), 1);
    light_map_finish(&ref);
    light_map_finish(&aut);
    light_map_finish(&one);
    light_map_finish(&two);
    ext_volume_finish(&v);
}

/* The sheared grid of a flat box: u and v horizontal and orthonormal, w = -sun, node planes
 * at equal heights from the sun's side of the box to the other, nodes at texel centres, the
 * box inside the texel-centre range; upright kept for tall boxes, near-vertical and grazing
 * suns. */
static void test_sheared_grid_frame(void **state)
{
    (void)state;
    struct grid3 box = {
        .n = {20, 30, 10}, .spacing = {200.0, 100.0, 50.0}, .origin = {-1000.0, 500.0, 0.0}};
    const double suns[][3] = {{1, 1, 1}, {0.3, -1, 1.2}, {-1, 0.2, 1.1}, {1, 1, -1.5}};
    const int n[3] = {9, 7, 11};
    for (size_t t = 0; t < sizeof suns / sizeof suns[0]; t++) {
        struct light_grid g;
        assert_true(light_grid_init(&g, suns[t], &box, n, LIGHT_GRID_AUTO));
        assert_true(g.sheared);
        double sl = sqrt(suns[t][0] * suns[t][0] + suns[t][1] * suns[t][1] +
                         suns[t][2] * suns[t][2]);
        assert_float_equal(g.u[2], 0.0, 1e-12);
        assert_float_equal(g.v[2], 0.0, 1e-12);
        assert_float_equal(g.u[0] * g.u[0] + g.u[1] * g.u[1], 1.0, 1e-12);
        assert_float_equal(g.v[0] * g.v[0] + g.v[1] * g.v[1], 1.0, 1e-12);
        assert_true(fabs(g.u[0] * g.v[0] + g.u[1] * g.v[1]) <= 1e-12);
        for (int a = 0; a < 3; a++)
            assert_float_equal(g.w[a], -suns[t][a] / sl, 1e-12);
        /* Planes: node plane k lies at the first plane's height + k (height / (n - 1)) toward
         * the other face; the first plane is the sun's side. */
        double top = 500.0, first = suns[t][2] > 0 ? top : 0.0;
        for (int k = 0; k < n[2]; k++) {
            double p[3], q[3];
            light_grid_node_world(&g, 0, 0, k, p);
            light_grid_node_world(&g, n[0] - 1, n[1] - 1, k, q);
            double z = first + (suns[t][2] > 0 ? -1.0 : 1.0) * k * top / (n[2] - 1);
            assert_float_equal(p[2], z, 1e-6);
            assert_float_equal(q[2], z, 1e-6);
        }
        check_grid_mapping(&g, &box);
        /* Forced upright, the same sun gives the orthonormal frame. */
        assert_true(light_grid_init(&g, suns[t], &box, n, LIGHT_GRID_UPRIGHT));
        assert_false(g.sheared);
    }
    /* Upright where shearing would waste nodes or fail: a tall box, the sun near the zenith,
     * a grazing sun. */
    struct light_grid g;
    struct grid3 tall = {.n = {10, 10, 40}, .spacing = {100, 100, 100}};
    assert_true(light_grid_init(&g, suns[0], &tall, n, LIGHT_GRID_AUTO));
    assert_false(g.sheared);
    assert_true(light_grid_init(&g, (const double[3]){0.1, 0, 1}, &box, n, LIGHT_GRID_AUTO));
    assert_false(g.sheared);
    double grazing[3];
    light_sun_direction(33.0, 1.0, grazing);
    assert_true(light_grid_init(&g, grazing, &box, n, LIGHT_GRID_AUTO));
    assert_false(g.sheared);
}

/* What the sheared grid buys: a layer 600 m thick in a volume 80 km wide and 2 km high, lit at
 * 20 degrees, 24^3 nodes either way.  Across the light, an upright grid's columns cross the
 * layer in about one slice; sheared, every column crosses it in seven.  Against the beam
 * integrated along the light to the point (midpoint rule, 2 m steps, the CPU's own extinction
 * samples), at points inside and under the layer. */
static void test_sheared_grid_resolves_a_flat_layer(void **state)
{
    (void)state;
    struct ext_volume v;
    make_volume(&v, 40, 40, 10, 2000.0, 2000.0, 200.0);
    for (int k = 0; k < 10; k++)
        for (int j = 0; j < 40; j++)
            for (int i = 0; i < 40; i++)
                set_beta(&v, i, j, k, 0.0f, (k >= 2 && k <= 4) ? 1e-3f : 0.0f);
    struct light_settings s;
    light_settings_defaults(&s);
    s.forward = false;
    s.resolution[0] = s.resolution[1] = s.resolution[2] = 24;
    double sun[3];
    light_sun_direction(200.0, 20.0, sun);
    struct light_map sheared = {0}, upright = {0};
    assert_true(light_map_build(&v, sun, &s, &sheared));
    s.grid = LIGHT_GRID_UPRIGHT;
    assert_true(light_map_build(&v, sun, &s, &upright));
    assert_true(sheared.grid.sheared && !upright.grid.sheared);
    double err[2] = {0.0, 0.0};
    for (int t = 0; t < 400; t++) {
        double p[3] = {20e3 + 40e3 * rnd(), 20e3 + 40e3 * rnd(), 300.0 + 900.0 * rnd()};
        double tau = 0.0, ds = 2.0;
        for (double d = 0.5 * ds; d < 10e3; d += ds) { /* 10 km toward the sun clears the top */
            float q[3] = {(float)(p[0] + d * sun[0]), (float)(p[1] + d * sun[1]),
                          (float)(p[2] + d * sun[2])}, b[2];
            light_sample_beta(&v, q, b);
            tau += ((double)b[0] + b[1]) * ds;
        }
        const struct light_map *maps[2] = {&sheared, &upright};
        for (int m = 0; m < 2; m++) {
            double tex[3];
            light_grid_world_to_tex(&maps[m]->grid, p, tex);
            float tf[3] = {(float)tex[0], (float)tex[1], (float)tex[2]};
            err[m] = fmax(err[m], fabs(light_map_sample(maps[m], tf) - exp(-tau)));
        }
    }
    print_message("flat layer at 24^3: worst light error sheared %.3g, upright %.3g\n", err[0],
                  err[1]);
    assert_true(err[0] < 0.05);
    assert_true(err[0] < 0.25 * err[1]);
    light_map_finish(&sheared);
    light_map_finish(&upright);
    ext_volume_finish(&v);
}

/* ---- exact slices ------------------------------------------------------------------------ */

/* A laterally wide homogeneous water slab, 64 km x 64 km x 1 km of optical depth TAU, lit from
 * straight above with NK nodes along the light and 9 x 9 across: the centre column (four nodes
 * from the edges, where the peripheral taps read 1) sees a laterally uniform medium. */
static void slab_beam(double tau, int nk, bool peripheral, struct light_map *m)
{
    struct ext_volume v;
    make_volume(&v, 8, 8, 8, 8000.0, 8000.0, 125.0);
    fill_uniform(&v, 0.0f, (float)(tau / 1000.0));
    struct light_settings s;
    realistic_settings(&s, 9);
    s.resolution[2] = nk;
    s.peripheral = peripheral;
    assert_true(light_map_build(&v, (const double[3]){0, 0, 1}, &s, m));
    ext_volume_finish(&v);
}

/* Each slice of the beam is integrated exactly: in a homogeneous slab the light at depth tau
 * is exp(-(1 - CPc) tau) (peripheral off) or exp(-(1 - CPc - CPp) tau) (peripheral on, the
 * taps seeing the same light) however many slices the path is cut into.  Nes' one-step form
 * L_k = L_k-1 (T + (1 - T) CPc), T = e^-tau_slice, only tends to it as the slices thin. */
static void test_beam_slice_count_independent(void **state)
{
    struct light_settings s;
    realistic_settings(&s, 9);
    const double cpc = s.cp.water_ctr, cpp = s.cp.water_per, tau = 10.0;
    assert_true(cpc > 0.05 && cpp > 0.0 && cpc + cpp < 1.0);
    const int nks[] = {8, 32, 128};
    for (int per = 0; per < 2; per++) {
        const double loss = 1.0 - cpc - (per ? cpp : 0.0);
        for (size_t r = 0; r < sizeof nks / sizeof nks[0]; r++) {
            struct light_map m = {0};
            slab_beam(tau, nks[r], per, &m);
            double worst = 0.0;
            for (int k = 0; k < nks[r]; k++) {
                double depth = tau * k / (nks[r] - 1.0);
                double expect = exp(-loss * depth);
                double got = light_map_node(&m, 4, 4, k);
                worst = fmax(worst, fabs(got - expect) / expect);
            }
            print_message("slab tau %g, %3d nodes, peripheral %s: max relative error %.2g\n",
                          tau, nks[r], per ? "on " : "off", worst);
            assert_true(worst <= 1e-4);
            light_map_finish(&m);
        }
    }
    /* The old form at 8 nodes (7 slices of tau 10/7): far off the exact light. */
    double t = exp(-tau / 7.0), old = 1.0;
    for (int k = 0; k < 7; k++)
        old *= t + (1.0 - t) * cpc; /* Nes eq. 5.8-5.9 */
    double exact = exp(-(1.0 - cpc) * tau);
    print_message("one-step form at 8 nodes: %.4g at the bottom, exact %.4g (x %.2f)\n", old,
                  exact, old / exact);
    assert_true(fabs(old - exact) / exact > 0.1);
}

/* ---- multiple scattering: the two-stream column pass -------------------------------------- */

/* The diffuse terms of settings S for a sun at elevation ELEV_DEG. */
static void terms_at(const struct light_settings *s, double elev_deg, struct light_diffuse_terms *t)
{
    double sun[3];
    light_sun_direction(200.0, elev_deg, sun);
    light_diffuse_terms_init(s, sun, t);
}

/* light_diffuse_column on a homogeneous water column of total vertical optical depth TAU cut
 * into N - 1 equal slices, lit at MU0 = sin(elevation): the light column crosses it along the
 * slant, each slice of optical depth TAU / ((N - 1) MU0), holding the beam the map would hold
 * there, exp(-k tau_slant), k = 1 - CPc (forward on, peripheral off).  OUT holds 2 N floats. */
static void homogeneous_column_escape(const struct light_diffuse_terms *d, int n, double tau,
                                      float rate, float *out)
{
    float *beam = malloc(7 * (size_t)n * sizeof(float));
    assert_non_null(beam);
    float *t = beam + n, *fi = beam + 2 * n, *scratch = beam + 3 * n, *lat = beam + 5 * n;
    const double ts = tau / ((n - 1.0) * d->mu0);
    for (int i = 0; i < n; i++) {
        beam[i] = (float)exp(-d->loss[0] * ts * i);
        t[i] = i > 0 ? (float)ts : 0.0f;
        fi[i] = 0.0f;
        lat[2 * i] = rate;
        lat[2 * i + 1] = 0.0f;
    }
    light_diffuse_column(n, beam, t, fi, rate > 0.0f ? lat : NULL, d, scratch, out);
    free(beam);
}

/* The same with no lateral escape (a plane-parallel layer). */
static void homogeneous_column(const struct light_diffuse_terms *d, int n, double tau,
                               float *out)
{
    homogeneous_column_escape(d, n, tau, 0.0f, out);
}

static void diffuse_settings(struct light_settings *s)
{
    realistic_settings(s, 8);
    s->peripheral = false;
    s->multiple = true;
    assert_true(s->cp.water_gamma > 0.0 && s->cp.water_cs_g > 0.0);
}

/* Conservative scattering: what the beam loses leaves the column as diffuse light, through the
 * top (V0 = M0 / 2: no diffuse light enters there, U0 = 0) or the bottom (U = M / 2: nothing
 * comes back from below, V = 0).  Per unit horizontal area the layer receives mu0 of the sun's
 * irradiance: mu0 (1 - e^(-k tau / mu0)) of it is lost by the beam. */
static void test_diffuse_column_conserves_energy(void **state)
{
    struct light_settings s;
    diffuse_settings(&s);
    const double taus[] = {0.1, 2.0, 20.0, 200.0};
    const int ns[] = {2, 33};
    const double elevs[] = {90.0, 35.0, 5.0};
    float out[2 * 33];
    for (size_t e = 0; e < sizeof elevs / sizeof elevs[0]; e++) {
        struct light_diffuse_terms d;
        terms_at(&s, elevs[e], &d);
        assert_float_equal(d.mu0, sin(elevs[e] * M_PI / 180.0), 1e-6);
        for (size_t a = 0; a < sizeof taus / sizeof taus[0]; a++) {
            for (size_t b = 0; b < sizeof ns / sizeof ns[0]; b++) {
                int n = ns[b];
                homogeneous_column(&d, n, taus[a], out);
                double beam = d.mu0 * exp(-d.loss[0] * taus[a] / d.mu0);
                double top = 0.5 * out[0], bottom = 0.5 * out[2 * (n - 1)];
                double sum = beam + top + bottom;
                print_message("elevation %2g, tau %5g, %2d nodes: reflected %.6f, diffuse "
                              "through %.6f, beam %.6f, sum / mu0 - 1 = %.2g\n",
                              elevs[e], taus[a], n, top, bottom, beam, sum / d.mu0 - 1.0);
                assert_true(fabs(sum / d.mu0 - 1.0) <= 1e-5);
                /* At the top only V, at the bottom only U. */
                assert_float_equal(out[1], -out[0], 1e-7);
                assert_float_equal(out[2 * n - 1], out[2 * n - 2], 1e-7);
                assert_true(top > 0.0 && bottom > 0.0);
            }
        }
    }
}

/* Each slice is solved exactly and joined by the adding method: the reflectance and the
 * diffuse transmittance do not depend on the number of slices. */
static void test_diffuse_column_slice_count_independent(void **state)
{
    struct light_settings s;
    diffuse_settings(&s);
    const double taus[] = {2.0, 20.0};
    const int ns[] = {2, 5, 33, 257};
    float *out = malloc(2 * 257 * sizeof(float));
    assert_non_null(out);
    for (int e = 0; e < 2; e++) {
        struct light_diffuse_terms d;
        terms_at(&s, e ? 35.0 : 90.0, &d);
        for (size_t a = 0; a < sizeof taus / sizeof taus[0]; a++) {
            double v0[4], ut[4], worst_v = 0.0, worst_u = 0.0;
            for (int b = 0; b < 4; b++) {
                homogeneous_column(&d, ns[b], taus[a], out);
                v0[b] = 0.5 * out[0];
                ut[b] = 0.5 * out[2 * (ns[b] - 1)];
                worst_v = fmax(worst_v, fabs(v0[b] - v0[0]) / v0[0]);
                worst_u = fmax(worst_u, fabs(ut[b] - ut[0]) / ut[0]);
            }
            print_message("mu0 %.3f, tau %g, 2..257 nodes: reflectance %.6f (spread %.2g), "
                          "diffuse transmittance %.6f (spread %.2g)\n",
                          d.mu0, taus[a], v0[0], worst_v, ut[0], worst_u);
            assert_true(worst_v <= 1e-4);
            assert_true(worst_u <= 1e-4);
        }
    }
    free(out);
}

/* The two-stream equations with the beam's loss as source, d/dt of (U, V) at vertical optical
 * depth t, for a beam fading as e^-(kappa t) (kappa = k / mu0) that deposits k e^-(kappa t)
 * per unit of t and horizontal area: dU/dt = -g U + g V + s_f k e^-(kappa t),
 * dV/dt = -g U + g V - s_b k e^-(kappa t). */
struct two_stream {
    double gamma, k, kappa, sb;
    double a; /* lateral escape, as absorption: dU/dt gains -a U, dV/dt gains +a V */
};

static void two_stream_rhs(const struct two_stream *p, double t, const double y[2], double dy[2])
{
    double src = p->k * exp(-p->kappa * t);
    double c = p->gamma * (y[1] - y[0]);
    dy[0] = c - p->a * y[0] + (1.0 - p->sb) * src;
    dy[1] = c + p->a * y[1] - p->sb * src;
}

/* The water column's two-stream problem for the pass's terms D (no lateral escape). */
static struct two_stream water_two_stream(const struct light_settings *s,
                                          const struct light_diffuse_terms *d)
{
    struct two_stream p = {0};
    p.gamma = s->cp.water_gamma;
    p.k = d->loss[0];
    p.kappa = d->loss[0] / d->mu0;
    p.sb = d->back[0] / d->loss[0];
    return p;
}

/* RK4 from t = 0 (U = 0, V = V0) to TAU in STEPS steps; with NODES > 0 also records M and N at
 * NODES equally spaced depths (STEPS a multiple of NODES - 1) into MN. */
static void two_stream_shoot(const struct two_stream *p, double v0, double tau, int steps,
                             int nodes, double *mn, double end[2])
{
    double y[2] = {0.0, v0}, h = tau / steps;
    int per_node = nodes > 1 ? steps / (nodes - 1) : 0;
    for (int i = 0; i <= steps; i++) {
        if (per_node && i % per_node == 0) {
            mn[2 * (i / per_node)] = 2.0 * (y[0] + y[1]);
            mn[2 * (i / per_node) + 1] = 2.0 * (y[0] - y[1]);
        }
        if (i == steps)
            break;
        double t = i * h, k1[2], k2[2], k3[2], k4[2], yt[2];
        two_stream_rhs(p, t, y, k1);
        for (int c = 0; c < 2; c++)
            yt[c] = y[c] + 0.5 * h * k1[c];
        two_stream_rhs(p, t + 0.5 * h, yt, k2);
        for (int c = 0; c < 2; c++)
            yt[c] = y[c] + 0.5 * h * k2[c];
        two_stream_rhs(p, t + 0.5 * h, yt, k3);
        for (int c = 0; c < 2; c++)
            yt[c] = y[c] + h * k3[c];
        two_stream_rhs(p, t + h, yt, k4);
        for (int c = 0; c < 2; c++)
            y[c] += h / 6.0 * (k1[c] + 2.0 * k2[c] + 2.0 * k3[c] + k4[c]);
    }
    end[0] = y[0];
    end[1] = y[1];
}

/* An independent solution of the same boundary value problem (U(0) = 0, V(tau) = 0): RK4 in
 * double precision, shooting on V(0); the system is linear, so two shots fix it. */
static void test_diffuse_column_matches_ode(void **state)
{
    struct light_settings s;
    diffuse_settings(&s);
    enum { N = 65, STEPS = 64 * 400 };
    const double taus[] = {2.0, 20.0};
    for (int e = 0; e < 2; e++) {
        struct light_diffuse_terms d;
        terms_at(&s, e ? 35.0 : 90.0, &d);
        struct two_stream p = water_two_stream(&s, &d);
        assert_true(p.sb > 0.0 && p.sb < 1.0);
        for (size_t a = 0; a < sizeof taus / sizeof taus[0]; a++) {
            double tau = taus[a], e0[2], e1[2], end[2], mn[2 * N];
            two_stream_shoot(&p, 0.0, tau, STEPS, 0, NULL, e0);
            two_stream_shoot(&p, 1.0, tau, STEPS, 0, NULL, e1);
            double v0 = -e0[1] / (e1[1] - e0[1]); /* V(tau) = 0 */
            two_stream_shoot(&p, v0, tau, STEPS, N, mn, end);
            assert_true(fabs(end[1]) < 1e-12);
            float out[2 * N];
            homogeneous_column(&d, N, tau, out);
            double dv = fabs(0.5 * out[0] - v0) / v0;
            double du = fabs(0.5 * out[2 * (N - 1)] - end[0]) / end[0];
            /* And the whole profile, relative to the largest value. */
            double big = 0.0, worst = 0.0;
            for (int i = 0; i < 2 * N; i++)
                big = fmax(big, fabs(mn[i]));
            for (int i = 0; i < 2 * N; i++)
                worst = fmax(worst, fabs(out[i] - mn[i]) / big);
            print_message("mu0 %.3f, tau %g: ODE V(0) %.6f U(tau) %.6f; column pass relative "
                          "differences %.2g, %.2g; M, N profile %.2g\n",
                          d.mu0, tau, v0, end[0], dv, du, worst);
            assert_true(dv <= 1e-4);
            assert_true(du <= 1e-4);
            assert_true(worst <= 1e-4);
        }
    }
}

/* With lateral escape the slices are absorbing layers (closed form) and their own diffuse
 * light leaves them by the layer's Green's function integrated over the exponential source
 * (closed form; thin slices, k tau_v < 0.01, use an even source's share instead): against the
 * same ODE with the escape as absorption, for runs 2 and 5 optical depths wide (rates 0.5 and
 * 0.2), on 3, 64 and 256 slices.  Exact per slice, the pass does not depend on how the column
 * is cut: within 1e-4 of the ODE on 3 slices as on 256. */
static void test_diffuse_column_escape_matches_ode(void **state)
{
    struct light_settings s;
    diffuse_settings(&s);
    enum { STEPS = 256 * 3 * 100 }; /* a multiple of every slice count */
    const float rates[] = {0.5f, 0.2f};
    const double taus[] = {2.0, 20.0};
    for (int e = 0; e < 2; e++) {
        struct light_diffuse_terms d;
        terms_at(&s, e ? 35.0 : 90.0, &d);
        struct two_stream p = water_two_stream(&s, &d);
        for (int r = 0; r < 2; r++) {
            p.a = light_lateral_escape((float)p.gamma, rates[r], 0.0f);
            assert_true(p.a > 0.0);
            for (size_t a = 0; a < sizeof taus / sizeof taus[0]; a++) {
                double tau = taus[a], e0[2], e1[2], end[2];
                two_stream_shoot(&p, 0.0, tau, STEPS, 0, NULL, e0);
                two_stream_shoot(&p, 1.0, tau, STEPS, 0, NULL, e1);
                double v0 = -e0[1] / (e1[1] - e0[1]);
                double worst[3];
                const int ns[3] = {4, 65, 257};
                for (int b = 0; b < 3; b++) {
                    double mn[2 * 257];
                    float out[2 * 257];
                    two_stream_shoot(&p, v0, tau, STEPS, ns[b], mn, end);
                    homogeneous_column_escape(&d, ns[b], tau, rates[r], out);
                    double big = 0.0;
                    worst[b] = 0.0;
                    for (int i = 0; i < 2 * ns[b]; i++)
                        big = fmax(big, fabs(mn[i]));
                    for (int i = 0; i < 2 * ns[b]; i++)
                        worst[b] = fmax(worst[b], fabs(out[i] - mn[i]) / big);
                }
                /* The escape lost: what the beam deposits minus what leaves by the ends. */
                double dep = d.mu0 * (1.0 - exp(-p.k * tau / d.mu0));
                print_message("mu0 %.3f, rate %g (a %.4f), tau %g: %.1f %% escapes; M, N "
                              "profile vs ODE %.2g (3 slices), %.2g (64), %.2g (256)\n",
                              d.mu0, (double)rates[r], p.a, tau,
                              100.0 * (1.0 - (v0 + end[0]) / dep), worst[0], worst[1],
                              worst[2]);
                assert_true(v0 + end[0] < dep); /* something escapes */
                for (int b = 0; b < 3; b++)
                    assert_true(worst[b] <= 1e-4);
            }
        }
    }
}

/* The escape rate: r e^-((1 - g) / r) per axis: the straight-flight rate r for runs much
 * narrower than a transport mean free path, nothing for wide ones, zero for none, and
 * increasing with the rate. */
static void test_lateral_escape_rate(void **state)
{
    (void)state;
    const float g = 0.105f, tr = 4.0f * g / 3.0f; /* water: 1 - g = 0.14 */
    assert_true(light_lateral_escape(g, 0.0f, 0.0f) == 0.0f);
    /* A run one optical depth wide along x, unbounded along y. */
    assert_float_equal(light_lateral_escape(g, 1.0f, 0.0f), expf(-tr), 1e-6);
    assert_float_equal(light_lateral_escape(g, 0.5f, 0.5f), 2.0f * 0.5f * expf(-2.0f * tr),
                       1e-6);
    /* Narrow: 0.01 optical depths wide, the flight rate within 0.2 %. */
    assert_float_equal(light_lateral_escape(g, 100.0f, 0.0f), 100.0f, 0.2f);
    /* Wide: 100 optical depths (14 transport mean free paths), under 1e-7 per unit depth. */
    assert_true(light_lateral_escape(g, 0.01f, 0.01f) < 1e-7f);
    float last = 0.0f;
    for (int i = 1; i <= 4000; i++) {
        float a = light_lateral_escape(g, 1e-3f * (float)i, 0.0f);
        assert_true(a >= last);
        last = a;
    }
}

/* The rates of a volume, times the extinction: a block four voxels wide (along x) and two
 * deep (along y) of extinction 1e-3 per metre on a 100 m grid, beside clear air, is 0.4 and
 * 0.2 optical depths wide: beta / w = 2.5e-3 and 5e-3 in the block, 0 in clear air; a
 * one-voxel run of 5e-3 on another row is 0.5 wide; a run of two unequal voxels shares one
 * width; NaN splits a run and infinity stays finite. */
static void test_lateral_rates(void **state)
{
    (void)state;
    struct ext_volume v;
    make_volume(&v, 10, 6, 2, 100.0, 100.0, 100.0);
    for (int k = 0; k < 2; k++)
        for (int j = 2; j < 4; j++)
            for (int i = 3; i < 7; i++)
                v.beta[2 * (i + 10 * (j + 6 * k)) + 1] = 1e-3f;
    v.beta[2 * 0 + 1] = 5e-3f; /* voxel (0, 0, 0) */
    /* Row j = 5, k = 1: ice 1e-3 then water 3e-3 at i = 8, 9: w = 0.4. */
    v.beta[2 * (8 + 10 * (5 + 6 * 1))] = 1e-3f;
    v.beta[2 * (9 + 10 * (5 + 6 * 1)) + 1] = 3e-3f;
    float *r = malloc(2 * 10 * 6 * 2 * sizeof(float));
    assert_non_null(r);
    light_lateral_rates(&v, r);
    for (int k = 0; k < 2; k++) {
        for (int j = 0; j < 6; j++) {
            for (int i = 0; i < 10; i++) {
                size_t at = 2 * (i + 10 * (j + 6 * k));
                bool block = i >= 3 && i < 7 && j >= 2 && j < 4;
                if (block) {
                    assert_float_equal(r[at], 1e-3 / 0.4, 1e-8);
                    assert_float_equal(r[at + 1], 1e-3 / 0.2, 1e-8);
                } else if (!(i == 0 && j == 0 && k == 0) && !(j == 5 && k == 1 && i >= 8)) {
                    assert_true(r[at] == 0.0f && r[at + 1] == 0.0f);
                }
            }
        }
    }
    assert_float_equal(r[0], 5e-3 / 0.5, 1e-7); /* one voxel along x, one along y */
    assert_float_equal(r[1], 5e-3 / 0.5, 1e-7);
    assert_float_equal(r[2 * (8 + 10 * (5 + 6 * 1))], 1e-3 / 0.4, 1e-8);
    assert_float_equal(r[2 * (9 + 10 * (5 + 6 * 1))], 3e-3 / 0.4, 1e-8);
    /* Non-finite input. */
    v.beta[2 * (4 + 10 * (2 + 6 * 0)) + 1] = NAN;
    v.beta[2 * (5 + 10 * (3 + 6 * 1)) + 1] = INFINITY;
    light_lateral_rates(&v, r);
    for (int i = 0; i < 2 * 10 * 6 * 2; i++)
        assert_true(isfinite(r[i]) && r[i] >= 0.0f);
    assert_float_equal(r[2 * (3 + 10 * (2 + 6 * 0))], 1e-3 / 0.1, 1e-7); /* split by the NaN */
    /* Plane by plane (the effects' facts): each plane's values of the whole volume's, exactly. */
    float plane[2 * 10 * 6];
    for (int k = 0; k < 2; k++) {
        light_lateral_rates_plane(&v, k, plane);
        assert_memory_equal(plane, r + 2 * 10 * 6 * k, sizeof(plane));
    }
    free(r);
    ext_volume_finish(&v);
}

/* Slices of optical depth 1e4 and 1e30 (kept finite), and empty ones, in both phases: every
 * output finite, M >= 0, |N| <= M; the column still conserves energy; and the same with
 * lateral escape from none to extreme, where it can only lose light. */
static void test_diffuse_column_extreme(void **state)
{
    enum { N = 24 };
    const float taus[N] = {0, 0, 1e4f, 0, 1e30f, 0, 0.5f, 1e4f, 1e4f, 0, 1e30f, 1e30f,
                           0, 2.0f, 0, 1e-30f, 1e4f, 0, 0, 1e30f, 3.0f, 0, 1e4f, 0};
    float beam[N], fi[N], scratch[2 * N], out[2 * N];
    for (int mode = 0; mode < 3; mode++) { /* forward off, central only, both */
        struct light_settings s;
        realistic_settings(&s, 8);
        s.multiple = true;
        s.forward = mode > 0;
        s.peripheral = mode > 1;
        for (int e = 0; e < 2; e++) { /* sun overhead, and low */
            struct light_diffuse_terms d;
            terms_at(&s, e ? 8.0 : 90.0, &d);
            for (int first = 0; first < 3; first++) { /* start at different rows */
                float t[N];
                for (int i = 0; i < N; i++) {
                    t[i] = i == 0 ? 0.0f : taus[(i + 7 * first) % N];
                    fi[i] = (float)((i + first) % 3) * 0.5f;
                }
                beam[0] = 1.0f;
                for (int i = 1; i < N; i++) {
                    double k = d.loss[0] + fi[i] * (d.loss[1] - d.loss[0]);
                    beam[i] = (float)(beam[i - 1] * exp(-k * (double)t[i]));
                }
                light_diffuse_column(N, beam, t, fi, NULL, &d, scratch, out);
                for (int i = 0; i < N; i++) {
                    float m = out[2 * i], nn = out[2 * i + 1];
                    if (!(isfinite(m) && isfinite(nn) && m >= 0.0f && fabsf(nn) <= m + 1e-6f))
                        fail_msg("mode %d mu0 %g start %d node %d: M %g N %g", mode,
                                 (double)d.mu0, first, i, (double)m, (double)nn);
                }
                double sum = d.mu0 * beam[N - 1] + 0.5 * out[0] + 0.5 * out[2 * (N - 1)];
                assert_true(fabs(sum / d.mu0 - 1.0) <= 1e-3);
                /* With lateral escape at rates from none to a run a millionth of an optical
                 * depth wide: the same bounds, and what leaves by the ends is at most what
                 * came in; never more than without escape. */
                static const float rates[] = {0.0f, 1e-6f, 0.3f, 40.0f, 1e6f};
                float lat[2 * N], esc[2 * N];
                for (int i = 0; i < N; i++) {
                    lat[2 * i] = rates[(i + first) % 5];
                    lat[2 * i + 1] = rates[(3 * i + mode) % 5];
                }
                light_diffuse_column(N, beam, t, fi, lat, &d, scratch, esc);
                for (int i = 0; i < N; i++) {
                    float m = esc[2 * i], nn = esc[2 * i + 1];
                    if (!(isfinite(m) && isfinite(nn) && m >= 0.0f && fabsf(nn) <= m + 1e-6f &&
                          m <= out[2 * i] * (1.0f + 1e-4f) + 1e-6f))
                        fail_msg("escape: mode %d mu0 %g start %d node %d: M %g N %g (%g "
                                 "without)",
                                 mode, (double)d.mu0, first, i, (double)m, (double)nn,
                                 (double)out[2 * i]);
                }
                double kept = d.mu0 * beam[N - 1] + 0.5 * esc[0] + 0.5 * esc[2 * (N - 1)];
                assert_true(kept <= d.mu0 * (1.0 + 1e-4));
            }
        }
    }
    /* A single slice that is all of it, and one column of two empty nodes: no diffuse light. */
    struct light_settings s;
    diffuse_settings(&s);
    struct light_diffuse_terms d;
    terms_at(&s, 90.0, &d);
    const float t1[2] = {0, 1e30f}, b1[2] = {1.0f, 0.0f}, f1[2] = {0, 0};
    light_diffuse_column(2, b1, t1, f1, NULL, &d, scratch, out);
    for (int i = 0; i < 4; i++)
        assert_true(isfinite(out[i]));
    assert_true(out[0] > 1.0f && out[0] <= 2.0f + 1e-6f); /* nearly all reflected */
    const float t0[2] = {0, 0}, b0[2] = {1.0f, 1.0f};
    light_diffuse_column(2, b0, t0, f1, NULL, &d, scratch, out);
    for (int i = 0; i < 4; i++)
        assert_true(out[i] == 0.0f);
}

/* The diffuse array of a whole map: only with settings.multiple, finite, M >= 0, |N| <= M,
 * zero in columns that cross no medium, the beam unchanged by it, and (peripheral off: no
 * light changes columns) every column conserving energy without lateral escape.  With it:
 * the same bounds, no column gives out more than it receives, and no node is brighter than
 * without it.  Returns the share of the diffuse light (sum of M) that lateral escape keeps. */
static double check_diffuse_map(const struct ext_volume *v, const double sun[3],
                                struct light_settings *s, const char *what)
{
    struct light_map on = {0}, off = {0}, lat = {0};
    s->lateral = true;
    s->multiple = true;
    assert_true(light_map_build(v, sun, s, &lat));
    s->lateral = false;
    s->multiple = false;
    assert_true(light_map_build(v, sun, s, &off));
    assert_null(off.diffuse);
    float zero[2] = {1, 1};
    light_map_sample_diffuse(&off, (const float[3]){0.5f, 0.5f, 0.5f}, zero);
    assert_true(zero[0] == 0.0f && zero[1] == 0.0f);
    s->multiple = true;
    assert_true(light_map_build(v, sun, s, &on));
    assert_non_null(on.diffuse);
    const int *n = on.grid.n;
    size_t plane = (size_t)n[0] * n[1], count = plane * n[2];
    assert_memory_equal(on.light, off.light, count * sizeof(float));
    double mmax = 0.0, worst_energy = 0.0;
    size_t clear = 0;
    struct light_diffuse_terms terms;
    light_diffuse_terms_init(s, sun, &terms);
    const double mu0 = terms.mu0;
    for (size_t c = 0; c < plane; c++) {
        bool lit = true;
        for (int k = 0; k < n[2]; k++) {
            float m = on.diffuse[2 * (c + plane * k)], nn = on.diffuse[2 * (c + plane * k) + 1];
            if (!(isfinite(m) && isfinite(nn) && m >= 0.0f && fabsf(nn) <= m * (1.0f + 1e-5f)))
                fail_msg("%s: column %zu node %d: M %g N %g", what, c, k, (double)m, (double)nn);
            mmax = fmax(mmax, m);
            lit = lit && on.light[c + plane * k] == 1.0f;
        }
        if (lit) { /* the column crosses no medium */
            clear++;
            for (int k = 0; k < n[2]; k++)
                assert_true(on.diffuse[2 * (c + plane * k)] == 0.0f);
        }
        if (!s->peripheral) { /* per unit horizontal area the column receives mu0 */
            double sum = mu0 * on.light[c + plane * (n[2] - 1)] + 0.5 * on.diffuse[2 * c] +
                         0.5 * on.diffuse[2 * (c + plane * (n[2] - 1))];
            worst_energy = fmax(worst_energy, fabs(sum / mu0 - 1.0));
        }
    }
    if (s->peripheral)
        print_message("%s: max M %.3g, %zu clear columns of %zu\n", what, mmax, clear, plane);
    else
        print_message("%s: max M %.3g, %zu clear columns of %zu, worst column energy error "
                      "%.2g\n",
                      what, mmax, clear, plane, worst_energy);
    assert_true(mmax > 0.1);
    assert_true(worst_energy <= 1e-4);
    double sum_on = 0.0, sum_lat = 0.0, worst_gain = 0.0;
    for (size_t c = 0; c < plane; c++) {
        for (int k = 0; k < n[2]; k++) {
            size_t at = 2 * (c + plane * k);
            float m = lat.diffuse[at], nn = lat.diffuse[at + 1];
            if (!(isfinite(m) && isfinite(nn) && m >= 0.0f && fabsf(nn) <= m * (1.0f + 1e-5f)))
                fail_msg("%s, lateral: column %zu node %d: M %g N %g", what, c, k, (double)m,
                         (double)nn);
            if (m > on.diffuse[at] * (1.0f + 1e-5f) + 1e-7f)
                fail_msg("%s: lateral escape brightens column %zu node %d: %g > %g", what, c,
                         k, (double)m, (double)on.diffuse[at]);
            sum_on += on.diffuse[at];
            sum_lat += m;
        }
        if (!s->peripheral) {
            double sum = mu0 * lat.light[c + plane * (n[2] - 1)] + 0.5 * lat.diffuse[2 * c] +
                         0.5 * lat.diffuse[2 * (c + plane * (n[2] - 1))];
            worst_gain = fmax(worst_gain, sum / mu0 - 1.0);
        }
    }
    print_message("%s: lateral escape keeps %.3f of the diffuse light\n", what,
                  sum_lat / sum_on);
    assert_true(worst_gain <= 1e-4);
    assert_memory_equal(lat.light, on.light, count * sizeof(float));
    light_map_finish(&lat);
    /* The lookup at a node's texel centre returns that node's pair. */
    int i = n[0] / 2, j = n[1] / 2, k = n[2] / 2;
    float tex[3] = {(i + 0.5f) / n[0], (j + 0.5f) / n[1], (k + 0.5f) / n[2]}, d[2];
    light_map_sample_diffuse(&on, tex, d);
    size_t at = 2 * ((size_t)i + n[0] * ((size_t)j + (size_t)n[1] * k));
    assert_float_equal(d[0], on.diffuse[at], 1e-5 * (1.0 + on.diffuse[at]));
    assert_float_equal(d[1], on.diffuse[at + 1], 1e-5 * (1.0 + fabsf(on.diffuse[at + 1])));
    /* Rebuilt into the same map with multiple off: the diffuse array goes. */
    s->multiple = false;
    assert_true(light_map_build(v, sun, s, &on));
    assert_null(on.diffuse);
    light_map_finish(&on);
    light_map_finish(&off);
    return sum_lat / sum_on;
}

/* A layer that fills the box, lit from above at 90 and 35 degrees: every light column that
 * crosses all of it (in at the top, out at the bottom) is the plane-parallel problem, so its
 * diffuse light must be homogeneous_column's for the optical depth the column's slices add up
 * to (the light map's, read from the beam it lets through), whichever nodes the layer's faces
 * fall between: the slices' depths, the beam and the wiring of the pass. */
static void test_diffuse_map_layer(void **state)
{
    struct ext_volume v;
    make_volume(&v, 40, 40, 10, 100.0, 100.0, 100.0);
    fill_uniform(&v, 0.0f, 2e-3f); /* water, tau 2 over 1 km */
    struct light_settings s;
    diffuse_settings(&s);
    s.lateral = false; /* the plane-parallel problem: no escape through the box's sides */
    s.resolution[0] = s.resolution[1] = 24;
    s.resolution[2] = 32;
    const double elevs[] = {90.0, 35.0};
    for (int e = 0; e < 2; e++) {
        double sun[3];
        light_sun_direction(200.0, elevs[e], sun);
        struct light_map m = {0};
        assert_true(light_map_build(&v, sun, &s, &m));
        struct light_diffuse_terms t;
        light_diffuse_terms_init(&s, sun, &t);
        assert_float_equal(t.mu0, sin(elevs[e] * M_PI / 180.0), 1e-6);
        const double through = exp(-t.loss[0] * 2.0 / t.mu0);
        const int *n = m.grid.n;
        size_t plane = (size_t)n[0] * n[1];
        double worst = 0.0, r_min = 1.0, r_max = 0.0;
        int whole = 0;
        float expect[2 * 65];
        for (size_t c = 0; c < plane; c++) {
            double bottom = m.light[c + plane * (n[2] - 1)];
            if (fabs(bottom / through - 1.0) > 0.1)
                continue; /* enters or leaves through a side: a shorter path */
            whole++;
            double tau = -log(bottom) / t.loss[0] * t.mu0; /* vertical */
            homogeneous_column(&t, 65, tau, expect);
            /* Above the layer the column holds what it reflects, below what it lets through. */
            double up = 0.5 * m.diffuse[2 * c];
            double down = 0.5 * m.diffuse[2 * (c + plane * (n[2] - 1))];
            worst = fmax(worst, fabs(up - 0.5 * expect[0]) / (0.5 * expect[0]));
            worst = fmax(worst, fabs(down - 0.5 * expect[2 * 64]) / (0.5 * expect[2 * 64]));
            assert_float_equal(m.diffuse[2 * c + 1], -m.diffuse[2 * c], 1e-6);
            r_min = fmin(r_min, up);
            r_max = fmax(r_max, up);
        }
        print_message("layer lit at %g degrees: %d of %zu light columns cross all of it; "
                      "reflected %.5f .. %.5f, largest difference from the plane-parallel "
                      "column %.2g\n",
                      elevs[e], whole, plane, r_min, r_max, worst);
        assert_true(whole >= (int)(plane / 8));
        assert_true(worst <= 1e-4);
        light_map_finish(&m);
    }
    ext_volume_finish(&v);
}

static void test_diffuse_map_sphere_and_storm(void **state)
{
    struct ext_volume v;
    make_volume(&v, 24, 20, 16, 300.0, 300.0, 100.0);
    fill_sphere(&v, 8.0);
    struct light_settings s;
    realistic_settings(&s, 24);
    double sun[3];
    light_sun_direction(247.0, 30.0, sun);
    check_diffuse_map(&v, sun, &s, "sphere, peripheral on");
    s.peripheral = false;
    check_diffuse_map(&v, sun, &s, "sphere, peripheral off");
    s.forward = false;
    check_diffuse_map(&v, (const double[3]){0, 0, 1}, &s, "sphere, shadow only, overhead");
    ext_volume_finish(&v);

    struct synth_desc d = {.kind = SYNTH_STORM,
                           .n = {64, 64, 32},
                           .extent_m = {60000.0, 60000.0, 16000.0},
                           .seed = 1,
                           .time = 0.5};
    if (!synth_extinction(&d, NULL, &v)) {
        print_message("synthetic storm unavailable; skipping its diffuse map\n");
        return;
    }
    realistic_settings(&s, 40);
    light_sun_direction(135.0, 35.0, sun);
    check_diffuse_map(&v, sun, &s, "storm, peripheral on");
    s.peripheral = false;
    check_diffuse_map(&v, sun, &s, "storm, peripheral off");
    ext_volume_finish(&v);
}

/* ---- compression ------------------------------------------------------------------------- */

static void check_compressed(const struct light_map *m, double eps)
{
    struct light_compressed c;
    assert_true(light_compressed_build(m, eps, &c));
    const int *n = m->grid.n;
    size_t dense_nodes = (size_t)n[0] * n[1] * n[2];
    assert_true(c.node_count <= dense_nodes);
    assert_true(light_compressed_bytes(&c) == (size_t)n[0] * n[1] * 8 + c.node_count * 8);
    /* Every stored sample within epsilon (plus float rounding). */
    for (int j = 0; j < n[1]; j++)
        for (int i = 0; i < n[0]; i++) {
            size_t col = (size_t)i + (size_t)n[0] * j;
            const float *nodes = c.nodes + 2 * (size_t)c.columns[2 * col];
            uint32_t cnt = c.columns[2 * col + 1];
            assert_true(cnt >= 1 && cnt <= (uint32_t)n[2]);
            assert_true(nodes[0] >= 0.0f && nodes[2 * (cnt - 1)] <= (float)(n[2] - 1));
            for (uint32_t q = 1; q < cnt; q++)
                assert_true(nodes[2 * q] >= nodes[2 * (q - 1)]);
            for (int k = 0; k < n[2]; k++) {
                float d = light_map_node(m, i, j, k);
                float e = light_column_eval(nodes, cnt, (float)k);
                if (!(fabsf(d - e) <= eps + 1e-6))
                    fail_msg("eps %g column (%d, %d) k %d: dense %.9g compressed %.9g", eps, i, j,
                             k, (double)d, (double)e);
            }
        }
    /* And at random points through the lookups the eye pass uses. */
    for (int t = 0; t < 2000; t++) {
        float tex[3] = {(float)rnd(), (float)rnd(), (float)rnd()};
        float d = light_map_sample(m, tex), e = light_compressed_sample(&c, tex);
        assert_true(fabsf(d - e) <= eps + 1e-5);
    }
    light_compressed_finish(&c);
}

static void test_compressed_within_epsilon(void **state)
{
    struct ext_volume v;
    make_volume(&v, 24, 24, 24, 250.0, 250.0, 100.0);
    fill_random(&v, 0.004f);
    struct light_settings s;
    realistic_settings(&s, 32);
    double sun[3];
    light_sun_direction(300.0, 40.0, sun);
    struct light_map m = {0};
    assert_true(light_map_build(&v, sun, &s, &m));
    const double eps[] = {0.0, 1e-4, 1e-3, 0.01, 0.05};
    for (size_t e = 0; e < sizeof eps / sizeof eps[0]; e++)
        check_compressed(&m, eps[e]);
    light_map_finish(&m);
    ext_volume_finish(&v);
}

/* Two functions compressed together (light_compress_column2, the diffuse light's M and N):
 * with both the same, the nodes of light_compress_column; with one constant, the other's
 * nodes; in general every sample of each within epsilon, and a node wherever either needs
 * one. */
static void test_compress_two_channels(void **state)
{
    float d[40], a[40], b[40], one[80], two[120];
    for (int i = 0; i < 40; i++) {
        d[i] = (float)i;
        a[i] = (float)(0.5 + 0.4 * sin(0.3 * i) * exp(-0.05 * i));
        b[i] = 0.3f;
    }
    const double eps[] = {0.0, 0.002, 0.05};
    for (size_t e = 0; e < sizeof eps / sizeof eps[0]; e++) {
        int m1 = light_compress_column(d, a, 40, eps[e], one);
        int m2 = light_compress_column2(d, a, a, 40, eps[e], two);
        assert_int_equal(m2, m1);
        for (int i = 0; i < m1; i++) {
            assert_true(two[3 * i] == one[2 * i]);
            assert_true(two[3 * i + 1] == one[2 * i + 1] && two[3 * i + 2] == one[2 * i + 1]);
        }
        m2 = light_compress_column2(d, a, b, 40, eps[e], two);
        assert_int_equal(m2, m1); /* the constant needs no node of its own */
        for (int i = 0; i < m1; i++)
            assert_true(two[3 * i + 2] == 0.3f);
    }
    /* A ramp in one, a kink in the other: the kink's node is kept for both. */
    for (int i = 0; i < 40; i++) {
        a[i] = 1.0f - 0.02f * (float)i;
        b[i] = i < 20 ? 0.0f : 0.05f * (float)(i - 20);
    }
    assert_int_equal(light_compress_column(d, a, 40, 0.001, one), 2);
    int m = light_compress_column2(d, a, b, 40, 0.001, two);
    assert_int_equal(m, 3);
    assert_true(two[3] == 19.0f || two[3] == 20.0f);
    /* Within epsilon everywhere, on a noisy pair. */
    for (int i = 0; i < 40; i++) {
        a[i] = (float)(2.0 + sin(1.7 * i) + 0.1 * i);
        b[i] = (float)(-1.0 + cos(0.9 * i));
    }
    m = light_compress_column2(d, a, b, 40, 0.01, two);
    assert_true(m > 2 && m <= 40);
    for (int i = 0; i < 40; i++) {
        int s = 0;
        while (s + 1 < m && two[3 * (s + 1)] <= d[i])
            s++;
        float va, vb;
        if (s + 1 >= m || d[i] <= two[3 * s]) {
            va = two[3 * s + 1];
            vb = two[3 * s + 2];
        } else {
            float f = (d[i] - two[3 * s]) / (two[3 * (s + 1)] - two[3 * s]);
            va = two[3 * s + 1] + f * (two[3 * (s + 1) + 1] - two[3 * s + 1]);
            vb = two[3 * s + 2] + f * (two[3 * (s + 1) + 2] - two[3 * s + 2]);
        }
        assert_true(fabs(va - a[i]) <= 0.01 + 1e-6 && fabs(vb - b[i]) <= 0.01 + 1e-6);
    }
}

static void test_compress_degenerate(void **state)
{
    float out[64];
    /* Equal depths: a step, and a repeated sample, with epsilon 0. */
    const float d1[] = {0, 1, 1, 2, 2, 2, 3};
    const float v1[] = {1, 0.8f, 0.4f, 0.4f, 0.4f, 0.3f, 0.2f};
    int m = light_compress_column(d1, v1, 7, 0.0, out);
    assert_true(m >= 2 && m <= 7);
    for (int i = 0; i < 2 * m; i++)
        assert_true(isfinite(out[i]));
    for (int i = 1; i < m; i++)
        assert_true(out[2 * i] >= out[2 * (i - 1)]);
    /* Both sides of the step are kept, the later value wins at the step. */
    assert_float_equal(light_column_eval(out, (uint32_t)m, 0.5f), 0.9f, 1e-6);
    assert_float_equal(light_column_eval(out, (uint32_t)m, 1.0f), 0.4f, 1e-6);
    assert_float_equal(light_column_eval(out, (uint32_t)m, 2.0f), 0.3f, 1e-6);
    assert_float_equal(light_column_eval(out, (uint32_t)m, 2.5f), 0.25f, 1e-6);
    /* All samples at one depth. */
    const float d2[] = {5, 5, 5, 5}, v2[] = {0.5f, 0.5f, 0.5f, 0.5f};
    m = light_compress_column(d2, v2, 4, 0.0, out);
    assert_int_equal(m, 1);
    assert_float_equal(light_column_eval(out, 1, 5.0f), 0.5f, 0);
    assert_float_equal(light_column_eval(out, 1, 0.0f), 0.5f, 0);
    /* Epsilon 0 on an exact ramp: two nodes; on a non-linear profile: every sample kept. */
    float d3[16], v3[16];
    for (int i = 0; i < 16; i++) {
        d3[i] = (float)i;
        v3[i] = 1.0f - 0.0625f * i;
    }
    assert_int_equal(light_compress_column(d3, v3, 16, 0.0, out), 2);
    for (int i = 0; i < 16; i++)
        v3[i] = (float)(i * i) / 256.0f;
    assert_int_equal(light_compress_column(d3, v3, 16, 0.0, out), 16);
    /* Flat start and tail: 1 until depth 5, a ramp to 0.5 at depth 9, then 0.5: two nodes,
     * exact with epsilon 0; a constant function is one node. */
    for (int i = 0; i < 16; i++)
        v3[i] = i <= 5 ? 1.0f : i >= 9 ? 0.5f : 1.0f - 0.125f * (float)(i - 5);
    int flat = light_compress_column(d3, v3, 16, 0.0, out);
    assert_int_equal(flat, 2);
    assert_true(out[0] == 5.0f && out[1] == 1.0f && out[2] == 9.0f && out[3] == 0.5f);
    for (int i = 0; i < 16; i++)
        assert_float_equal(light_column_eval(out, 2, d3[i]), v3[i], 1e-6);
    for (int i = 0; i < 16; i++)
        v3[i] = 0.75f;
    assert_int_equal(light_compress_column(d3, v3, 16, 0.0, out), 1);
    assert_true(out[1] == 0.75f);
    /* One sample, none, and bad input. */
    assert_int_equal(light_compress_column(d3, v3, 1, 0.0, out), 1);
    assert_int_equal(light_compress_column(d3, v3, 0, 0.0, out), 0);
    assert_float_equal(light_column_eval(out, 0, 3.0f), 1.0f, 0);
    unsigned errors = log_error_count();
    const float bad_d[] = {0, 2, 1};
    assert_int_equal(light_compress_column(bad_d, v3, 3, 0.0, out), -1);
    assert_int_equal(light_compress_column(d3, v3, 3, -1.0, out), -1);
    assert_int_equal(light_compress_column(d3, v3, 3, NAN, out), -1);
    assert_int_equal(log_error_count(), errors + 3);
}

/* On a smooth profile compression really removes nodes, within the bound. */
static void test_compression_reduces(void **state)
{
    float d[256], v[256], out[512];
    for (int i = 0; i < 256; i++) {
        d[i] = (float)i;
        v[i] = (float)exp(-i / 40.0);
    }
    int m = light_compress_column(d, v, 256, 1e-3, out);
    print_message("exp profile, 256 samples, eps 1e-3: %d nodes\n", m);
    assert_true(m >= 3 && m <= 40);
    for (int i = 0; i < 256; i++)
        assert_true(fabsf(light_column_eval(out, (uint32_t)m, d[i]) - v[i]) <= 1e-3 + 1e-6);

    /* A whole map: the slab's light falls exponentially. */
    struct ext_volume vol;
    make_volume(&vol, 16, 16, 16, 100.0, 100.0, 100.0);
    fill_uniform(&vol, 0.0f, 0.002f);
    struct light_settings s;
    realistic_settings(&s, 32);
    s.resolution[2] = 128;
    double sun[3];
    light_sun_direction(45.0, 60.0, sun);
    struct light_map map = {0};
    assert_true(light_map_build(&vol, sun, &s, &map));
    struct light_compressed c;
    assert_true(light_compressed_build(&map, 0.002, &c));
    print_message("slab 32x32x128 light map, eps 0.002: %zu nodes, %zu of %zu bytes\n",
                  c.node_count, light_compressed_bytes(&c), light_map_bytes(&map));
    assert_true(c.node_count * 8 < (size_t)32 * 32 * 128);
    assert_true(light_compressed_bytes(&c) * 6 < light_map_bytes(&map));
    light_compressed_finish(&c);
    light_compressed_finish(&c);
    light_compressed_finish(NULL);
    light_map_finish(&map);
    ext_volume_finish(&vol);
}

/* ---- rebuild on change -------------------------------------------------------------------- */

static void test_key_and_cache(void **state)
{
    struct ext_volume v;
    make_volume(&v, 8, 8, 8, 100.0, 100.0, 100.0);
    fill_sphere(&v, 4.0);
    struct light_settings s;
    realistic_settings(&s, 12);
    double sun[3];
    light_sun_direction(135.0, 30.0, sun);
    struct light_key k, k2;
    light_key_init(&k, &v.grid, sun, 7, 1, &s);
    double sun2[3] = {2 * sun[0], 2 * sun[1], 2 * sun[2]}; /* same direction */
    light_key_init(&k2, &v.grid, sun2, 7, 1, &s);
    assert_true(light_key_equal(&k, &k2));
    assert_true(light_key_hash(&k) == light_key_hash(&k2));

    struct light_cache cache;
    light_cache_init(&cache);
    struct light_map m = {0};
    struct light_compressed c = {0};
    bool built;
    /* Twelve camera positions, one frame each: the light map does not depend on the camera. */
    for (int cam = 0; cam < 12; cam++) {
        assert_true(light_map_update(&v, &k, &cache, &m, &c, &built));
        assert_true(built == (cam == 0));
    }
    assert_int_equal(cache.builds, 1);
    assert_true(c.node_count > 0);

    /* Each input that matters triggers exactly one rebuild. */
    enum { CHANGES = 13 };
    struct light_key changed[CHANGES];
    for (int i = 0; i < CHANGES; i++)
        changed[i] = k;
    light_sun_direction(136.0, 30.0, changed[0].sun);
    changed[1].volume_id = 8;
    changed[2].volume_generation = 2;
    changed[3].settings.cp.ice_ctr += 0.01;
    changed[4].settings.resolution[2] = 13;
    changed[5].settings.peripheral = false;
    changed[6].settings.epsilon = 0.01;
    changed[7].box.spacing[0] = 101.0;
    changed[8].settings.substeps = 3;
    /* Multiple scattering: the switch alone, and the two-stream terms it reads. */
    changed[9].settings.multiple = true;
    changed[10].settings.cp.water_cs_g += 0.01;
    changed[11].settings.cp.ice_gamma += 0.01;
    /* The same box on the model's own levels (a stretched grid). */
    const double zc[8] = {20.0, 60.0, 120.0, 200.0, 300.0, 450.0, 600.0, 750.0};
    assert_true(grid3_set_levels(&changed[12].box, zc, 8, k.box.origin[2],
                                 k.box.origin[2] + 8 * k.box.spacing[2]));
    for (int i = 0; i < CHANGES; i++) {
        assert_false(light_key_equal(&k, &changed[i]));
        assert_true(light_key_hash(&k) != light_key_hash(&changed[i]));
        unsigned before = cache.builds;
        if (i == 7 || i == 12) { /* a different box must come with its volume */
            assert_true(light_cache_stale(&cache, &changed[i]));
            continue;
        }
        assert_true(light_map_update(&v, &changed[i], &cache, &m, NULL, &built));
        assert_true(built);
        assert_true(light_map_update(&v, &changed[i], &cache, &m, NULL, &built));
        assert_false(built);
        assert_int_equal(cache.builds, before + 1);
    }
    assert_true(cache.total_ms >= cache.last_ms && cache.last_ms >= 0.0);
    light_cache_invalidate(&cache);
    assert_true(light_cache_stale(&cache, &changed[6]));
    light_compressed_finish(&c);
    light_map_finish(&m);
    ext_volume_finish(&v);
}

/* ---- memory figures on the procedural storm (docs/lightmap.md) ---------------------------- */

static void test_storm_memory_figures(void **state)
{
    struct synth_desc d = {.kind = SYNTH_STORM,
                           .n = {128, 128, 64},
                           .extent_m = {60000.0, 60000.0, 16000.0},
                           .seed = 1,
                           .time = 0.5};
    struct ext_volume v;
    if (!synth_extinction(&d, NULL, &v)) {
        print_message("synthetic storm unavailable; skipping memory figures\n");
        return;
    }
    struct light_settings s;
    realistic_settings(&s, 128);
    double sun[3];
    light_sun_direction(135.0, 35.0, sun); /* the default scene's sun */
    struct light_map m = {0};
    double t0 = time_now_ms();
    assert_true(light_map_build(&v, sun, &s, &m));
    double ms = time_now_ms() - t0;
    assert_all_in_unit(&m);
    print_message("default storm (128x128x64 voxels), light map 128^3, sun az 135 el 35:\n"
                  "  max beta %.3g /m, %d sub-steps, build %.0f ms, min light %.3g, dense %zu "
                  "bytes\n",
                  ext_volume_max_beta(&v), m.substeps, ms, (double)map_min(&m),
                  light_map_bytes(&m));
    size_t prev = SIZE_MAX;
    const double eps[] = {0.0, 0.001, 0.002, 0.005, 0.01, 0.02};
    for (size_t e = 0; e < sizeof eps / sizeof eps[0]; e++) {
        struct light_compressed c;
        t0 = time_now_ms();
        assert_true(light_compressed_build(&m, eps[e], &c));
        double cms = time_now_ms() - t0;
        size_t bytes = light_compressed_bytes(&c);
        float worst = 0.0f;
        for (int t = 0; t < 20000; t++) {
            float tex[3] = {(float)rnd(), (float)rnd(), (float)rnd()};
            worst =
                fmaxf(worst, fabsf(light_map_sample(&m, tex) - light_compressed_sample(&c, tex)));
        }
        uint32_t most = 0;
        size_t busy = 0, busy_nodes = 0; /* columns that cross the storm */
        for (size_t col = 0; col < (size_t)128 * 128; col++) {
            uint32_t cnt = c.columns[2 * col + 1];
            most = cnt > most ? cnt : most;
            if (cnt > 2)
                busy++, busy_nodes += cnt;
        }
        print_message("  eps %-6g %zu columns with > 2 nodes, %.1f nodes each\n", eps[e], busy,
                      busy ? (double)busy_nodes / busy : 0.0);
        print_message("  eps %-6g nodes %9zu (%.2f per column, max %u) bytes %10zu (%.1f%% of "
                      "dense) compress %.0f ms, worst sampled error %.2g\n",
                      eps[e], c.node_count, (double)c.node_count / (128.0 * 128.0), most, bytes,
                      100.0 * bytes / light_map_bytes(&m), cms, (double)worst);
        assert_true(worst <= eps[e] + 1e-5);
        assert_true(bytes <= prev);
        prev = bytes;
        light_compressed_finish(&c);
    }
    light_map_finish(&m);
    ext_volume_finish(&v);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sun_direction),
        cmocka_unit_test(test_grid_frame_and_mapping),
        cmocka_unit_test(test_grid_rejects_bad_input),
        cmocka_unit_test(test_peripheral_offset),
        cmocka_unit_test(test_beta_sampling),
        cmocka_unit_test(test_empty_volume_all_ones),
        cmocka_unit_test(test_slab_closed_form_overhead),
        cmocka_unit_test(test_slab_closed_form_oblique),
        cmocka_unit_test(test_single_voxel),
        cmocka_unit_test(test_axis_and_grazing_sun),
        cmocka_unit_test(test_very_thick),
        cmocka_unit_test(test_shadow_monotone),
        cmocka_unit_test(test_forward_at_least_shadow),
        cmocka_unit_test(test_peripheral_spreads_light),
        cmocka_unit_test(test_silver_lining),
        cmocka_unit_test(test_substeps_flat_volume),
        cmocka_unit_test(test_sheared_grid_frame),
        cmocka_unit_test(test_sheared_grid_resolves_a_flat_layer),
        cmocka_unit_test(test_beam_slice_count_independent),
        cmocka_unit_test(test_diffuse_column_conserves_energy),
        cmocka_unit_test(test_diffuse_column_slice_count_independent),
        cmocka_unit_test(test_diffuse_column_matches_ode),
        cmocka_unit_test(test_diffuse_column_escape_matches_ode),
        cmocka_unit_test(test_lateral_escape_rate),
        cmocka_unit_test(test_lateral_rates),
        cmocka_unit_test(test_diffuse_column_extreme),
        cmocka_unit_test(test_diffuse_map_sphere_and_storm),
        cmocka_unit_test(test_diffuse_map_layer),
        cmocka_unit_test(test_compressed_within_epsilon),
        cmocka_unit_test(test_compress_degenerate),
        cmocka_unit_test(test_compress_two_channels),
        cmocka_unit_test(test_compression_reduces),
        cmocka_unit_test(test_key_and_cache),
        cmocka_unit_test(test_storm_memory_figures),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
