/*
 * light/volume: the diffuse light as one 3-D field (docs/lightmap.md, "The diffuse light
 * volume"), the alternative to the light map's independent columns.  The light the beam loses
 * anywhere in the volume (what the deep light map's sweep takes out of it) is the source of a
 * diffusion (P1) problem on a coarse world-aligned grid of cells over the volume box, solved to
 * convergence: diffuse light flows in every direction, across light columns and out of the
 * sides of towers, which the tilted columns cannot do.  Like the light map it depends on the
 * sun, the extinction and the light settings, not on the view, so one field serves every eye.
 *
 * The contract is the converged solution of the discrete system below (light_volume_build, in
 * double, preconditioned conjugate gradients); any solver that reaches it within the stated
 * residual gives the same field.  No GL, no config, no files.
 */
#ifndef ANVIL_LIGHT_VOLUME_H
#define ANVIL_LIGHT_VOLUME_H

#include <stdbool.h>
#include <stddef.h>

#include "data/volume.h"
#include "light/light.h"

/* The solve's preconditioner (light_volume_build; the GPU build mirrors both). */
enum light_volume_precond {
    LIGHT_VOLUME_PRECOND_BRICKS, /* block Jacobi on bricks plus a coarse correction */
    LIGHT_VOLUME_PRECOND_JACOBI, /* the diagonal alone */
};

/* The bricks' preconditioner: bricks of LIGHT_VOLUME_BRICK cells a side, each solved by
 * LIGHT_VOLUME_BRICK_SWEEPS symmetric red-black Gauss-Seidel sweeps, and the coarse system
 * (one cell a brick) by LIGHT_VOLUME_COARSE_SWEEPS (light_volume_build; chosen on the storm,
 * docs/lightmap.md "The diffuse light volume", "Solve"). */
#define LIGHT_VOLUME_BRICK 4
#define LIGHT_VOLUME_BRICK_SWEEPS 2
#define LIGHT_VOLUME_COARSE_SWEEPS 4

/* Zero means default. */
struct light_volume_desc {
    int resolution[3];   /* cells along x, y, z; 0 = the volume's voxels / 2, within [2, 32] */
    int substeps;        /* samples of the source and the extinction per cell and axis; 0 = 3 */
    double tolerance;    /* relative residual the solve stops at; 0 = 1e-6 */
    int max_iterations;  /* 0 = 4000 */
    enum light_volume_precond preconditioner; /* 0 = bricks */
};

struct light_volume {
    struct grid3 grid;   /* the cells: the volume box cut into grid.n cells of grid.spacing */
    /* Per cell, four floats: the fluence phi and the net flux F (x, y, z), both relative to
     * the sun's irradiance E.  In the P1 radiance I(w) = (phi + 3 F.w) E / (4 pi) they are
     * what light_map.diffuse's M and the flux of the columns are: phi = 4 pi I0 / E. */
    float *field;
    int iterations;      /* conjugate gradient iterations the build took */
    double residual;     /* relative residual reached */
    double source;       /* the total source, sum of Q0 V over the cells, E m^2: the power the
                            beam lost in the volume over E */
    double leak;         /* the net flux out through the box's faces, E m^2 (= source when
                            converged: albedo 1, nothing is absorbed) */
};

/* Fills the defaults of D's zero fields for a volume on GRID. */
void light_volume_desc_defaults(struct light_volume_desc *d, const struct grid3 *grid);

/* The per-phase terms of the source ([0] water, [1] ice) for the settings S and the sun SUN:
 * TR = 1 - g, LOSS the share of the extinction that leaves the beam (what the forward cone
 * and ring do not keep), GS the mean cosine of what leaves it (the phase's first moment less
 * the cone's, over LOSS). */
void light_volume_phase_terms(const struct light_settings *s, const double sun[3], double tr[2],
                              double loss[2], double gs[2]);

/* Builds the diffuse light volume of VOL lit by the beam of MAP (light_map_build's, any
 * storage of the settings S: forward, peripheral and the phases' terms are read from S) into
 * OUT, which must be zeroed or hold an earlier volume.  D may be NULL (defaults).  On failure
 * (logged: out of memory, a solve that does not converge) OUT is finished and false returned.
 * CPU, single thread. */
bool light_volume_build(const struct ext_volume *vol, const struct light_map *map,
                        const struct light_settings *s, const struct light_volume_desc *d,
                        struct light_volume *out);

/* Frees the field and zeroes V; NULL and zeroed volumes are fine. */
void light_volume_finish(struct light_volume *v);

/* The field at world point P [m], trilinear between cell centres, clamped to the edge cells
 * inside the box; zero outside it.  OUT: phi, Fx, Fy, Fz. */
void light_volume_sample(const struct light_volume *v, const double p[3], float out[4]);

/* The cells of DESC's resolution (its defaults filled) over the volume box BOX: the grid of
 * light_volume_build's field and of the GPU build's. */
void light_volume_grid(const struct grid3 *box, const struct light_volume_desc *desc,
                       struct grid3 *out);

/* The source light_volume_build gives cell CELL (its indices along x, y, z) of VOL lit by MAP
 * (the settings S, the desc DESC or NULL for the defaults): *Q0, the power the beam loses in the
 * cell over its volume and E (per metre), and DQ, Q0 times the offset of the loss's centroid
 * from the cell's centre (metres). */
void light_volume_cell_source(const struct ext_volume *vol, const struct light_map *map,
                              const struct light_settings *s, const struct light_volume_desc *desc,
                              const int cell[3], double *q0, double dq[3]);

/* The resistance to the net flux at a surface that faces clear air (the box's faces, and the
 * jump from optically thick to clear inside it), per unit area in units of 1 / flux per
 * fluence: phi at the surface = R F.  A Milne-type condition.  The exact solution of Milne's
 * problem (a conservative, isotropically scattering half space) has its asymptotic diffusion
 * fluence extrapolate to zero at z0 = 0.7104 transport mean free paths beyond the surface
 * (Case & Zweifel, "Linear Transport Theory", 1967; Davison, "Neutron Transport Theory",
 * 1957).  With F = -D dphi/dn and D = 1 / (3 sigma_tr), phi_s = z0 |dphi/dn| = 3 x 0.7104 F:
 * R = 2.1312.  Marshak's vacuum condition (the incoming half-range flux phi / 4 - F / 2 set to
 * zero) gives R = 2, an extrapolation length of 2 / 3: it lets a little too much out. */
#define LIGHT_VOLUME_BOUNDARY_R 2.1312

/* The largest |F| / phi the eye reads: the flux beyond it is scaled down to it.  P1 keeps its
 * radiance non-negative up to 1/3; where the eye looks (the first optical depths of a cloud's
 * surface) the field is far from P1's two moments (light just scattered out of the beam runs
 * on forward, the light leaving runs out), and its flux applied through the phase's mean
 * cosine (0.86 for water) swings the light scattered toward the eye by up to 86 %, which made
 * a layer seen from the sun's side at low elevation 0.05 x Monte Carlo and from the other side
 * 1.4 x.  The cap was chosen on the bench's layer table (docs/accuracy.md, "The diffuse light
 * volume"): 0.05 and 0.15 were each worse in one corner of it. */
#define LIGHT_VOLUME_ANISOTROPY 0.1

/* What the field scatters toward the eye, relative to E / (4 pi) as the eye pass counts the
 * sun's P_v(psi) L: the phase's first moment applied to the P1 radiance,
 * max(phi + 3 g F.DIR, 0) with |F| capped at LIGHT_VOLUME_ANISOTROPY phi, DIR the unit
 * direction the scattered light travels (toward the eye), G the phase's mean cosine. */
float light_volume_scattered(const float field[4], float g, const double dir[3]);

/* Bytes of the field as an RGBA32F 3D texture. */
size_t light_volume_bytes(const struct light_volume *v);

#endif
