/*
 * optics: extinction from mass ratios (Nes eq. 5.2-5.4), air density (1976 US standard
 * atmosphere, WRF fields) and the Henyey-Greenstein and Cornette-Shanks phase functions with
 * their cumulative forms.  See docs/physics.md, section "Optics", for the derivations and the
 * sources of every default.
 */
#include "optics/optics.h"

#include <assert.h>
#include <math.h>
#include <stddef.h>

#define PI 3.14159265358979323846

/* Largest |g| for which the phase functions promise finite values. */
#define G_MAX 0.999

static const char *const species_names[SPECIES_COUNT] = {
    [SPECIES_CLOUD] = "cloud", [SPECIES_RAIN] = "rain",       [SPECIES_ICE] = "ice",
    [SPECIES_SNOW] = "snow",   [SPECIES_GRAUPEL] = "graupel",
};

static const char *const species_wrf_names[SPECIES_COUNT] = {
    [SPECIES_CLOUD] = "QCLOUD", [SPECIES_RAIN] = "QRAIN",     [SPECIES_ICE] = "QICE",
    [SPECIES_SNOW] = "QSNOW",   [SPECIES_GRAUPEL] = "QGRAUP",
};

const char *species_name(enum species f)
{
    assert(f >= 0 && f < SPECIES_COUNT);
    return species_names[f];
}

const char *species_wrf_name(enum species f)
{
    assert(f >= 0 && f < SPECIES_COUNT);
    return species_wrf_names[f];
}

bool species_is_ice(enum species f)
{
    assert(f >= 0 && f < SPECIES_COUNT);
    return f == SPECIES_ICE || f == SPECIES_SNOW || f == SPECIES_GRAUPEL;
}

void optics_params_defaults(struct optics_params *p)
{
    assert(p);
    /* Nes Table 5.1: mean radii. */
    p->radius_m[SPECIES_CLOUD] = 0.01e-3;
    p->radius_m[SPECIES_RAIN] = 1.0e-3;
    p->radius_m[SPECIES_ICE] = 1.0e-3;
    p->radius_m[SPECIES_SNOW] = 2.0e-3;
    p->radius_m[SPECIES_GRAUPEL] = 2.5e-3;
    /* SPEC defaults: liquid water, solid ice, and bulk densities of snow and graupel. */
    p->density[SPECIES_CLOUD] = 1000.0;
    p->density[SPECIES_RAIN] = 1000.0;
    p->density[SPECIES_ICE] = 917.0;
    p->density[SPECIES_SNOW] = 100.0;
    p->density[SPECIES_GRAUPEL] = 400.0;
    /* Asymmetry parameters in the visible: water droplets (Hansen & Travis 1974), ice
     * crystals (Macke et al. 1996).  Sources in docs/physics.md. */
    p->g_water = 0.86;
    p->g_ice = 0.75;
    /* Nes §5.2.4, Riley §4.4.1: most of the scattered light leaves within ~10 degrees. */
    p->eye_peak_deg = 10.0;
}

double optics_beta(const struct optics_params *p, enum species f, double q, double rho_air)
{
    assert(p);
    assert(f >= 0 && f < SPECIES_COUNT);
    if (!isfinite(q) || q <= 0.0 || !isfinite(rho_air) || rho_air <= 0.0)
        return 0.0;
    double denom = 2.0 * p->density[f] * p->radius_m[f];
    if (!(denom > 0.0))
        return 0.0;
    return 3.0 * rho_air * q / denom; /* Nes eq. 5.3 */
}

/*
 * 1976 US standard atmosphere (NOAA/NASA/USAF, 1976), the layers below 47 km geopotential
 * height.  Constants as in the standard: R* = 8.31432 J/(mol K), M0 = 28.9644 g/mol,
 * g0 = 9.80665 m/s^2, r0 = 6356.766 km (the radius used to turn geometric into geopotential
 * height).  Layer base pressures follow from integrating the hydrostatic equation, so they
 * are computed rather than tabulated.
 */
#define STD_R (8.31432 / 0.0289644)
#define STD_G0 9.80665
#define STD_R0 6356766.0
#define STD_TOP_M 47000.0

struct std_layer {
    double base_h; /* geopotential height of the layer base, m */
    double lapse;  /* dT/dh, K/m */
};

/* clang-format off */
static const struct std_layer std_layers[] = {
    {0.0, -0.0065},
    {11000.0, 0.0},
    {20000.0, 0.0010},
    {32000.0, 0.0028},
    {47000.0, 0.0},
};
/* clang-format on */

/* Temperature and pressure at geopotential height TOP within a layer whose base has T, P. */
static void std_layer_step(const struct std_layer *l, double top, double *t, double *p)
{
    double dh = top - l->base_h;
    if (l->lapse == 0.0) {
        *p *= exp(-STD_G0 * dh / (STD_R * *t));
    } else {
        double t_top = *t + l->lapse * dh;
        *p *= pow(t_top / *t, -STD_G0 / (STD_R * l->lapse));
        *t = t_top;
    }
}

double optics_std_atmosphere_density(double height_m)
{
    double z = height_m;
    if (!(z > 0.0))
        z = 0.0; /* also NaN */
    if (z > STD_TOP_M)
        z = STD_TOP_M;
    double h = STD_R0 * z / (STD_R0 + z); /* geometric -> geopotential */
    double t = 288.15, p = 101325.0;
    size_t nlayers = sizeof std_layers / sizeof std_layers[0];
    for (size_t i = 0; i + 1 < nlayers; i++) {
        double top = std_layers[i + 1].base_h;
        if (h <= top) {
            std_layer_step(&std_layers[i], h, &t, &p);
            break;
        }
        std_layer_step(&std_layers[i], top, &t, &p);
    }
    return p / (STD_R * t);
}

/* WRF share/module_model_constants.F: r_d = 287., cp = 7.*r_d/2. (= 1004.5),
 * p1000mb = 100000. */
#define WRF_P0 100000.0
#define WRF_RD 287.0
#define WRF_CP 1004.5

double optics_wrf_temperature(double p_total_pa, double theta_k)
{
    if (!isfinite(p_total_pa) || !isfinite(theta_k) || p_total_pa <= 0.0 || theta_k <= 0.0)
        return 0.0;
    return theta_k * pow(p_total_pa / WRF_P0, WRF_RD / WRF_CP);
}

double optics_wrf_air_density(double p_total_pa, double theta_k)
{
    if (!isfinite(p_total_pa) || !isfinite(theta_k) || p_total_pa <= 0.0 || theta_k <= 0.0)
        return 0.0;
    double t_abs = theta_k * pow(p_total_pa / WRF_P0, WRF_RD / WRF_CP); /* Poisson's eq. */
    return p_total_pa / (WRF_RD * t_abs);                               /* ideal gas */
}

static double poisson_fast(double p_total_pa)
{
    return (double)powf((float)(p_total_pa / WRF_P0), (float)(WRF_RD / WRF_CP));
}

double optics_wrf_temperature_fast(double p_total_pa, double theta_k)
{
    if (!isfinite(p_total_pa) || !isfinite(theta_k) || p_total_pa <= 0.0 || theta_k <= 0.0)
        return 0.0;
    return theta_k * poisson_fast(p_total_pa);
}

double optics_wrf_air_density_fast(double p_total_pa, double theta_k)
{
    if (!isfinite(p_total_pa) || !isfinite(theta_k) || p_total_pa <= 0.0 || theta_k <= 0.0)
        return 0.0;
    return p_total_pa / (WRF_RD * theta_k * poisson_fast(p_total_pa));
}

/*
 * Phase functions.  Both share the factor (1 + g^2 - 2 g mu)^(3/2).  Written as a sum of two
 * non-negative terms it never cancels: for g >= 0, (1-g)^2 + 2g(1-mu); for g < 0,
 * (1+g)^2 - 2g(1+mu).  (The first form alone cancels for g < 0 near mu = -1, where the value
 * is (1+g)^2, about 1e-6 at g = -0.999.)  The callers pass 1-mu and 1+mu so that they can
 * compute them without cancellation too.
 */
static double clamp_g(double g)
{
    if (g > G_MAX)
        return G_MAX;
    if (g < -G_MAX)
        return -G_MAX;
    return g;
}

static float clamp_g_f(float g)
{
    if (g > (float)G_MAX)
        return (float)G_MAX;
    if (g < (float)-G_MAX)
        return (float)-G_MAX;
    return g;
}

static double clamp_mu(double mu)
{
    return mu > 1.0 ? 1.0 : (mu < -1.0 ? -1.0 : mu);
}

static float clamp_mu_f(float mu)
{
    return mu > 1.0f ? 1.0f : (mu < -1.0f ? -1.0f : mu);
}

static double hg_base(double g, double one_minus_mu, double one_plus_mu)
{
    if (g >= 0.0)
        return (1.0 - g) * (1.0 - g) + 2.0 * g * one_minus_mu;
    return (1.0 + g) * (1.0 + g) - 2.0 * g * one_plus_mu;
}

static float hg_base_f(float g, float one_minus_mu, float one_plus_mu)
{
    if (g >= 0.0f)
        return (1.0f - g) * (1.0f - g) + 2.0f * g * one_minus_mu;
    return (1.0f + g) * (1.0f + g) - 2.0f * g * one_plus_mu;
}

double phase_hg(double g, double mu)
{
    g = clamp_g(g);
    mu = clamp_mu(mu);
    double d = hg_base(g, 1.0 - mu, 1.0 + mu);
    return (1.0 - g) * (1.0 + g) / (4.0 * PI * d * sqrt(d));
}

double phase_cs(double g, double mu)
{
    g = clamp_g(g);
    mu = clamp_mu(mu);
    double d = hg_base(g, 1.0 - mu, 1.0 + mu);
    /* Cornette & Shanks 1992; Riley et al. */
    return 3.0 / (8.0 * PI) * (1.0 - g) * (1.0 + g) / (2.0 + g * g) * (1.0 + mu * mu) /
           (d * sqrt(d));
}

float phase_hg_f(float g, float mu)
{
    g = clamp_g_f(g);
    mu = clamp_mu_f(mu);
    float d = hg_base_f(g, 1.0f - mu, 1.0f + mu);
    return (1.0f - g) * (1.0f + g) / (4.0f * (float)PI * d * sqrtf(d));
}

float phase_cs_f(float g, float mu)
{
    g = clamp_g_f(g);
    mu = clamp_mu_f(mu);
    float d = hg_base_f(g, 1.0f - mu, 1.0f + mu);
    return 3.0f / (8.0f * (float)PI) * (1.0f - g) * (1.0f + g) / (2.0f + g * g) * (1.0f + mu * mu) /
           (d * sqrtf(d));
}

/* <mu> of CS: the HG moments <mu> = g and <mu^3> = (3g + 2g^3)/5 weighted by
 * 3(1+mu^2) / (2(2+g^2)). */
double phase_cs_mean_cosine(double g)
{
    return 3.0 * g * (4.0 + g * g) / (5.0 * (2.0 + g * g));
}

static double cs_mean_cosine_slope(double g)
{
    double g2 = g * g;
    return 3.0 * (8.0 + 2.0 * g2 + g2 * g2) / (5.0 * (2.0 + g2) * (2.0 + g2));
}

double phase_cs_g_for_mean_cosine(double mean_cosine)
{
    if (isnan(mean_cosine))
        return 0.0;
    double lo = -G_MAX, hi = G_MAX;
    if (mean_cosine <= phase_cs_mean_cosine(lo))
        return lo;
    if (mean_cosine >= phase_cs_mean_cosine(hi))
        return hi;
    /* The mean cosine rises monotonically in g (its slope is positive), so Newton's method
     * kept inside a shrinking bracket converges from any start. */
    double g = mean_cosine / 1.2;
    for (int i = 0; i < 100; i++) {
        double f = phase_cs_mean_cosine(g) - mean_cosine;
        if (f == 0.0)
            break;
        if (f > 0.0)
            hi = g;
        else
            lo = g;
        double next = g - f / cs_mean_cosine_slope(g);
        if (!(next > lo && next < hi))
            next = 0.5 * (lo + hi);
        if (fabs(next - g) <= 1e-15)
            return next;
        g = next;
    }
    return g;
}

/*
 * Cumulative phase CP(theta) = 2 pi int_{cos theta}^1 p(mu) dmu (Riley eq. 12-17).  With
 * x = 1 - cos theta, s = 1 - g and t = sqrt(1 + g^2 - 2g cos theta), substituting
 * u = 1 + g^2 - 2 g mu gives polynomials in u^(1/2), and writing t - s = g e with
 * e = 2x / (t + s) removes the factors of 1/g (derivation in docs/physics.md):
 *   HG: CP = (1 - g^2) x / ((t + s) s t)
 *   CS: CP = 3 (1 - g^2) / (4 (2 + g^2)) * x / (4 (t + s) s t)
 *            * (16 - 8 s e + 8/3 s^2 e^2 + 2/3 g s e^3)
 * Both are free of cancellation for all |g| <= 0.999, including g -> 0.
 */
struct cp_terms {
    double g, x, s, t;
};

/* Returns false when THETA is at either end: *END receives CP there. */
static bool cp_setup(double g, double theta, struct cp_terms *c, double *end)
{
    if (!(theta > 0.0)) {
        *end = 0.0;
        return false;
    }
    if (theta >= PI) {
        *end = 1.0;
        return false;
    }
    double sh = sin(0.5 * theta), ch = cos(0.5 * theta);
    c->g = clamp_g(g);
    c->x = 2.0 * sh * sh; /* 1 - cos theta */
    c->s = 1.0 - c->g;
    c->t = sqrt(hg_base(c->g, c->x, 2.0 * ch * ch));
    return true;
}

static double clamp_unit(double v)
{
    return v < 0.0 ? 0.0 : (v > 1.0 ? 1.0 : v);
}

double phase_hg_cumulative(double g, double theta)
{
    struct cp_terms c;
    double end = 0.0;
    if (!cp_setup(g, theta, &c, &end))
        return end;
    return clamp_unit((1.0 - c.g) * (1.0 + c.g) * c.x / ((c.t + c.s) * c.s * c.t));
}

double phase_cs_cumulative(double g, double theta)
{
    struct cp_terms c;
    double end = 0.0;
    if (!cp_setup(g, theta, &c, &end))
        return end;
    double e = 2.0 * c.x / (c.t + c.s);
    double se = c.s * e;
    double poly = 16.0 - 8.0 * se + 8.0 / 3.0 * se * se + 2.0 / 3.0 * c.g * se * e * e;
    double norm = 3.0 * (1.0 - c.g) * (1.0 + c.g) / (4.0 * (2.0 + c.g * c.g));
    return clamp_unit(norm * c.x / (4.0 * (c.t + c.s) * c.s * c.t) * poly);
}

double phase_cs_back_fraction(double g, double psi_min, double mu0)
{
    enum { STEPS = 8192 };
    mu0 = mu0 < 0.0 ? 0.0 : mu0 > 1.0 ? 1.0 : mu0;
    double lo = psi_min < 0.0 ? 0.0 : psi_min > PI ? PI : psi_min;
    double s = sqrt(fmax(0.0, 1.0 - mu0 * mu0));
    double h = (PI - lo) / STEPS, sum = 0.0;
    for (int i = 0; i < STEPS; i++) {
        double psi = lo + (i + 0.5) * h;
        double cs = cos(psi), sn = sin(psi);
        /* The direction at psi and azimuth phi has the cosine mu0 cos psi + s sin psi cos phi
         * with the axis: it faces back where cos phi < c. */
        double back;
        if (s * sn <= 0.0) {
            back = mu0 * cs < 0.0 ? 1.0 : 0.0;
        } else {
            double c = -mu0 * cs / (s * sn);
            back = c <= -1.0 ? 0.0 : c >= 1.0 ? 1.0 : acos(-c) / PI;
        }
        sum += phase_cs(g, cs) * sn * back;
    }
    return clamp_unit(2.0 * PI * h * sum);
}

/*
 * One eye-phase column: CS with parameter G, constant p(psi0) inside psi0 (Nes §5.2.4: the
 * forward peak truncated), scaled so the sphere integral is 1, times 4 pi.  The clamped
 * phase integrates to 2 pi p(psi0) (1 - cos psi0) + 1 - CP(psi0).
 */
static void eye_column(double g, double psi0, int n, float *out)
{
    double sh = sin(0.5 * psi0);
    double cap = phase_cs(g, cos(psi0));
    double total = 2.0 * PI * cap * 2.0 * sh * sh + 1.0 - phase_cs_cumulative(g, psi0);
    for (int i = 0; i < n; i++) {
        double psi = PI * i / (n - 1);
        double p = psi < psi0 ? cap : phase_cs(g, cos(psi));
        out[2 * i] = (float)(4.0 * PI * p / total);
    }
}

void optics_eye_phase_table(const struct optics_params *p, int n, float *out)
{
    assert(p && out);
    assert(n >= 2);
    double psi0 = p->eye_peak_deg * PI / 180.0;
    if (!(psi0 > 0.0))
        psi0 = 0.0;
    if (psi0 > PI)
        psi0 = PI;
    eye_column(phase_cs_g_for_mean_cosine(p->g_ice), psi0, n, out);
    eye_column(phase_cs_g_for_mean_cosine(p->g_water), psi0, n, out + 1);
}

void optics_forward_cp(const struct optics_params *p, double forward_angle_rad,
                       struct optics_cp *out)
{
    assert(p && out);
    double gw = phase_cs_g_for_mean_cosine(p->g_water);
    double gi = phase_cs_g_for_mean_cosine(p->g_ice);
    double q = 0.25 * forward_angle_rad, h = 0.5 * forward_angle_rad;
    /* Nes eq. 5.9-5.10 */
    out->water_ctr = phase_cs_cumulative(gw, q);
    out->water_per = phase_cs_cumulative(gw, h) - out->water_ctr;
    out->ice_ctr = phase_cs_cumulative(gi, q);
    out->ice_per = phase_cs_cumulative(gi, h) - out->ice_ctr;
    out->water_cs_g = gw;
    out->ice_cs_g = gi;
    out->water_gamma = 0.75 * (1.0 - p->g_water);
    out->ice_gamma = 0.75 * (1.0 - p->g_ice);
}
