/*
 * light: the deep light map (Nes §5.3) on the CPU.  A light-space grid across and along the sun
 * direction, light transport swept slice by slice from the sun side with self-shadowing and
 * central plus peripheral forward scattering (Nes eq. 5.8-5.11, Riley eq. 14-17), node
 * compression of each light ray (Nes Algorithm 2, Lokovic-Veach), and the key that decides when
 * a map must be rebuilt.
 *
 * This is the reference that the GPU build (a compute shader, later in this folder) mirrors: the
 * same grid, the same sample positions, the same float32 arithmetic.  docs/lightmap.md states
 * the discretisation.  No GL here, no config, no files; volumes come from data/volume.h and
 * cumulative phases from optics (optics_forward_cp), passed in through light_settings.
 *
 * Light-space frame: w = -sun (the direction light travels), u and v across it, (u, v, w)
 * right-handed.  The grid has n[0] x n[1] x n[2] NODES spanning the projection of the volume box
 * on u, v and w exactly: node (i, j, k) sits at light coordinates lo + (i, j, k) * step with
 * step = (hi - lo) / (n - 1).  Node plane k = 0 is the plane through the box corner nearest the
 * sun; k grows along the light.  Values are stored i fastest: index = i + n0 (j + n1 k).
 *
 * Stored value: the light intensity at the node's world point, relative to the incident sun
 * (1 = unattenuated), travelling along w: direct light plus light forward-scattered within the
 * forward angle.  It is what a particle at that point receives from the sun; the eye pass
 * multiplies it by the sample's (1 - T_s) P_v(psi) (Nes eq. 5.18).  Always within [0, 1].
 *
 * Must not know: views, cameras, windows, configs, the session.
 */
#ifndef ANVIL_LIGHT_H
#define ANVIL_LIGHT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "data/volume.h"
#include "optics/optics.h"

/* Unit vector TOWARD the sun in the world frame (x east, y north, z up) from the azimuth
 * (degrees clockwise from north) and elevation (degrees above the horizon):
 * (sin az cos el, cos az cos el, sin el).  Multiples of 90 degrees give exact zeros and ones. */
void light_sun_direction(double azimuth_deg, double elevation_deg, double out[3]);

/* Extinction at world point P [m] from VOL: trilinear between voxel centres, clamped to the
 * edge voxels inside the box, zero outside the box (the box is closed: its faces are inside).
 * OUT[0] scatters with the ice phase, OUT[1] with the water phase, 1/m.  Float32 like the GPU;
 * a negative or NaN result reads as 0. */
void light_sample_beta(const struct ext_volume *vol, const float p[3], float out[2]);

/* ---- light-space grid ------------------------------------------------------------------- */

struct light_grid {
    double sun[3];           /* unit, toward the sun */
    /* Upright grid (sheared false): u, v, w orthonormal, w = -sun, u x v = w; node planes
     * across the light.  Sheared grid (a box flat against the light's drift, see
     * light_grid_init): u horizontal across the light, v horizontal along the light's
     * heading, w = -sun; node planes horizontal, so every column crosses a flat volume's
     * whole height in n[2] - 1 slices. */
    bool sheared;
    double u[3], v[3], w[3];
    double lo[3], hi[3];     /* upright: the box projected on u, v, w; sheared: the columns'
                                first plane on u, v, and 0 .. the column length */
    int n[3];                /* nodes along u, v, w (each >= 2) */
    double step[3];          /* node spacing along u and v, and the path along the light from
                                one node plane to the next, metres */
    /* World position of node (i, j, k) = origin + i du + j dv + k dw, as the float32 values
     * the transport loop uses (GPU uniforms). */
    float origin[3], du[3], dv[3], dw[3];
    /* World point (metres, homogeneous) -> texture coordinates of a 3D texture holding the
     * nodes, column-major: node (i, j, k) maps to the texel centre ((i, j, k) + 0.5) / n, so
     * hardware trilinear filtering interpolates between nodes.  Points inside the volume box
     * map inside [0.5/n, 1 - 0.5/n]. */
    float world_to_tex[16];
};

/* Sets up the grid for the sun direction SUN (toward the sun, any nonzero length) over the box
 * of BOX with N nodes per axis.  u is horizontal unless the sun is within ~26 degrees of the
 * zenith or nadir (then u is taken across the x axis); the choice is deterministic and exact
 * for axis-aligned suns.  The grid is sheared (horizontal node planes) when the sun is between
 * about 3 and 64 degrees from the horizon and the light drifts across the box's height by at
 * most a quarter of its smaller horizontal size (a WRF domain; docs/lightmap.md, "Light-space
 * grid"); else, or with KIND LIGHT_GRID_UPRIGHT, upright.  Returns false (logged) on a zero or non-finite SUN, a degenerate box,
 * or N outside [2, 4096]. */
enum light_grid_kind { LIGHT_GRID_AUTO, LIGHT_GRID_UPRIGHT };
bool light_grid_init(struct light_grid *g, const double sun[3], const struct grid3 *box,
                     const int n[3], enum light_grid_kind kind);

/* World position of node (i, j, k), metres (double, from the frame; for tests and tools). */
void light_grid_node_world(const struct light_grid *g, double i, double j, double k, double out[3]);

/* World point P -> texture coordinates (applies world_to_tex). */
void light_grid_world_to_tex(const struct light_grid *g, const double p[3], double out[3]);

/* ---- settings and the dense map ----------------------------------------------------------- */

struct light_settings {
    int resolution[3];        /* nodes [across u, across v, along the light] */
    double forward_angle_deg; /* theta: light scattered within theta/2 stays in the beam */
    bool forward;             /* forward scattering on; off = shadow only */
    bool peripheral;          /* peripheral ring theta/4 .. theta/2 on (needs forward) */
    bool multiple;            /* multiple scattering: the diffuse light of the two-stream
                                 column pass (light_map.diffuse) */
    bool volume;              /* with multiple: the GPU build makes the 3-D diffuse light
                                 volume (light_volume.h) in place of the columns' diffuse
                                 light (effects.multiple = "volume"); light_map_build, the
                                 columns' CPU reference, ignores it */
    bool lateral;             /* with multiple: diffuse light escapes through the sides of
                                 clouds narrower than the plane-parallel column assumes */
    enum light_grid_kind grid; /* auto: sheared for flat boxes; upright: never sheared */
    struct optics_cp cp;      /* CP(theta/4) and CP(theta/2) - CP(theta/4) per phase */
    double epsilon;           /* compression error bound (compressed storage only) */
    int substeps;             /* extinction samples per slice; 0 = light_auto_substeps */
};

/* Defaults: 128^3 nodes, theta = 20 degrees, forward and peripheral on, lateral escape on
 * (it acts with multiple only), epsilon 0.002,
 * substeps auto, and cp all zero: call light_settings_set_optics (or fill cp) before building
 * with forward on. */
void light_settings_defaults(struct light_settings *s);

/* Sets the forward angle and fills cp from OPTICS with optics_forward_cp. */
void light_settings_set_optics(struct light_settings *s, const struct optics_params *optics,
                               double forward_angle_deg);

/* One phase for every species (effects.phase off): copies the ice phase's (ICE) or the water
 * phase's terms of s->cp over the other's, so the build compiles the mix out. */
void light_settings_one_phase(struct light_settings *s, bool ice);
/* Whether both phases' terms in s->cp are equal (the mix is then exact and compiled out). */
bool light_settings_phases_equal(const struct light_settings *s);

/* Peripheral offset (metres): the distance in the across-light plane, one slice spacing DZ
 * back, of a ray arriving from the middle of the peripheral ring, 3 theta / 8:
 * dz tan(3 theta / 8). */
double light_peripheral_offset(double forward_angle_deg, double dz);

/* The peripheral taps of grid G in node units along u and v for the offset R (metres across
 * the light): R / step along u; along v as well in an upright grid, R / (step |w_z|) in a
 * sheared one, whose v runs horizontally and so crosses the light at sin(elevation). */
void light_grid_peripheral_taps(const struct light_grid *g, double r, float out[2]);

/* Extinction samples per slice so that the samples along the light are no farther apart than
 * the shortest distance in which the light crosses one voxel (min over axes of
 * spacing_a / |w_a|): 1 when the light grid is as fine as the volume, more for flat volumes
 * lit at low sun (Isabel: 2000 km wide, 20 km high).  At most 128. */
int light_auto_substeps(const struct light_grid *g, const struct grid3 *box);

struct light_map {
    struct light_grid grid;
    int substeps;   /* extinction samples per slice used by the build */
    float *light;   /* grid.n[0] * grid.n[1] * grid.n[2] values in [0, 1], owned */
    /* With settings.multiple, the diffuse light at each node, two floats per node in the same
     * order: M = 2 (U + V) and N = 2 (U - V) for the diffuse fluxes U (through a horizontal
     * plane away from the sun's side: down when the sun is up) and V (back toward it) of the
     * two-stream column pass, per unit horizontal area, relative to the sun's irradiance E.
     * In the Eddington radiance I(mu) = I0 + I1 mu (mu the cosine with that vertical
     * direction), M = 4 pi I0 / E and N = (8 pi / 3) I1 / E; the eye pass scatters
     * M + (3/2) g N mu_eye toward the eye beside P_v(psi) L_l.  M >= 0, |N| <= M; NULL when
     * off. */
    float *diffuse;
};

/* Computes the dense light map of VOL for the sun direction SUN (toward the sun) with settings
 * S.  MAP must be zeroed or hold an earlier map (its array is reused when the size matches).
 * On failure (logged) MAP is finished.  CPU, single thread, float32 transport. */
bool light_map_build(const struct ext_volume *vol, const double sun[3],
                     const struct light_settings *s, struct light_map *map);

/* Frees the array and zeroes MAP; NULL and zeroed maps are fine. */
void light_map_finish(struct light_map *map);

static inline float light_map_node(const struct light_map *m, int i, int j, int k)
{
    const int *n = m->grid.n;
    return m->light[(size_t)i + (size_t)n[0] * ((size_t)j + (size_t)n[1] * (size_t)k)];
}

/* Texture coordinate TEX on an axis of N nodes -> lower node index, with *T the weight of the
 * next node; clamped to [0, n - 1] like GL_LINEAR with CLAMP_TO_EDGE. */
int light_tex_node(float tex, int n, float *t);
/* Trilinear lookup at texture coordinates TEX (as from world_to_tex), clamped to the edge
 * nodes: what a GL_LINEAR, CLAMP_TO_EDGE sampler3D returns (up to its weight precision).
 * light_map_sample_diffuse does the same for M and N of the diffuse array (0 when there is
 * none). */
float light_map_sample(const struct light_map *m, const float tex[3]);
void light_map_sample_diffuse(const struct light_map *m, const float tex[3], float out[2]);

/* The per-phase terms of the diffuse pass ([0] water, [1] ice): the share of the extinction
 * that leaves the beam (what the forward cone and ring do not keep), the share of all scattered
 * light that leaves it AND heads up toward the sun's side of the horizontal (it depends on the
 * sun's elevation: phase_cs_back_fraction), and the Eddington coupling 3 (1 - g) / 4; mu0 is
 * |sin(elevation)| (at least 1e-3). */
struct light_diffuse_terms {
    float loss[2], back[2], gamma[2];
    float mu0;
};

void light_diffuse_terms_init(const struct light_settings *s, const double sun[3],
                              struct light_diffuse_terms *t);

/* Extinction (per metre) below which a voxel counts as clear air between clouds: 0.01 per km,
 * so that 100 km of it is optical depth 1. */
#define LIGHT_CLEAR_BETA 1e-5f

/* The lateral escape rates of every voxel of VOL (docs/lightmap.md, "Lateral escape"), each
 * times the voxel's extinction: OUT[2 v] and OUT[2 v + 1] are beta_v / w along x and along y,
 * w the optical width of the run of cloudy voxels (extinction at least LIGHT_CLEAR_BETA) that
 * holds voxel v along that axis, summed in float32 from the run's lower end; 0 in clear
 * voxels.  Interpolated like the extinction and divided by it, they give the rate 1 / w
 * weighted by the extinction at the point: a thin cloud touching a thick one does not lend
 * the thick one its rate.  NaN and negative extinction read as clear, infinity as 1e30. */
void light_lateral_rates(const struct ext_volume *vol, float *out);
/* The same for the voxels of plane K only, into OUT (2 n0 n1 floats, the plane's own
 * indexing): runs lie within a plane, so these are the plane's values of light_lateral_rates
 * exactly.  Safe to call for different planes from several threads at once. */
void light_lateral_rates_plane(const struct ext_volume *vol, int k, float *out);

/* The lateral escape of the diffuse light, per unit vertical optical depth, for the rates RX,
 * RY of light_lateral_rates and the Eddington coupling GAMMA (docs/lightmap.md, "Lateral
 * escape"): along each axis r e^-((1 - g) / r), 1 - g = 4 GAMMA / 3.  A diffuse photon in a
 * run of optical width w = 1 / r flies out of its side before it scatters again at the rate
 * r per unit vertical optical depth (the isotropic mean of |sin theta cos phi| is 1/2, the
 * two-stream path is 2 per unit depth); the factor leaves that to runs narrower than a
 * transport mean free path, 1 / (1 - g): wider, the light a cloud loses through its sides
 * is the brightness of those sides, which a column cannot place, and the plane-parallel
 * column is the better estimate.  It enters the two-stream equations as absorption does. */
float light_lateral_escape(float gamma, float rx, float ry);

/* The two-stream pass of one light column (light_map_build with settings.multiple; exposed for
 * tests), in the tilted independent column approximation: the column along the light is solved
 * as a plane-parallel atmosphere lit at mu0 whose layers are its slices (docs/lightmap.md,
 * "Multiple scattering").  N nodes from the sun's side; BEAM[k] the light map values down the
 * column; TAU[k] and F_ICE[k], k >= 1, the optical depth along the light and the ice share of
 * the slice from node k - 1 to node k (TAU[0], F_ICE[0] unused); LATERAL, NULL for none,
 * the slice's lateral escape rates (LATERAL[2 k], LATERAL[2 k + 1]: light_lateral_rates
 * averaged over the slice), which make the slice lose diffuse light through its sides
 * (light_lateral_escape); D the phase terms.  Writes
 * OUT[2 k] = M and OUT[2 k + 1] = N at every node (see light_map.diffuse).  SCRATCH holds 2 N
 * floats.  Without lateral escape scattering is conservative: a slice is a layer of vertical optical depth mu0 TAU that
 * receives what the beam loses in it, mu0 BEAM (1 - e^-(loss TAU)) per unit horizontal area;
 * that is split between the hemispheres by the phase, and the diffuse fluxes are coupled by
 * the Eddington two-stream equations, integrated exactly across each slice and joined by the
 * adding method (docs/lightmap.md). */
void light_diffuse_column(int n, const float *beam, const float *tau, const float *f_ice,
                          const float *lateral, const struct light_diffuse_terms *d,
                          float *scratch, float *out);

/* Bytes of the dense map as a float32 3D texture. */
size_t light_map_bytes(const struct light_map *m);

/* ---- compression ------------------------------------------------------------------------- */

/* Compresses one visibility function: COUNT samples (DEPTH[i], VALUE[i]), depths
 * non-decreasing, into nodes (OUT[2 m] = depth, OUT[2 m + 1] = intensity) such that linear
 * interpolation between the nodes stays within EPSILON of every sample (up to float rounding)
 * (Nes Algorithm 2, eq. 5.14-5.17, with Lokovic-Veach's choice of the node on the feasible
 * slope cone).  Equal depths give a step (two nodes at one depth) or merge when within EPSILON;
 * EPSILON = 0 keeps exactly collinear runs merged.  A flat start or tail (within EPSILON) is
 * left to the clamping of light_column_eval, so a constant function is one node and the first
 * node need not sit at the first depth.  OUT holds at least 2 COUNT floats.  Returns
 * the number of nodes (>= 1 when COUNT >= 1), or -1 (logged) on decreasing or non-finite
 * input or a negative or non-finite EPSILON. */
int light_compress_column(const float *depth, const float *value, int count, double epsilon,
                          float *out);

/* The same for two functions of the same samples at once (the diffuse light's M and N):
 * nodes (OUT[3 m] = depth, OUT[3 m + 1], OUT[3 m + 2] = the two values) such that linear
 * interpolation keeps each within EPSILON of its samples; a segment ends where either would
 * leave its hoops, a flat start or tail is one where both are flat.  OUT holds 3 COUNT floats.
 * With one function it is light_compress_column, node for node. */
int light_compress_column2(const float *depth, const float *value0, const float *value1,
                           int count, double epsilon, float *out);

/* Value of a compressed visibility function at DEPTH: binary search for the segment, then linear
 * interpolation; clamped to the first and last node; a step (equal depths) takes the later
 * node; the result is clamped to [0, 1]. */
float light_column_eval(const float *nodes, uint32_t count, float depth);

/* The compressed deep light map in a GPU-friendly layout (two SSBOs): per column (i + n0 j)
 * columns[2 c] = index of its first node, columns[2 c + 1] = its node count; nodes[2 m] = depth
 * in node-plane units (k, so depth d is at light coordinate lo_w + d step_w), nodes[2 m + 1] =
 * intensity.  With multiple scattering the diffuse light likewise, M and N compressed together
 * (light_compress_column2): diffuse_columns as columns, diffuse_nodes[3 m] = depth,
 * [3 m + 1] = M, [3 m + 2] = N. */
struct light_compressed {
    struct light_grid grid;
    uint32_t *columns; /* 2 n0 n1, owned */
    float *nodes;      /* 2 node_count, owned */
    size_t node_count;
    uint32_t *diffuse_columns; /* 2 n0 n1, owned; NULL without the diffuse light */
    float *diffuse_nodes;      /* 3 diffuse_node_count, owned */
    size_t diffuse_node_count;
    double epsilon;
};

/* Compresses every column of MAP within EPSILON, its diffuse light too when it has one.  OUT
 * is initialised here; on failure (logged) it is finished. */
bool light_compressed_build(const struct light_map *map, double epsilon,
                            struct light_compressed *out);

void light_compressed_finish(struct light_compressed *c);

/* Lookup at texture coordinates TEX, mirroring light_map_sample: bilinear over the four
 * neighbouring columns (clamped to the edge), each evaluated at the depth by light_column_eval. */
float light_compressed_sample(const struct light_compressed *c, const float tex[3]);

/* The diffuse light at TEX, mirroring light_map_sample_diffuse: bilinear over the four
 * columns, each by binary search and linear interpolation along it (clamped to its first and
 * last node, not to [0, 1]); 0 and 0 without the diffuse light. */
void light_compressed_sample_diffuse(const struct light_compressed *c, const float tex[3],
                                     float out[2]);

/* Bytes of all arrays as SSBOs. */
size_t light_compressed_bytes(const struct light_compressed *c);

/* ---- rebuild on change ------------------------------------------------------------------- */

/* Everything that determines a light map.  VOLUME_ID names the data (e.g. the time step);
 * VOLUME_GENERATION must change whenever the extinction values change for any other reason
 * (optics radii/densities, species selection or scale, a reload). */
struct light_key {
    struct grid3 box;
    double sun[3]; /* normalised */
    uint64_t volume_id;
    uint64_t volume_generation;
    struct light_settings settings;
};

void light_key_init(struct light_key *k, const struct grid3 *box, const double sun[3],
                    uint64_t volume_id, uint64_t volume_generation, const struct light_settings *s);

/* Field-wise equality (no padding bytes compared) and a 64-bit FNV-1a hash of the same
 * fields.  -0.0 and 0.0 compare and hash equal. */
bool light_key_equal(const struct light_key *a, const struct light_key *b);
uint64_t light_key_hash(const struct light_key *k);

/* Remembers the key of the map that is current, and counts builds. */
struct light_cache {
    bool valid;
    struct light_key key;
    uint64_t hash;
    unsigned builds;
    double last_ms, total_ms;
};

void light_cache_init(struct light_cache *c);
/* True when no map has been built yet or K differs from the current map's key. */
bool light_cache_stale(const struct light_cache *c, const struct light_key *k);
/* Records that a map for K has just been built, taking MS milliseconds. */
void light_cache_built(struct light_cache *c, const struct light_key *k, double ms);
/* Forgets the current map (e.g. after a failed build or a lost GL context). */
void light_cache_invalidate(struct light_cache *c);

/* CPU convenience: rebuilds MAP (and COMPRESSED when not NULL) only when K is stale.  Returns
 * false (logged) when a needed build failed; *BUILT says whether a build happened. */
bool light_map_update(const struct ext_volume *vol, const struct light_key *k,
                      struct light_cache *cache, struct light_map *map,
                      struct light_compressed *compressed, bool *built);

#endif
