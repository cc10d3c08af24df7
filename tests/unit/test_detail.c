/* Procedural detail (Riley §4.5) and height exaggeration on the CPU volumes. */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "data/detail.h"
#include "data/synth.h"
#include "data/volume.h"

static struct synth_desc storm(void)
{
    return (struct synth_desc){.kind = SYNTH_STORM, .n = {32, 32, 16},
                               .extent_m = {60e3, 60e3, 16e3}, .seed = 1, .time = 0.5};
}

static struct detail_desc detail_on(unsigned seed, double amount)
{
    struct detail_desc d = {.on = true, .scale_m = 3e3, .seed = seed};
    for (int f = 0; f < SPECIES_COUNT; f++)
        d.amount[f] = amount;
    return d;
}

static bool same_fields(const struct field_volume *a, const struct field_volume *b)
{
    size_t n = grid3_count(&a->grid);
    for (int f = 0; f < SPECIES_COUNT; f++) {
        if (!a->q[f] != !b->q[f])
            return false;
        if (a->q[f] && memcmp(a->q[f], b->q[f], n * sizeof(float)) != 0)
            return false;
    }
    return true;
}

static void detailed(const struct detail_desc *d, struct field_volume *out)
{
    struct synth_desc s = storm();
    assert_true(synth_storm_fields(&s, out));
    detail_apply_fields(d, out);
}

static void test_same_seed_same_volume(void **state)
{
    struct detail_desc d = detail_on(7, 0.6);
    struct field_volume a, b, c, plain;
    detailed(&d, &a);
    detailed(&d, &b);
    assert_true(same_fields(&a, &b));
    /* Another seed is another volume, and detail changes the storm at all. */
    struct detail_desc d2 = detail_on(8, 0.6);
    detailed(&d2, &c);
    assert_false(same_fields(&a, &c));
    struct detail_desc off = {0};
    detailed(&off, &plain);
    assert_false(same_fields(&a, &plain));
    field_volume_finish(&a);
    field_volume_finish(&b);
    field_volume_finish(&c);
    field_volume_finish(&plain);
}

static void test_amount_zero_is_off(void **state)
{
    struct detail_desc zero = detail_on(3, 0.0), off = {0};
    off.amount[SPECIES_CLOUD] = 0.8; /* ignored: off */
    struct field_volume a, b;
    detailed(&zero, &a);
    detailed(&off, &b);
    assert_true(same_fields(&a, &b));
    field_volume_finish(&a);
    field_volume_finish(&b);

    /* One species' amount touches that species only. */
    struct detail_desc cloud = detail_on(3, 0.0);
    cloud.amount[SPECIES_CLOUD] = 0.7;
    detailed(&cloud, &a);
    detailed(&off, &b);
    size_t n = grid3_count(&a.grid);
    assert_non_null(a.q[SPECIES_CLOUD]);
    assert_memory_not_equal(a.q[SPECIES_CLOUD], b.q[SPECIES_CLOUD], n * sizeof(float));
    for (int f = SPECIES_RAIN; f < SPECIES_COUNT; f++) {
        if (a.q[f])
            assert_memory_equal(a.q[f], b.q[f], n * sizeof(float));
    }
    /* Empty air stays empty, mass stays non-negative. */
    for (size_t i = 0; i < n; i++) {
        if (b.q[SPECIES_CLOUD][i] == 0.0f)
            assert_true(a.q[SPECIES_CLOUD][i] == 0.0f);
        assert_true(a.q[SPECIES_CLOUD][i] >= 0.0f);
    }
    field_volume_finish(&a);
    field_volume_finish(&b);
}

static void test_factor_statistics(void **state)
{
    /* Over many points the factor averages close to 1 (detail moves mass, it adds little),
     * stays in [1 - a, 1 + a], and varies: each style spreads over a good part of its range. */
    for (int f = 0; f < SPECIES_COUNT; f++) {
        struct detail_desc d = detail_on(11, 0.5);
        double sum = 0.0, lo = INFINITY, hi = -INFINITY;
        int n = 0;
        for (int k = 0; k < 20; k++) {
            for (int j = 0; j < 40; j++) {
                for (int i = 0; i < 40; i++) {
                    double p[3] = {i * 1370.0, j * 1130.0, k * 610.0};
                    double m = detail_factor(&d, (enum species)f, p);
                    assert_true(m >= 0.5 - 1e-9 && m <= 1.5 + 1e-9);
                    sum += m;
                    lo = fmin(lo, m);
                    hi = fmax(hi, m);
                    n++;
                }
            }
        }
        double mean = sum / n;
        assert_true(fabs(mean - 1.0) < 0.2);
        assert_true(hi - lo > 0.4);
        /* Off or amount 0: exactly 1. */
        const double p[3] = {1, 2, 3};
        d.on = false;
        assert_true(detail_factor(&d, (enum species)f, p) == 1.0);
        d.on = true;
        d.amount[f] = 0.0;
        assert_true(detail_factor(&d, (enum species)f, p) == 1.0);
    }
}

static void test_extinction_channels(void **state)
{
    /* Extinction files: the ice channel takes ice's noise, the water channel cloud's. */
    struct grid3 g = {.n = {16, 16, 8}, .spacing = {1e3, 1e3, 500}};
    struct ext_volume a, b;
    assert_true(ext_volume_init(&a, &g));
    assert_true(ext_volume_init(&b, &g));
    for (size_t i = 0; i < 2 * grid3_count(&g); i++)
        a.beta[i] = b.beta[i] = 1e-3f;
    struct detail_desc d = detail_on(5, 0.0);
    d.amount[SPECIES_ICE] = 0.9;
    detail_apply_ext(&d, &a);
    bool ice_changed = false;
    for (size_t i = 0; i < grid3_count(&g); i++) {
        ice_changed |= a.beta[2 * i] != b.beta[2 * i];
        assert_true(a.beta[2 * i + 1] == b.beta[2 * i + 1]);
    }
    assert_true(ice_changed);
    ext_volume_finish(&a);
    ext_volume_finish(&b);
}

static void test_stretch_keeps_column_optical_depth(void **state)
{
    struct synth_desc s = storm();
    struct ext_volume a, b;
    assert_true(synth_extinction(&s, NULL, &a));
    assert_true(synth_extinction(&s, NULL, &b));
    ext_volume_stretch_height(&b, 5.0);
    assert_float_equal(b.grid.spacing[2], 5.0 * a.grid.spacing[2], 1e-9);
    assert_float_equal(b.grid.origin[2], 5.0 * a.grid.origin[2], 1e-9);
    assert_float_equal(b.grid.spacing[0], a.grid.spacing[0], 0.0);
    for (int j = 0; j < a.grid.n[1]; j += 3) {
        for (int i = 0; i < a.grid.n[0]; i += 3) {
            double ta = 0.0, tb = 0.0;
            for (int k = 0; k < a.grid.n[2]; k++) {
                size_t v = grid3_index(&a.grid, i, j, k);
                ta += (a.beta[2 * v] + a.beta[2 * v + 1]) * a.grid.spacing[2];
                tb += (b.beta[2 * v] + b.beta[2 * v + 1]) * b.grid.spacing[2];
            }
            assert_float_equal(tb, ta, 1e-5 * (ta + 1e-9));
        }
    }
    /* k = 1 changes nothing. */
    struct ext_volume c;
    assert_true(synth_extinction(&s, NULL, &c));
    ext_volume_stretch_height(&c, 1.0);
    assert_memory_equal(c.beta, a.beta, 2 * grid3_count(&a.grid) * sizeof(float));
    ext_volume_finish(&a);
    ext_volume_finish(&b);
    ext_volume_finish(&c);
}

int main(void)
{
    log_set_level(LOG_NONE);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_same_seed_same_volume),
        cmocka_unit_test(test_amount_zero_is_off),
        cmocka_unit_test(test_factor_statistics),
        cmocka_unit_test(test_extinction_channels),
        cmocka_unit_test(test_stretch_keeps_column_optical_depth),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
