/* Hard cases of SPEC.md on the CPU side: the Monte Carlo reference through a single voxel,
 * along axes and at grazing angles, through a 1000:1 volume, with |g| -> 1; the light map
 * reference (with its diffuse light) and the optics tables with |g| -> 1.  docs/stability.md
 * lists every case. */
#include <math.h>
#include <string.h>

#include "testutil.h"

#include "common/log.h"
#include "data/synth.h"
#include "light/light.h"
#include "optics/optics.h"
#include "reference/reference.h"

static struct reference *slab_reference(int nx, int ny, int nz, double ex, double ey, double ez,
                                        double tau, struct ext_volume *vol)
{
    struct synth_desc d = {.kind = SYNTH_SLAB, .n = {nx, ny, nz}, .extent_m = {ex, ey, ez},
                           .tau = tau};
    struct optics_params optics;
    optics_params_defaults(&optics);
    assert_true(synth_extinction(&d, &optics, vol));
    struct reference_desc rd;
    reference_desc_defaults(&rd);
    struct reference *ref = reference_create(vol, &rd);
    assert_non_null(ref);
    return ref;
}

static double transmittance(const struct reference *ref, const double o[3], double dx, double dy,
                            double dz)
{
    double n = sqrt(dx * dx + dy * dy + dz * dz);
    double dir[3] = {dx / n, dy / n, dz / n};
    struct reference_rng rng;
    reference_rng_seed(&rng, 7, 0);
    double t = reference_transmittance(ref, o, dir, 0.0, 1e12, &rng);
    assert_true(isfinite(t) && t >= 0.0 && t <= 1.0);
    return t;
}

static void test_reference_single_voxel_and_axes(void **state)
{
    /* One voxel of 1 x 1 x 1 km, vertical optical depth 3: a homogeneous block, so residual
     * ratio tracking is exact along any direction, including exactly along an axis. */
    struct ext_volume vol = {0};
    struct reference *ref = slab_reference(1, 1, 1, 1e3, 1e3, 1e3, 3.0, &vol);
    double above[3] = {500, 500, 5e3}, west[3] = {-5e3, 500, 500}, south[3] = {500, -5e3, 500};
    assert_float_equal(transmittance(ref, above, 0, 0, -1), exp(-3.0), 1e-12);
    assert_float_equal(transmittance(ref, west, 1, 0, 0), exp(-3.0), 1e-12);
    assert_float_equal(transmittance(ref, south, 0, 1, 0), exp(-3.0), 1e-12);
    /* Grazing: a ray along the top face (z = 1 km exactly) and one just below it. */
    double on_face[3] = {-5e3, 500, 1e3};
    transmittance(ref, on_face, 1, 0, 0); /* on the boundary: finite and in [0, 1] */
    double grazing[3] = {-5e3, 500, 999.999};
    assert_float_equal(transmittance(ref, grazing, 1, 1e-15, 0), exp(-3.0), 1e-9);
    /* Direction components of 1e-300: no division blows up. */
    assert_float_equal(transmittance(ref, west, 1, 1e-300, -1e-300), exp(-3.0), 1e-12);
    reference_destroy(ref);
    ext_volume_finish(&vol);
}

static void test_reference_extreme_aspect(void **state)
{
    /* 1000 x 1000 x 1 km: straight down e^-tau, at 60 degrees from vertical e^-2 tau. */
    struct ext_volume vol = {0};
    struct reference *ref = slab_reference(64, 64, 2, 1e6, 1e6, 1e3, 2.0, &vol);
    double o[3] = {5e5, 5e5, 2e3};
    /* (beta is float32: relative 1e-6) */
    assert_float_equal(transmittance(ref, o, 0, 0, -1), exp(-2.0), 1e-6 * exp(-2.0));
    assert_float_equal(transmittance(ref, o, sin(M_PI / 3), 0, -cos(M_PI / 3)), exp(-4.0),
                       1e-6 * exp(-4.0));
    /* And lying flat inside it: the whole 1000 km width at tau 2 per km (2000): zero. */
    double side[3] = {-1e3, 5e5, 500};
    assert_true(transmittance(ref, side, 1, 0, 0) < 1e-300);
    reference_destroy(ref);
    ext_volume_finish(&vol);
}

static void test_extreme_asymmetry(void **state)
{
    /* Samplers stay in [-1, 1] and follow the clamped g; the phase tables and the cumulative
     * phases stay finite, non-negative and within [0, 1]. */
    static const double gs[] = {-1.0, -0.999999, 0.999999, 1.0};
    struct reference_rng rng;
    reference_rng_seed(&rng, 3, 1);
    for (size_t i = 0; i < sizeof(gs) / sizeof(gs[0]); i++) {
        double sum_hg = 0.0, sum_cs = 0.0;
        const int n = 20000;
        for (int k = 0; k < n; k++) {
            double a = reference_sample_hg(gs[i], &rng), b = reference_sample_cs(gs[i], &rng);
            assert_true(isfinite(a) && a >= -1.0 && a <= 1.0);
            assert_true(isfinite(b) && b >= -1.0 && b <= 1.0);
            sum_hg += a;
            sum_cs += b;
        }
        double sign = gs[i] > 0 ? 1.0 : -1.0;
        assert_true(sign * sum_hg / n > 0.99);
        assert_true(sign * sum_cs / n > 0.99);

        struct optics_params optics;
        optics_params_defaults(&optics);
        optics.g_water = gs[i];
        optics.g_ice = -gs[i];
        float table[2 * 256];
        optics_eye_phase_table(&optics, 256, table);
        for (int k = 0; k < 2 * 256; k++)
            assert_true(isfinite(table[k]) && table[k] >= 0.0f);
        struct optics_cp cp;
        optics_forward_cp(&optics, 20.0 * M_PI / 180.0, &cp);
        assert_true(cp.water_ctr >= 0.0 && cp.water_per >= 0.0);
        assert_true(cp.water_ctr + cp.water_per <= 1.0 + 1e-9);
        assert_true(cp.ice_ctr >= 0.0 && cp.ice_per >= 0.0);
        assert_true(cp.ice_ctr + cp.ice_per <= 1.0 + 1e-9);

        /* The two-stream terms: a backward share in [0, 1] at any sun, a coupling in
         * [0, 1.5]. */
        for (double mu0 = 0.0; mu0 <= 1.0; mu0 += 0.25) {
            double bw = phase_cs_back_fraction(cp.water_cs_g, 0.1, mu0);
            double bi = phase_cs_back_fraction(cp.ice_cs_g, 0.1, mu0);
            assert_true(bw >= 0.0 && bw <= 1.0 && bi >= 0.0 && bi <= 1.0);
        }
        assert_true(cp.water_gamma >= 0.0 && cp.water_gamma <= 1.5);
        assert_true(cp.ice_gamma >= 0.0 && cp.ice_gamma <= 1.5);

        /* The CPU light map with these phases: in [0, 1] everywhere; its diffuse light (g -> 1:
         * nothing leaves the beam, no coupling; g -> -1: all of it backward) finite, M >= 0,
         * |N| <= M. */
        struct synth_desc d = {.kind = SYNTH_SPHERE, .n = {12, 12, 12},
                               .extent_m = {1e3, 1e3, 1e3}, .tau = 50.0};
        struct ext_volume vol = {0};
        assert_true(synth_extinction(&d, &optics, &vol));
        struct light_settings s;
        light_settings_defaults(&s);
        s.resolution[0] = s.resolution[1] = s.resolution[2] = 12;
        light_settings_set_optics(&s, &optics, 20.0);
        s.multiple = true;
        double sun[3] = {0.3, 0.2, 0.9};
        struct light_map map = {0};
        assert_true(light_map_build(&vol, sun, &s, &map));
        for (int k = 0; k < 12 * 12 * 12; k++) {
            assert_true(isfinite(map.light[k]) && map.light[k] >= 0.0f && map.light[k] <= 1.0f);
            float m = map.diffuse[2 * k], nn = map.diffuse[2 * k + 1];
            if (!(isfinite(m) && isfinite(nn) && m >= 0.0f && fabsf(nn) <= m + 1e-6f))
                fail_msg("g %g node %d: M %g N %g", gs[i], k, (double)m, (double)nn);
        }
        light_map_finish(&map);
        ext_volume_finish(&vol);
    }
}

int main(void)
{
    log_set_level(LOG_ERROR);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reference_single_voxel_and_axes),
        cmocka_unit_test(test_reference_extreme_aspect),
        cmocka_unit_test(test_extreme_asymmetry),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
