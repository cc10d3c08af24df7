/*
 * optics: extinction, air density and phase functions against hand-computed numbers and
 * against numerical integrals that resolve the forward peak (adaptive Simpson in mu).
 */
#include <math.h>
#include <stdbool.h>
#include <stdio.h>

#include "optics/optics.h"
#include "testutil.h"

#define PI 3.14159265358979323846

static const double g_list[] = {-0.999, -0.9, -0.5, 0.0, 0.5, 0.9, 0.99, 0.999};
#define G_COUNT (sizeof g_list / sizeof g_list[0])

/* ---- numerical integration --------------------------------------------------------------- */

struct integrand {
    double (*f)(const struct integrand *in, double x);
    double g;
    double cap_mu; /* eye-phase clamp: mu above this reads p(cap_mu) */
};

static double simpson_rec(const struct integrand *in, double a, double b, double fa, double fm,
                          double fb, double whole, double tol, int depth)
{
    double m = 0.5 * (a + b);
    double lm = 0.5 * (a + m), rm = 0.5 * (m + b);
    double flm = in->f(in, lm), frm = in->f(in, rm);
    double left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
    double right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
    double diff = left + right - whole;
    if (depth <= 0 || fabs(diff) <= 15.0 * tol || b - a < 1e-14)
        return left + right + diff / 15.0;
    return simpson_rec(in, a, m, fa, flm, fm, left, tol, depth - 1) +
           simpson_rec(in, m, b, fm, frm, fb, right, tol, depth - 1);
}

/* Adaptive Simpson: it subdivides down to the width of the peak (1e-6 in mu at g = 0.999),
 * which a fixed grid in mu would not. */
static double integrate(const struct integrand *in, double a, double b, double tol)
{
    double fa = in->f(in, a), fb = in->f(in, b), fm = in->f(in, 0.5 * (a + b));
    double whole = (b - a) / 6.0 * (fa + 4.0 * fm + fb);
    return simpson_rec(in, a, b, fa, fm, fb, whole, tol, 60);
}

static double f_hg(const struct integrand *in, double mu)
{
    return 2.0 * PI * phase_hg(in->g, mu);
}

static double f_cs(const struct integrand *in, double mu)
{
    return 2.0 * PI * phase_cs(in->g, mu);
}

static double f_cs_mu(const struct integrand *in, double mu)
{
    return 2.0 * PI * mu * phase_cs(in->g, mu);
}

static double f_cs_capped(const struct integrand *in, double mu)
{
    return 2.0 * PI * phase_cs(in->g, mu > in->cap_mu ? in->cap_mu : mu);
}

static bool close_rel(double a, double b, double rel)
{
    return fabs(a - b) <= rel * fabs(b);
}

/* ---- species and extinction -------------------------------------------------------------- */

static void test_species_names(void **state)
{
    (void)state;
    assert_string_equal(species_name(SPECIES_CLOUD), "cloud");
    assert_string_equal(species_name(SPECIES_GRAUPEL), "graupel");
    assert_string_equal(species_wrf_name(SPECIES_CLOUD), "QCLOUD");
    assert_string_equal(species_wrf_name(SPECIES_RAIN), "QRAIN");
    assert_string_equal(species_wrf_name(SPECIES_ICE), "QICE");
    assert_string_equal(species_wrf_name(SPECIES_SNOW), "QSNOW");
    assert_string_equal(species_wrf_name(SPECIES_GRAUPEL), "QGRAUP");
    assert_false(species_is_ice(SPECIES_CLOUD));
    assert_false(species_is_ice(SPECIES_RAIN));
    assert_true(species_is_ice(SPECIES_ICE));
    assert_true(species_is_ice(SPECIES_SNOW));
    assert_true(species_is_ice(SPECIES_GRAUPEL));
}

static void test_defaults(void **state)
{
    (void)state;
    struct optics_params p;
    optics_params_defaults(&p);
    assert_true(p.radius_m[SPECIES_CLOUD] == 1e-5);
    assert_true(p.radius_m[SPECIES_GRAUPEL] == 2.5e-3);
    assert_true(p.density[SPECIES_ICE] == 917.0);
    assert_true(p.g_water > 0.8 && p.g_water < 0.9);
    assert_true(p.g_ice > 0.7 && p.g_ice < p.g_water);
    assert_true(p.eye_peak_deg == 10.0);
}

static void test_beta_hand_values(void **state)
{
    (void)state;
    struct optics_params p;
    optics_params_defaults(&p);
    /* beta = 3 rho_air q / (2 rho_f R_f), q = 1e-3 kg/kg, rho_air = 1 kg/m^3:
     *   cloud   3e-3 / (2 * 1000 * 1e-5)   = 3e-3 / 0.02  = 0.15 /m
     *   rain    3e-3 / (2 * 1000 * 1e-3)   = 3e-3 / 2     = 1.5e-3 /m
     *   ice     3e-3 / (2 * 917 * 1e-3)    = 3e-3 / 1.834 = 1.635769e-3 /m
     *   snow    3e-3 / (2 * 100 * 2e-3)    = 3e-3 / 0.4   = 7.5e-3 /m
     *   graupel 3e-3 / (2 * 400 * 2.5e-3)  = 3e-3 / 2     = 1.5e-3 /m */
    assert_true(close_rel(optics_beta(&p, SPECIES_CLOUD, 1e-3, 1.0), 0.15, 1e-12));
    assert_true(close_rel(optics_beta(&p, SPECIES_RAIN, 1e-3, 1.0), 1.5e-3, 1e-12));
    assert_true(close_rel(optics_beta(&p, SPECIES_ICE, 1e-3, 1.0), 1.635769e-3, 1e-6));
    assert_true(close_rel(optics_beta(&p, SPECIES_SNOW, 1e-3, 1.0), 7.5e-3, 1e-12));
    assert_true(close_rel(optics_beta(&p, SPECIES_GRAUPEL, 1e-3, 1.0), 1.5e-3, 1e-12));
    /* Linear in both: rho_air 0.5 and q 2e-3 give the same cloud number. */
    assert_true(close_rel(optics_beta(&p, SPECIES_CLOUD, 2e-3, 0.5), 0.15, 1e-12));
    /* Parameters are honoured: doubling the cloud radius halves beta. */
    p.radius_m[SPECIES_CLOUD] = 2e-5;
    assert_true(close_rel(optics_beta(&p, SPECIES_CLOUD, 1e-3, 1.0), 0.075, 1e-12));
}

static void test_beta_bad_input(void **state)
{
    (void)state;
    struct optics_params p;
    optics_params_defaults(&p);
    const double bad[] = {-1e-3, -0.0, 0.0, NAN, INFINITY, -INFINITY};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        for (int f = 0; f < SPECIES_COUNT; f++) {
            double b = optics_beta(&p, (enum species)f, bad[i], 1.0);
            assert_true(b == 0.0);
        }
    }
    assert_true(optics_beta(&p, SPECIES_CLOUD, 1e-3, NAN) == 0.0);
    assert_true(optics_beta(&p, SPECIES_CLOUD, 1e-3, -1.0) == 0.0);
}

/* ---- air density ------------------------------------------------------------------------- */

static void test_std_atmosphere(void **state)
{
    (void)state;
    /* 0 m: 101325 / (287.0531 * 288.15) = 1.225000. */
    assert_true(close_rel(optics_std_atmosphere_density(0.0), 1.225, 1e-5));
    /* 11 km geometric = 10981.0 m geopotential (r0 z / (r0 + z), r0 = 6356766 m):
     * T = 288.15 - 0.0065 * 10981.0 = 216.774 K, p = 101325 (T/288.15)^5.25588 = 22700 Pa,
     * rho = 22700 / (287.0531 * 216.774) = 0.36480 (1976 table: 3.6480e-1). */
    assert_true(close_rel(optics_std_atmosphere_density(11000.0), 0.36480, 2e-4));
    /* 20 km geometric = 19937.3 m geopotential, in the isothermal layer: T = 216.65 K,
     * p = 22632.06 exp(-9.80665 * 8937.3 / (287.0531 * 216.65)) = 5529.3 Pa,
     * rho = 5529.3 / (287.0531 * 216.65) = 0.088910 (1976 table: 8.8910e-2).
     * At 20 km geopotential it would be 0.088035. */
    assert_true(close_rel(optics_std_atmosphere_density(20000.0), 0.088910, 2e-4));
    /* 32 km geometric, in the +1 K/km layer (1976 table: 1.3555e-2). */
    assert_true(close_rel(optics_std_atmosphere_density(32000.0), 0.013555, 5e-4));
    /* Clamped: below ground reads ground, above 47 km reads 47 km.  47 km geometric is
     * 46655.0 m geopotential: T = 228.65 + 0.0028 * 14655.0 = 269.684 K, p = 115.85 Pa,
     * rho = 115.85 / (287.0531 * 269.684) = 1.4965e-3 (1.4275e-3 is 47 km geopotential). */
    assert_true(optics_std_atmosphere_density(-500.0) == optics_std_atmosphere_density(0.0));
    assert_true(optics_std_atmosphere_density(NAN) == optics_std_atmosphere_density(0.0));
    double top = optics_std_atmosphere_density(47000.0);
    assert_true(close_rel(top, 1.4965e-3, 5e-4));
    assert_true(optics_std_atmosphere_density(80000.0) == top);
    /* Continuous and strictly decreasing across the layer boundaries. */
    double prev = optics_std_atmosphere_density(0.0);
    for (double z = 10.0; z <= 47000.0; z += 10.0) {
        double rho = optics_std_atmosphere_density(z);
        assert_true(rho < prev);
        assert_true(prev - rho < 2e-3 * prev);
        prev = rho;
    }
}

static void test_wrf_air_density(void **state)
{
    (void)state;
    /* p = p0: T_abs = theta = 300 K, rho = 1e5 / (287 * 300) = 1.161440. */
    assert_true(close_rel(optics_wrf_air_density(100000.0, 300.0), 1.161440, 1e-6));
    /* p = 85000 Pa: R_d/c_p = 287/1004.5 = 2/7, T_abs = 300 * 0.85^(2/7) = 286.3883 K,
     * rho = 85000 / (287 * 286.3883) = 1.034146. */
    assert_true(close_rel(optics_wrf_air_density(85000.0, 300.0), 1.034146, 1e-6));
    assert_true(optics_wrf_air_density(0.0, 300.0) == 0.0);
    assert_true(optics_wrf_air_density(-1.0, 300.0) == 0.0);
    assert_true(optics_wrf_air_density(85000.0, NAN) == 0.0);
    assert_true(optics_wrf_air_density(INFINITY, 300.0) == 0.0);
}

/* The single-precision Poisson factor the load path uses: over WRF's pressures (1 hPa to
 * 1100 hPa) and potential temperatures, air density and temperature stored as floats are
 * within 2 float ulps of the double formula's; the same refusals. */
static void test_wrf_fast_forms(void **state)
{
    (void)state;
    double worst = 0.0;
    for (int i = 0; i <= 20000; i++) {
        float p = 100.0f + (110000.0f - 100.0f) * (float)i / 20000.0f;
        double theta = 250.0 + 0.013 * i;
        float a = (float)optics_wrf_air_density(p, theta);
        float b = (float)optics_wrf_air_density_fast(p, theta);
        float ta = (float)optics_wrf_temperature(p, theta);
        float tb = (float)optics_wrf_temperature_fast(p, theta);
        double ua = fabs((double)a - b) / (nextafterf(a, INFINITY) - a);
        double ut = fabs((double)ta - tb) / (nextafterf(ta, INFINITY) - ta);
        worst = fmax(worst, fmax(ua, ut));
    }
    assert_true(worst <= 2.0);
    assert_true(optics_wrf_air_density_fast(0.0, 300.0) == 0.0);
    assert_true(optics_wrf_air_density_fast(85000.0, NAN) == 0.0);
    assert_true(optics_wrf_temperature_fast(-1.0, 300.0) == 0.0);
    assert_true(close_rel(optics_wrf_air_density_fast(85000.0, 300.0), 1.034146, 1e-6));
}

/* ---- phase functions --------------------------------------------------------------------- */

static void test_phase_normalised(void **state)
{
    (void)state;
    for (size_t i = 0; i < G_COUNT; i++) {
        struct integrand hg = {.f = f_hg, .g = g_list[i]};
        struct integrand cs = {.f = f_cs, .g = g_list[i]};
        double ihg = integrate(&hg, -1.0, 1.0, 1e-10);
        double ics = integrate(&cs, -1.0, 1.0, 1e-10);
        if (fabs(ihg - 1.0) > 1e-6 || fabs(ics - 1.0) > 1e-6)
            printf("g = %g: HG %.10f CS %.10f\n", g_list[i], ihg, ics);
        assert_true(fabs(ihg - 1.0) <= 1e-6);
        assert_true(fabs(ics - 1.0) <= 1e-6);
    }
    /* g = 0: HG is isotropic, CS is the Rayleigh shape 3/(16 pi) (1 + mu^2). */
    assert_true(close_rel(phase_hg(0.0, 0.3), 1.0 / (4.0 * PI), 1e-14));
    assert_true(close_rel(phase_cs(0.0, 0.5), 3.0 / (16.0 * PI) * 1.25, 1e-14));
    /* HG at mu = 1: (1 - g^2) / (4 pi (1 - g)^3) = (1 + g) / (4 pi (1 - g)^2). */
    assert_true(close_rel(phase_hg(0.9, 1.0), 1.9 / (4.0 * PI * 0.01), 1e-12));
}

static void test_phase_float_finite(void **state)
{
    (void)state;
    for (size_t i = 0; i < G_COUNT; i++) {
        float g = (float)g_list[i];
        for (int k = -1; k <= 2001; k++) {
            /* k = -1 and 2001 probe mu a rounding step outside [-1, 1]. */
            float mu = k < 0 ? -1.0000001f : (k > 2000 ? 1.0000001f : -1.0f + k / 1000.0f);
            double mu_d = mu > 1.0f ? 1.0 : (mu < -1.0f ? -1.0 : (double)mu);
            float hg = phase_hg_f(g, mu), cs = phase_cs_f(g, mu);
            assert_true(isfinite(hg) && hg > 0.0f);
            assert_true(isfinite(cs) && cs > 0.0f);
            /* Same inputs in double: float must keep its own precision (this fails where
             * 1 + g^2 - 2 g mu cancels, e.g. g = -0.999 at mu = -1). */
            double hg_d = phase_hg((double)g, mu_d), cs_d = phase_cs((double)g, mu_d);
            if (!close_rel(hg, hg_d, 1e-4) || !close_rel(cs, cs_d, 1e-4))
                printf("g = %g mu = %.8f: hg %g/%g cs %g/%g\n", (double)g, (double)mu, (double)hg,
                       hg_d, (double)cs, cs_d);
            assert_true(close_rel(hg, hg_d, 1e-4));
            assert_true(close_rel(cs, cs_d, 1e-4));
        }
    }
}

static void test_cumulative_ends_and_monotone(void **state)
{
    (void)state;
    for (size_t i = 0; i < G_COUNT; i++) {
        double g = g_list[i];
        assert_true(phase_hg_cumulative(g, 0.0) == 0.0);
        assert_true(phase_cs_cumulative(g, 0.0) == 0.0);
        assert_true(phase_hg_cumulative(g, PI) == 1.0);
        assert_true(phase_cs_cumulative(g, PI) == 1.0);
        double prev_hg = 0.0, prev_cs = 0.0;
        for (int k = 1; k <= 20000; k++) {
            double theta = PI * k / 20000.0;
            double hg = phase_hg_cumulative(g, theta), cs = phase_cs_cumulative(g, theta);
            assert_true(hg >= prev_hg && hg <= 1.0);
            assert_true(cs >= prev_cs && cs <= 1.0);
            prev_hg = hg;
            prev_cs = cs;
        }
        assert_true(prev_hg == 1.0 && prev_cs == 1.0);
    }
}

static void test_cumulative_matches_integral(void **state)
{
    (void)state;
    const double deg[] = {0.01, 0.1, 1.0, 2.5, 5.0, 10.0, 20.0, 45.0, 90.0, 135.0, 179.0, 179.99};
    const double extra_g[] = {1e-9, 1e-5, -1e-3, 0.05};
    for (size_t i = 0; i < G_COUNT + 4; i++) {
        double g = i < G_COUNT ? g_list[i] : extra_g[i - G_COUNT];
        for (size_t k = 0; k < sizeof deg / sizeof deg[0]; k++) {
            double theta = deg[k] * PI / 180.0;
            struct integrand hg = {.f = f_hg, .g = g};
            struct integrand cs = {.f = f_cs, .g = g};
            double want_hg = integrate(&hg, cos(theta), 1.0, 1e-12);
            double want_cs = integrate(&cs, cos(theta), 1.0, 1e-12);
            double got_hg = phase_hg_cumulative(g, theta);
            double got_cs = phase_cs_cumulative(g, theta);
            if (fabs(got_hg - want_hg) > 1e-8 || fabs(got_cs - want_cs) > 1e-8)
                printf("g = %g theta = %g deg: HG %.12g/%.12g CS %.12g/%.12g\n", g, deg[k], got_hg,
                       want_hg, got_cs, want_cs);
            assert_true(fabs(got_hg - want_hg) <= 1e-8);
            assert_true(fabs(got_cs - want_cs) <= 1e-8);
        }
    }
    /* Closed forms at g = 0, x = 1 - cos theta: HG x/2; CS 3/8 (2x - x^2 + x^3/3).
     * theta = 60 deg, x = 1/2: HG 0.25, CS 3/8 * (1 - 1/4 + 1/24) = 0.296875. */
    assert_true(close_rel(phase_hg_cumulative(0.0, PI / 3.0), 0.25, 1e-12));
    assert_true(close_rel(phase_cs_cumulative(0.0, PI / 3.0), 0.296875, 1e-12));
}

static void test_cs_mean_cosine(void **state)
{
    (void)state;
    /* 3 g (4 + g^2) / (5 (2 + g^2)) at g = 0.9: 3 * 0.9 * 4.81 / (5 * 2.81) = 0.924342,
     * larger than g.  Small g: 6g/5. */
    assert_true(close_rel(phase_cs_mean_cosine(0.9), 12.987 / 14.05, 1e-12));
    assert_true(close_rel(phase_cs_mean_cosine(1e-6), 1.2e-6, 1e-6));
    assert_true(phase_cs_mean_cosine(0.0) == 0.0);
    /* ... and it is the first moment of phase_cs. */
    for (size_t i = 0; i < G_COUNT; i++) {
        struct integrand in = {.f = f_cs_mu, .g = g_list[i]};
        double want = integrate(&in, -1.0, 1.0, 1e-11);
        assert_true(fabs(phase_cs_mean_cosine(g_list[i]) - want) <= 1e-7);
    }
    /* The inverse: a mean cosine of 0.9 needs g = 0.869138 (root of 3g^3 - 4.5g^2 + 12g - 9,
     * found by bisection by hand); 0.86 needs 0.819747; 0.75 needs 0.691786. */
    assert_true(fabs(phase_cs_g_for_mean_cosine(0.9) - 0.8691385) < 1e-6);
    assert_true(fabs(phase_cs_g_for_mean_cosine(0.86) - 0.8197469) < 1e-6);
    assert_true(fabs(phase_cs_g_for_mean_cosine(0.75) - 0.6917858) < 1e-6);
    for (double mc = -0.99; mc <= 0.99; mc += 0.01) {
        double g = phase_cs_g_for_mean_cosine(mc);
        assert_true(fabs(phase_cs_mean_cosine(g) - mc) < 1e-12);
        assert_true(fabs(g) <= fabs(mc));
    }
    for (size_t i = 0; i < G_COUNT; i++)
        assert_true(fabs(phase_cs_g_for_mean_cosine(phase_cs_mean_cosine(g_list[i])) - g_list[i]) <
                    1e-12);
    /* Out of range: clamped to the largest |g| the phase functions accept. */
    assert_true(phase_cs_g_for_mean_cosine(1.5) == 0.999);
    assert_true(phase_cs_g_for_mean_cosine(-1.5) == -0.999);
    assert_true(phase_cs_g_for_mean_cosine(NAN) == 0.0);
}

/* ---- eye phase table and forward cumulative phase ---------------------------------------- */

static void check_eye_column(const float *tab, int n, double g_cs, double psi0)
{
    /* Independent normalisation: integrate the clamped phase numerically. */
    struct integrand in = {.f = f_cs_capped, .g = g_cs, .cap_mu = cos(psi0)};
    double norm = integrate(&in, -1.0, 1.0, 1e-11);
    double cap = 4.0 * PI * phase_cs(g_cs, cos(psi0)) / norm;
    double avg = 0.0;
    for (int i = 0; i < n; i++) {
        double psi = PI * i / (n - 1);
        float v = tab[2 * i];
        assert_true(isfinite(v) && v > 0.0f);
        double want = psi < psi0 ? cap : 4.0 * PI * phase_cs(g_cs, cos(psi)) / norm;
        assert_true(close_rel(v, want, 1e-5));
        assert_true(v <= cap * (1.0 + 1e-6));
        if (i > 0)
            avg += 0.5 * (tab[2 * i] * sin(psi) + tab[2 * i - 2] * sin(psi - PI / (n - 1)));
    }
    /* Average over the sphere: (1/2) int_0^pi v(psi) sin psi dpsi, by trapezoids. */
    avg *= 0.5 * PI / (n - 1);
    assert_true(fabs(avg - 1.0) < 1e-4);
}

static void test_eye_phase_table(void **state)
{
    (void)state;
    struct optics_params p;
    optics_params_defaults(&p);
    enum { N = 4097 };
    static float tab[2 * N];
    optics_eye_phase_table(&p, N, tab);
    double psi0 = p.eye_peak_deg * PI / 180.0;
    check_eye_column(tab, N, phase_cs_g_for_mean_cosine(p.g_ice), psi0);
    check_eye_column(tab + 1, N, phase_cs_g_for_mean_cosine(p.g_water), psi0);
    /* Entries inside the peak all read the clamp value; ice scatters more to the side. */
    assert_true(tab[0] == tab[2]);
    assert_true(tab[1] == tab[3]);
    assert_true(tab[2 * (N / 2)] > tab[2 * (N / 2) + 1]);
    assert_true(tab[1] > tab[0]);

    /* A sharper peak and another size. */
    p.g_water = 0.95;
    p.g_ice = 0.3;
    p.eye_peak_deg = 3.0;
    optics_eye_phase_table(&p, 1025, tab);
    check_eye_column(tab, 1025, phase_cs_g_for_mean_cosine(0.3), 3.0 * PI / 180.0);
    check_eye_column(tab + 1, 1025, phase_cs_g_for_mean_cosine(0.95), 3.0 * PI / 180.0);

    /* Mean cosine 0: CS with g = 0 is the Rayleigh shape, 3/4 (1 + cos^2 psi) relative to
     * isotropic, unchanged by a clamp at 0 degrees. */
    p.g_water = p.g_ice = 0.0;
    p.eye_peak_deg = 0.0;
    optics_eye_phase_table(&p, 3, tab);
    assert_true(close_rel(tab[0], 1.5, 1e-6) && close_rel(tab[1], 1.5, 1e-6));
    assert_true(close_rel(tab[2], 0.75, 1e-6) && close_rel(tab[3], 0.75, 1e-6));
    assert_true(close_rel(tab[4], 1.5, 1e-6) && close_rel(tab[5], 1.5, 1e-6));
}

static void test_forward_cp(void **state)
{
    (void)state;
    struct optics_params p;
    optics_params_defaults(&p);
    double theta = 20.0 * PI / 180.0;
    struct optics_cp cp;
    optics_forward_cp(&p, theta, &cp);
    double gw = phase_cs_g_for_mean_cosine(p.g_water), gi = phase_cs_g_for_mean_cosine(p.g_ice);
    assert_true(close_rel(cp.water_ctr, phase_cs_cumulative(gw, theta / 4.0), 1e-14));
    assert_true(
        close_rel(cp.water_ctr + cp.water_per, phase_cs_cumulative(gw, theta / 2.0), 1e-14));
    assert_true(close_rel(cp.ice_ctr, phase_cs_cumulative(gi, theta / 4.0), 1e-14));
    assert_true(close_rel(cp.ice_ctr + cp.ice_per, phase_cs_cumulative(gi, theta / 2.0), 1e-14));
    assert_true(cp.water_ctr > 0.0 && cp.water_per > 0.0);
    assert_true(cp.ice_ctr > 0.0 && cp.ice_per > 0.0);
    assert_true(cp.water_ctr + cp.water_per < 1.0);
    /* Water scatters further forward than ice. */
    assert_true(cp.water_ctr > cp.ice_ctr);

    optics_forward_cp(&p, 0.0, &cp);
    assert_true(cp.water_ctr == 0.0 && cp.water_per == 0.0);
    assert_true(cp.ice_ctr == 0.0 && cp.ice_per == 0.0);
}

/* The backward share of a vertical two-stream column lit at mu0: its closed-form ends (sun
 * overhead: the backward hemisphere 1 - CP(pi/2); sun at the horizon: half of what leaves the
 * cone, by symmetry), isotropic scattering halves at every sun, and a forward-peaked phase
 * sends less back the higher the sun. */
static void test_cs_back_fraction(void **state)
{
    const double gs[] = {0.0, 0.5, 0.85, -0.3};
    const double psis[] = {0.0, 0.1, 0.3};
    for (size_t a = 0; a < sizeof gs / sizeof gs[0]; a++) {
        for (size_t b = 0; b < sizeof psis / sizeof psis[0]; b++) {
            double g = gs[a], psi = psis[b];
            double top = phase_cs_back_fraction(g, psi, 1.0);
            double side = phase_cs_back_fraction(g, psi, 0.0);
            /* 8192 midpoint steps across the hemisphere's edge: about 1e-5 */
            assert_float_equal(top, 1.0 - phase_cs_cumulative(g, 0.5 * PI), 1e-4);
            assert_float_equal(side, 0.5 * (1.0 - phase_cs_cumulative(g, psi)), 1e-4);
            double prev = side;
            for (double mu0 = 0.1; mu0 <= 1.0001; mu0 += 0.1) {
                double f = phase_cs_back_fraction(g, psi, mu0);
                assert_true(f >= 0.0 && f <= 1.0);
                if (g == 0.0 && psi == 0.0)
                    assert_float_equal(f, 0.5, 1e-6);
                if (g > 0.0)
                    assert_true(f <= prev + 1e-9);
                prev = f;
            }
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_species_names),
        cmocka_unit_test(test_defaults),
        cmocka_unit_test(test_beta_hand_values),
        cmocka_unit_test(test_beta_bad_input),
        cmocka_unit_test(test_std_atmosphere),
        cmocka_unit_test(test_wrf_air_density),
        cmocka_unit_test(test_wrf_fast_forms),
        cmocka_unit_test(test_phase_normalised),
        cmocka_unit_test(test_phase_float_finite),
        cmocka_unit_test(test_cumulative_ends_and_monotone),
        cmocka_unit_test(test_cumulative_matches_integral),
        cmocka_unit_test(test_cs_mean_cosine),
        cmocka_unit_test(test_eye_phase_table),
        cmocka_unit_test(test_forward_cp),
        cmocka_unit_test(test_cs_back_fraction),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
