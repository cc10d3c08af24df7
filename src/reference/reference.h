/*
 * reference: the Monte Carlo yardstick, a renderer in its own right.  A CPU volumetric path
 * tracer over the same scene the renderer draws (extinction volume, sun, sky, ground, camera
 * matrices) that converges to the solution of the volume rendering equation (Elek eq.
 * 2.11-2.13) which the renderer's single-scattering eye pass and light map approximate:
 * multiple scattering of any order, the full (untruncated) phase functions, light from the
 * sky as well as the sun.  The benchmark (bench/) measures the renderer's error against it;
 * anvil reference writes its images.
 *
 * What it computes, in units and in relation to render_settings, is in docs/reference.md.
 * In short: the sun is a directional source of irradiance E [W/m^2 per unit area normal to
 * the beam]; the renderer's sun_radiance is E / (4 pi).  Radiance out is linear, same units
 * as the sky radiance.
 *
 * Estimators: delta (Woodcock) tracking for free flights and residual ratio tracking for
 * transmittance to the sun, both against a grid of per-block bounds of the trilinear
 * extinction (min and max over 8^3 voxels plus a one-voxel apron) traversed with a DDA;
 * importance-sampled Henyey-Greenstein (closed-form inversion, Elek eq. 2.5) and
 * Cornette-Shanks (exact rejection from an HG proposal); next-event estimation of the sun;
 * Russian roulette on throughput, no depth cut.
 *
 * Files: sample.c (random numbers, phase sampling), trace.c (the bound grid, tracking, one
 * path's radiance), image.c (a view's image over threads).
 *
 * It must not know GL, files, configs or windows: it takes a volume and plain descriptions
 * (struct reference_desc, the renderer's render_view matrices) and returns images in memory;
 * whoever calls it reads the scene and writes the files.  It never prints; failures go to the
 * log.
 */
#ifndef ANVIL_REFERENCE_REFERENCE_H
#define ANVIL_REFERENCE_REFERENCE_H

#include <stdbool.h>
#include <stdint.h>

#include "data/volume.h"
#include "optics/optics.h"
#include "render/image.h"
#include "render/render.h"

struct progress;

/* ---- random numbers: xoshiro256** (Blackman & Vigna 2018), seeded with splitmix64 -------- */

struct reference_rng {
    uint64_t s[4];
};

/* A stream determined by (SEED, STREAM) alone: the image renderer uses the pixel index as
 * STREAM, so results do not depend on the number of threads. */
void reference_rng_seed(struct reference_rng *rng, uint64_t seed, uint64_t stream);
uint64_t reference_rng_next(struct reference_rng *rng);
/* Uniform in [0, 1) with 53 random bits. */
double reference_rng_uniform(struct reference_rng *rng);

/* ---- phase functions: sampling (evaluation is optics' phase_hg / phase_cs) ---------------- */

enum reference_phase {
    REFERENCE_PHASE_CS, /* Cornette-Shanks, as the renderer's eye pass (default) */
    REFERENCE_PHASE_HG, /* Henyey-Greenstein (g = 0: isotropic, for the closed forms) */
};

/* Cosine of the scattering angle drawn from HG with asymmetry G (|G| clamped to 0.999 like
 * phase_hg).  Elek eq. 2.5 rearranged so that it stays exact as G -> 0. */
double reference_sample_hg(double g, struct reference_rng *rng);
/* Cosine drawn exactly from CS with parameter G (not its mean cosine): rejection from HG with
 * the same G, accepted with probability (1 + mu^2) / 2; mean acceptance (2 + g^2) / 3. */
double reference_sample_cs(double g, struct reference_rng *rng);

/* ---- the scene ------------------------------------------------------------------------- */

/* Zero means default where noted (reference_desc_defaults fills them). */
struct reference_desc {
    enum reference_phase phase;
    double g_ice, g_water;    /* phase parameters as the phase function takes them (for CS
                                 the CS parameter, not the mean cosine) */
    double albedo;            /* single-scattering albedo; default 1 */
    double sun_dir[3];        /* unit vector toward the sun */
    double sun_irradiance[3]; /* E per colour channel (see above) */
    double sky[3];            /* sky radiance, every direction not blocked by the ground */
    double ground_albedo[3];  /* Lambertian plane z = 0 */
    bool ground_on;
    int block;        /* majorant block edge in voxels; 0 = 8 */
    long max_bounces; /* safety cap on scattering events per path; 0 = none */
};

/* Defaults: CS with g = 0, albedo 1, sun overhead with E = 0, no sky, no ground, block 8. */
void reference_desc_defaults(struct reference_desc *d);

/* The reference for what the renderer draws with S and OPTICS: CS phases with the
 * parameters whose mean cosines are optics g_ice / g_water (untruncated), E = 4 pi
 * sun_radiance, the same sky, ground and sun direction, albedo 1. */
void reference_desc_from_render(const struct render_settings *s, const struct optics_params *optics,
                                struct reference_desc *d);

struct reference;

/* Prepares VOL for tracing (the bound grid).  VOL is borrowed, not copied: it must stay
 * unchanged and alive until reference_destroy.  Returns NULL (logged) on a bad description
 * (direction not unit, albedo outside [0, 1], grid without voxels) or out of memory. */
struct reference *reference_create(const struct ext_volume *vol, const struct reference_desc *d);
void reference_destroy(struct reference *ref);

/* ---- estimators (each call is one sample; thread safe for distinct RNGs) --------------- */

/* Extinction of both phases at P (metres) as the renderer samples it: trilinear between
 * voxel centres, clamp-to-edge inside the box, zero outside.  OUT[0] ice, OUT[1] water. */
void reference_beta(const struct reference *ref, const double p[3], double out[2]);

/* Delta tracking from ORIGIN along unit DIR over [T0, T1] (clipped to the box).  Returns
 * true with *T_HIT at a real collision, false when the ray passes (probability e^-tau). */
bool reference_free_flight(const struct reference *ref, const double origin[3], const double dir[3],
                           double t0, double t1, struct reference_rng *rng, double *t_hit);

/* Residual ratio tracking: an unbiased estimate of the transmittance along ORIGIN + t DIR,
 * t in [T0, T1] (clipped to the box); in [0, 1]. */
double reference_transmittance(const struct reference *ref, const double origin[3],
                               const double dir[3], double t0, double t1,
                               struct reference_rng *rng);

/* One path-traced sample of the radiance arriving at ORIGIN from along unit DIR (the ray
 * ORIGIN + t DIR, t >= 0, as a camera ray), RGB into OUT.  *UNCOLLIDED (may be NULL) tells
 * whether the first segment passed the medium without a real collision: its mean is the
 * transmittance to the background, the renderer's alpha. */
void reference_radiance(const struct reference *ref, const double origin[3], const double dir[3],
                        struct reference_rng *rng, double out[3], bool *uncollided);

/* ---- images -------------------------------------------------------------------------- */

struct reference_image_desc {
    int spp;     /* samples per pixel, >= 1 (the standard error needs >= 2) */
    int threads; /* 0 = one per online CPU */
    uint64_t seed;
    bool jitter; /* spread samples over the pixel; false samples the centre as the renderer
                    does */
    struct progress *progress; /* rows done are counted here (NULL: not) */
};

/* Renders VIEW (the renderer's matrices; rays start at the near plane, one per sample through
 * the pixel centre unless jittered) into RADIANCE (mean: RGB radiance, alpha the
 * transmittance to the background) and STDERR (standard error of each mean, alpha
 * likewise), both initialised here at the view's size, rows bottom to top like the GPU's.
 * Deterministic for a given SEED whatever the thread count.  Returns false (logged) on out of
 * memory or a failed thread start; the images are then finished. */
bool reference_render(const struct reference *ref, const struct render_view *view,
                      const struct reference_image_desc *d, struct image *radiance,
                      struct image *stderr_img);

#endif
