/*
 * optics: the physics of light in clouds as plain functions of numbers.  Mass ratio to
 * extinction per hydrometeor species (Nes eq. 5.2-5.4), air density, and the phase functions
 * (Henyey-Greenstein, Cornette-Shanks) with their cumulative forms.  No GL, no files, no
 * volumes: callers loop over voxels.
 *
 * Must not know: volumes, grids, GL, files, configs.
 */
#ifndef ANVIL_OPTICS_H
#define ANVIL_OPTICS_H

#include <stdbool.h>

enum species {
    SPECIES_CLOUD,
    SPECIES_RAIN,
    SPECIES_ICE,
    SPECIES_SNOW,
    SPECIES_GRAUPEL,
    SPECIES_COUNT
};

/* "cloud", "rain", "ice", "snow", "graupel". */
const char *species_name(enum species f);
/* WRF variable: "QCLOUD", "QRAIN", "QICE", "QSNOW", "QGRAUP". */
const char *species_wrf_name(enum species f);
/* Ice, snow and graupel scatter with the ice phase; cloud and rain with the water phase
 * (Nes §5.2.4). */
bool species_is_ice(enum species f);

struct optics_params {
    double radius_m[SPECIES_COUNT];  /* mean particle radius, Nes Table 5.1 */
    double density[SPECIES_COUNT];   /* particle density, kg/m^3 (SPEC defaults) */
    double g_water;                  /* mean cosine of the water phase (cloud, rain) */
    double g_ice;                    /* mean cosine of the ice phase (ice, snow, graupel) */
    double eye_peak_deg;             /* eye phase: forward peak truncated inside this angle */
};

/* Fills the defaults: radii cloud 0.01 mm, rain 1 mm, ice 1 mm, snow 2 mm, graupel 2.5 mm;
 * densities water 1000, ice 917, snow 100, graupel 400 kg/m^3; phase asymmetries as
 * documented in docs/physics.md. */
void optics_params_defaults(struct optics_params *p);

/* Extinction coefficient [1/m] of species F at mass ratio Q [kg/kg] in air of density
 * RHO_AIR [kg/m^3]: 3 rho_air q / (2 rho_f R_f) (Nes eq. 5.3).  Q that is negative or not
 * finite gives 0. */
double optics_beta(const struct optics_params *p, enum species f, double q, double rho_air);

/* Air density [kg/m^3] of the 1976 US standard atmosphere at geometric height H [m]
 * (valid 0-47 km; clamped outside). */
double optics_std_atmosphere_density(double height_m);

/* Air density from WRF fields: P_TOTAL = P + PB [Pa], THETA = T + 300 [K] (potential
 * temperature): T_abs = theta (p/p0)^(R_d/c_p), rho = p / (R_d T_abs). */
double optics_wrf_air_density(double p_total_pa, double theta_k);
/* Absolute air temperature [K] from the same: theta (p/p0)^(R_d/c_p); 0 when P_TOTAL or THETA
 * is not positive and finite. */
double optics_wrf_temperature(double p_total_pa, double theta_k);
/* The same two within float rounding (at most 2 float ulps apart, tests/unit/test_optics.c):
 * the Poisson factor (p / p0)^(R_d / c_p) taken in single precision, a third of the time of
 * the double one.  For loading a step's millions of values that are stored as floats. */
double optics_wrf_air_density_fast(double p_total_pa, double theta_k);
double optics_wrf_temperature_fast(double p_total_pa, double theta_k);

/* Phase functions of the scattering angle's cosine MU, in 1/sr, normalised so that the
 * integral over the sphere is 1.  Finite for |g| <= 0.999 in both precisions: the
 * denominator 1 + g^2 - 2 g mu is computed without cancellation, as (1-g)^2 + 2 g (1-mu) for
 * g >= 0 and (1+g)^2 - 2 g (1+mu) for g < 0. */
double phase_hg(double g, double mu);
double phase_cs(double g, double mu);
float phase_hg_f(float g, float mu);
float phase_cs_f(float g, float mu);

/* Mean cosine of Cornette-Shanks with parameter G (it is not G): 3g(4+g^2) / (5(2+g^2)). */
double phase_cs_mean_cosine(double g);
/* The CS parameter whose mean cosine is MEAN_COSINE (inverse of the above, |mc| < 0.9). */
double phase_cs_g_for_mean_cosine(double mean_cosine);

/* Cumulative phase: fraction of scattered light that leaves within angle THETA [rad] of the
 * forward direction.  CP(0) = 0, CP(pi) = 1, monotone. */
double phase_hg_cumulative(double g, double theta);
double phase_cs_cumulative(double g, double theta);

/* Share of all the light scattered by the CS phase G that leaves at an angle of at least
 * PSI_MIN [rad] from the beam AND into the hemisphere facing back along an axis that the beam
 * makes the cosine MU0 in [0, 1] with: the backward share of the scattered light for a vertical
 * two-stream column lit at MU0 = sin(elevation).  At MU0 = 1 and PSI_MIN <= pi / 2 it is
 * 1 - CP(pi / 2); at MU0 = 0 it is half of 1 - CP(PSI_MIN).  Integrated numerically over the
 * scattering angle (8192 steps; the azimuth in closed form). */
double phase_cs_back_fraction(double g, double psi_min, double mu0);

/* Eye-scattering phase table (Nes §5.2.4): N entries at angles psi_i = pi i/(N-1); for each,
 * OUT[2i] the ice phase and OUT[2i+1] the water phase.  Each is the CS phase with its
 * asymmetry, the forward peak clamped to its value at eye_peak_deg, renormalised to integrate
 * to 1 over the sphere and given relative to isotropic (so an isotropic phase reads 1). */
void optics_eye_phase_table(const struct optics_params *p, int n, float *out);

/* Cumulative CS phase of the water and ice phases at an angle, for the light pass. */
struct optics_cp {
    double water_ctr, water_per; /* CP(theta/4), CP(theta/2) - CP(theta/4) */
    double ice_ctr, ice_per;
    /* For the diffuse (two-stream) pass of the light map: the Cornette-Shanks parameter of
     * each phase (for phase_cs_back_fraction, which depends on the sun's elevation), and the
     * Eddington two-stream coupling 3 (1 - g) / 4 of the phase's mean cosine g (Meador and
     * Weaver 1980, Table 1, with albedo 1). */
    double water_cs_g, ice_cs_g;
    double water_gamma, ice_gamma;
};
void optics_forward_cp(const struct optics_params *p, double forward_angle_rad,
                       struct optics_cp *out);

#endif
