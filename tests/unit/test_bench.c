/* The quality benchmark's verdicts (bench/bench.h, bench/tables.h): which settings do the same
 * work, how their timings are pooled, when one setting beats another on the Pareto front, and
 * what the accuracy table says about it. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include "bench/bench.h"
#include "bench/tables.h"
#include "common/log.h"

/* A dense 64^3 map with forward, peripheral and multiple scattering, the default ray step,
 * and two phases whose forward-scattering terms differ (the mix is compiled in). */
static struct bench_variant variant(double theta)
{
    struct bench_variant v;
    memset(&v, 0, sizeof(v));
    v.shadows = true;
    v.mode = LIGHT_GPU_DENSE;
    light_settings_defaults(&v.light);
    for (int a = 0; a < 3; a++)
        v.light.resolution[a] = 64;
    v.light.forward_angle_deg = theta;
    v.light.cp.water_ctr = 0.01 * theta;
    v.light.cp.water_per = 0.005 * theta;
    v.light.cp.ice_ctr = 0.008 * theta;
    v.light.cp.ice_per = 0.004 * theta;
    v.light.multiple = true;
    return v;
}

static struct bench_result result(struct bench_variant v, const double *build, int n_build,
                                  const double *view, int n_view)
{
    struct bench_result r;
    memset(&r, 0, sizeof(r));
    r.v = v;
    memcpy(r.build_samples, build, sizeof(double) * (size_t)n_build);
    r.n_build_samples = n_build;
    memcpy(r.view_samples, view, sizeof(double) * (size_t)n_view);
    r.n_view_samples = n_view;
    bench_timings_finish(&r);
    return r;
}

static void test_same_work(void **state)
{
    (void)state;
    struct bench_variant a = variant(20.0), b = variant(30.0);
    /* The forward angle only changes constants of one shader. */
    assert_true(bench_same_work(&a, &b));
    assert_true(bench_same_work(&b, &a));

    struct bench_variant c = b;
    c.step_m = 100.0f; /* another ray step: another eye pass */
    assert_false(bench_same_work(&a, &c));
    c = b;
    c.light.resolution[2] = 128;
    assert_false(bench_same_work(&a, &c));
    c = b;
    c.light.peripheral = false; /* compiled out */
    assert_false(bench_same_work(&a, &c));
    c = b;
    c.mode = LIGHT_GPU_COMPRESSED;
    assert_false(bench_same_work(&a, &c));
    c = b;
    c.light.multiple = false;
    assert_false(bench_same_work(&a, &c));
    /* One phase for both species compiles the mix out: not the same shader. */
    c = b;
    c.light.cp.ice_ctr = c.light.cp.water_ctr;
    c.light.cp.ice_per = c.light.cp.water_per;
    assert_true(light_settings_phases_equal(&c.light));
    assert_false(bench_same_work(&a, &c));
    /* Without a light map nothing of the map matters. */
    a.shadows = c.shadows = false;
    assert_true(bench_same_work(&a, &c));
}

static void test_pool_timings(void **state)
{
    (void)state;
    const double slow[] = {80.0, 90.0, 100.0}, fast[] = {60.0, 62.0, 64.0};
    const double other[] = {50.0, 52.0, 54.0};
    const double view_a[] = {10.0, 11.0, 12.0}, view_b[] = {7.0, 8.0, 9.0};
    struct bench_variant per_off = variant(20.0), fine = variant(20.0);
    per_off.light.peripheral = false;
    fine.step_m = 50.0f;
    struct bench_result res[4] = {
        result(variant(20.0), slow, 3, view_a, 3), /* the default, under load */
        result(variant(30.0), fast, 3, view_b, 3), /* the same work, a quiet moment */
        result(per_off, other, 3, view_b, 3),      /* less work */
        result(fine, fast, 3, view_a, 3),          /* the default's map, a finer eye pass */
    };
    assert_true(fabs(res[0].build_ms - 90.0) <= 1e-12);
    assert_true(fabs(res[1].build_ms - 62.0) <= 1e-12);
    bench_pool_timings(res, 4);
    /* The default, theta 30 and the finer eye pass build the same map: all nine samples,
     * sorted 60 60 62 62 64 64 80 90 100, median 64. */
    assert_true(fabs(res[0].build_ms - 64.0) <= 1e-12);
    assert_true(fabs(res[1].build_ms - 64.0) <= 1e-12);
    assert_true(fabs(res[3].build_ms - 64.0) <= 1e-12);
    assert_true(res[0].build_spread > 0.0);
    /* Their views: the default and theta 30 pool (7 8 9 10 11 12, median 9.5); the finer
     * step keeps its own, and so does the map without its peripheral ring. */
    assert_true(fabs(res[0].view_ms - 9.5) <= 1e-12);
    assert_true(fabs(res[1].view_ms - 9.5) <= 1e-12);
    assert_true(fabs(res[3].view_ms - 11.0) <= 1e-12);
    assert_true(fabs(res[2].build_ms - 52.0) <= 1e-12);
    assert_true(fabs(res[2].view_ms - 8.0) <= 1e-12);
    /* The samples themselves are left as measured. */
    assert_true(res[0].build_samples[0] == 80.0 && res[1].build_samples[0] == 60.0);
}

/* A result of MS milliseconds (all of it the build, scattering by SPREAD) and error ERR; results
 * of different times build different maps, so none shares another's timings. */
static struct bench_result timed(double ms, double spread, double err)
{
    struct bench_result r;
    memset(&r, 0, sizeof(r));
    r.v = variant(20.0);
    r.v.light.resolution[2] = 16 + (int)ms;
    r.build_ms = ms;
    r.build_spread = spread;
    r.rmse_model = err;
    r.self_rmse = 2.0 * err;
    return r;
}

static void test_beats_beyond_noise(void **state)
{
    (void)state;
    struct bench_result a = timed(100.0, 0.0, 1.0);
    /* Faster by more than the 10 % floor, no worse: beats. */
    struct bench_result b = timed(85.0, 0.0, 1.0);
    assert_true(bench_beats(&b, &a, false));
    assert_true(bench_beats(&b, &a, true));
    assert_false(bench_beats(&a, &b, false));
    /* Within the floor: a tie. */
    b = timed(95.0, 0.0, 1.0);
    assert_false(bench_beats(&b, &a, false));
    assert_true(bench_no_worse(&b, &a, false));
    /* The repeats' spread widens the margin: 15 % faster, but a spread of 20 %. */
    b = timed(85.0, 17.0, 1.0);
    assert_false(bench_beats(&b, &a, false));
    /* Better error beyond 1 % at the same time: beats; within 1 %: a tie. */
    b = timed(100.0, 0.0, 0.98);
    assert_true(bench_beats(&b, &a, false));
    b = timed(100.0, 0.0, 0.995);
    assert_false(bench_beats(&b, &a, false));
    /* Faster but worse: neither beats the other. */
    b = timed(50.0, 0.0, 1.2);
    assert_false(bench_beats(&b, &a, false));
    assert_false(bench_beats(&a, &b, false));
}

static void test_shared_timings_do_not_widen_the_margin(void **state)
{
    (void)state;
    /* The default and a coarser ray step build the same map: pooled, their build is one
     * median (80 ms) whatever its scatter (1.48 x MAD 20 = 29.6 ms, 30 %).  The coarser step's
     * view is 15 ms faster, 15 % of the whole: beyond the 10 % floor, it beats the default. */
    const double builds[] = {50.0, 110.0, 80.0, 60.0, 100.0};
    const double fine[] = {20.0, 21.0, 19.0, 20.0, 20.0}, coarse[] = {5.0, 5.0, 6.0, 5.0, 4.0};
    struct bench_variant dv = variant(20.0), cv = variant(20.0);
    cv.step_m = 500.0f;
    struct bench_result res[2] = {result(dv, builds, 5, fine, 5), result(cv, builds, 5, coarse, 5)};
    bench_pool_timings(res, 2);
    assert_true(fabs(res[0].build_ms - 80.0) <= 1e-12 && fabs(res[1].build_ms - 80.0) <= 1e-12);
    assert_true(res[0].build_spread > 0.25 * 100.0);
    for (int self = 0; self < 2; self++) {
        res[0].rmse_model = res[1].rmse_model = 1.0;
        res[0].self_rmse = res[1].self_rmse = 1.0;
        assert_true(bench_beats(&res[1], &res[0], self));
    }
    /* Another map, as scattered: its build's spread counts, and 15 % is inside it. */
    cv.light.resolution[2] = 128;
    struct bench_result other[2] = {result(dv, builds, 5, fine, 5),
                                    result(cv, builds, 5, coarse, 5)};
    bench_pool_timings(other, 2);
    other[0].rmse_model = other[1].rmse_model = 1.0;
    assert_false(bench_beats(&other[1], &other[0], false));
    assert_true(bench_no_worse(&other[1], &other[0], false));
}

static void test_pareto(void **state)
{
    (void)state;
    struct bench_result res[4] = {
        timed(100.0, 0.0, 1.0), /* beaten by the next */
        timed(80.0, 0.0, 0.9),
        timed(40.0, 0.0, 2.0),  /* fastest */
        timed(400.0, 0.0, 0.5), /* most accurate */
    };
    bench_pareto(res, 4);
    assert_false(res[0].pareto);
    assert_true(res[1].pareto && res[2].pareto && res[3].pareto);
    /* Pooled equal timings leave a tie to the error: 0.995 is within its noise. */
    res[0] = timed(80.0, 0.0, 0.995);
    res[1] = timed(80.0, 0.0, 1.0);
    bench_pareto(res, 2);
    assert_true(res[0].pareto && res[1].pareto);
}

/* One scene of the accuracy table: a default of 100 ms and error 1, then the settings. */
static void scene(struct bench_scene_results *s, const char *name, const struct bench_result *res,
                  int n)
{
    memset(s, 0, sizeof(*s));
    snprintf(s->name, sizeof(s->name), "%s", name);
    for (int i = 0; i < n; i++) {
        s->res[i] = res[i];
        snprintf(s->res[i].v.knob, sizeof(s->res[i].v.knob), "%s", i ? "ray step" : "default");
        snprintf(s->res[i].v.value, sizeof(s->res[i].v.value), "%d voxel", i);
        s->res[i].v.is_default = i == 0;
    }
    s->n = n;
    bench_pareto(s->res, n);
}

/* The verdicts as the accuracy table writes them. */
static char *verdicts(const struct bench_scene_results *s, int n, bool self)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    for (int i = 0; i < n; i++)
        bench_write_verdict(f, &s[i], self);
    bench_write_verdict_across(f, s, n, self);
    fclose(f);
    return buf;
}

static void test_verdicts(void **state)
{
    (void)state;
    static struct bench_scene_results s[2];
    /* On the storm, "ray step 1 voxel" is 20 % faster and as accurate: the default is beaten;
     * on the sphere it is as fast but worse: no verdict across the scenes. */
    const struct bench_result storm[] = {timed(100.0, 0.0, 1.0), timed(80.0, 0.0, 1.0)};
    const struct bench_result sphere[] = {timed(100.0, 0.0, 1.0), timed(100.0, 0.0, 1.5)};
    scene(&s[0], "storm", storm, 2);
    scene(&s[1], "sphere", sphere, 2);
    char *text = verdicts(s, 2, false);
    assert_string_equal(text,
                        "- **storm**, against Monte Carlo: the default is *not* on the Pareto "
                        "front; beaten by ray step 1 voxel (0.80× the time, error 1 vs 1);\n"
                        "- **sphere**, against Monte Carlo: the default is on the Pareto front.\n"
                        "- **Every scene**, against Monte Carlo: the defaults are on the Pareto "
                        "front: no setting is as fast and as accurate on every scene and better "
                        "on one.\n");
    free(text);
    /* Faster on the sphere too (within the noise in error): beaten on every scene. */
    const struct bench_result both[] = {timed(100.0, 0.0, 1.0), timed(100.0, 0.0, 1.005)};
    scene(&s[1], "sphere", both, 2);
    text = verdicts(s, 2, true);
    assert_non_null(strstr(text, "- **Every scene**, against the converged renderer: the "
                                 "defaults are *not* on the Pareto front; beaten on every "
                                 "scene by ray step 1 voxel;\n"));
    free(text);
    /* One scene: no verdict across scenes. */
    text = verdicts(s, 1, false);
    assert_null(strstr(text, "Every scene"));
    free(text);
}

static size_t count_rgb(const uint8_t *rgb, int w, int h, const uint8_t col[3])
{
    size_t k = 0;
    for (size_t i = 0; i < (size_t)w * h; i++)
        k += memcmp(&rgb[3 * i], col, 3) == 0;
    return k;
}

/* Both tiers of multiple scattering in the plot: the 3-D diffusion row gets its own marker and
 * a key, on both plots, and a sweep without that row draws neither. */
static void test_plot_marks_the_volume_tier(void **state)
{
    (void)state;
    struct bench_result res[3] = {timed(100.0, 0.0, 1.0), timed(50.0, 0.0, 2.0),
                                  timed(300.0, 0.0, 0.8)};
    res[0].v.is_default = true;
    res[1].v.light.multiple = false;
    const struct bench_result *all[1] = {res};
    const char *names[1] = {"storm"};
    int n[1] = {3}, w = 0, h = 0;
    for (int self = 0; self < 2; self++) {
        res[2].v.light.volume = false;
        uint8_t *rgb = bench_plot_rgb("t", 1, names, all, n, self, &w, &h);
        assert_non_null(rgb);
        assert_int_equal(count_rgb(rgb, w, h, bench_plot_volume_rgb), 0);
        free(rgb);
        res[2].v.light.volume = true;
        assert_true(bench_is_volume_tier(&res[2].v));
        rgb = bench_plot_rgb("t", 1, names, all, n, self, &w, &h);
        assert_non_null(rgb);
        /* The square (7 px half-width, 2 px thick: 4 * 2 * 15 px less the corners) and the
         * key's square and words. */
        assert_true(count_rgb(rgb, w, h, bench_plot_volume_rgb) > 100);
        free(rgb);
    }
    /* Without multiple scattering (or without the light map) "volume" is no tier. */
    res[2].v.light.multiple = false;
    assert_false(bench_is_volume_tier(&res[2].v));
    res[2].v.light.multiple = true;
    res[2].v.shadows = false;
    assert_false(bench_is_volume_tier(&res[2].v));
}

/* The key goes to the corner of the plot with fewest points: with the 3-D diffusion row the
 * slowest and worst (top right), the top-right quarter of the panel holds that row's square and
 * nothing else green, and the key's green square and words are elsewhere. */
static void test_plot_key_avoids_the_points(void **state)
{
    (void)state;
    struct bench_result res[4] = {timed(100.0, 0.0, 1.0), timed(50.0, 0.0, 2.0),
                                  timed(300.0, 0.0, 0.8), timed(1000.0, 0.0, 3.0)};
    res[0].v.is_default = true;
    res[3].v.light.volume = true;
    const struct bench_result *all[1] = {res};
    const char *names[1] = {"storm"};
    int n[1] = {4}, w = 0, h = 0;
    uint8_t *rgb = bench_plot_rgb("t", 1, names, all, n, false, &w, &h);
    assert_non_null(rgb);
    size_t top_right = 0, all_green = 0;
    for (int y = 0; y < h; y++) {
        for (int x = 0; x < w; x++) {
            bool green = memcmp(&rgb[3 * ((size_t)y * w + x)], bench_plot_volume_rgb, 3) == 0;
            all_green += green;
            top_right += green && x >= w / 2 && y < h / 2;
        }
    }
    free(rgb);
    /* The marker: a square 15 px wide, 2 px thick. */
    assert_in_range(top_right, 100, 120);
    assert_true(all_green > top_right + 100);
}

int main(void)
{
    log_set_level(LOG_WARN);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_same_work),
        cmocka_unit_test(test_pool_timings),
        cmocka_unit_test(test_beats_beyond_noise),
        cmocka_unit_test(test_shared_timings_do_not_widen_the_margin),
        cmocka_unit_test(test_pareto),
        cmocka_unit_test(test_verdicts),
        cmocka_unit_test(test_plot_marks_the_volume_tier),
        cmocka_unit_test(test_plot_key_avoids_the_points),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
