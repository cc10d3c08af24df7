/*
 * render: ray casting one view of the volume on the GPU (compute shader), and tone mapping.
 * A renderer owns the view-independent GPU state — the extinction texture, the eye phase
 * table, the programs — so any number of views can be drawn from it without redoing that
 * work.  It does not know where views come from (display) or how the volume was made (data).
 * Every function needs the GL context current.
 *
 * Must not know: where views come from (displays, cameras), how volumes or light maps are
 * made, configs, windows.
 */
#ifndef ANVIL_RENDER_H
#define ANVIL_RENDER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "data/volume.h"
#include "gpu/gpu.h"
#include "optics/optics.h"
#include "render/image.h"

/* Lighting and background shared by every view of a frame. */
struct render_settings {
    float sun_dir[3];      /* unit vector toward the sun */
    float sun_radiance[3]; /* intensity times colour */
    float sky[3];          /* background radiance */
    float ground[3];       /* ground albedo */
    bool ground_on;
    float step_m;          /* ray step; 0 = half the voxel crossing along each ray */
    float termination;     /* stop rays below this transmittance */
    /* Level of detail (LOD 1, render.lod): a step at least this many pixels wide where it
     * is; 0 = off, every step the voxel rule's or step_m. */
    float lod_pixels;
    /* Effects compiled out of the eye pass (app/effects.h); zero = simulated. */
    bool single_phase;     /* one phase for every species: PHASE_MIX 0 */
    bool single_phase_ice; /* ... the ice phase (else the water phase) */
    bool no_ground_shadow; /* the ground sees the full sun: GROUND_SHADOW 0 */
    /* effects.temporal: with a next volume set (renderer_set_next_volume), the eye pass
     * blends beta = mix(beta_k, beta_k+1, temporal_f): TEMPORAL 1.  False: compiled out. */
    bool temporal;
    float temporal_f;      /* in [0, 1]; also the blend of a light map pair (LIGHTMAP_PAIR) */
    /* Empty-space skipping off (SKIP 0): every step reads the volume, as before the macro
     * cells; the pictures are the same (tests/gl/test_skip.c), only slower.  For comparisons. */
    bool no_skip;
};

/* Steps one ray may take at most, whatever render.step asks: a bound on the work of a
 * pixel (a GPU that runs too long is reset by its driver). */
#define RENDER_MAX_STEPS 16384

/* One view: camera matrices (column-major, world metres) and image size. */
struct render_view {
    float view[16];
    float proj[16];
    int width, height;
};

/* Statistics a caller may report (--stats); the views' times go to renderer_set_timing's
 * log. */
struct render_stats {
    unsigned views;         /* views drawn */
    double upload_ms;       /* CPU+GPU time of the last volume upload */
    uint64_t upload_bytes;  /* bytes of every volume uploaded (extinction, tints, the layers'
                               and slices' fields, next) and of macro cells made on the CPU */
    unsigned uploads;       /* volumes uploaded */
    unsigned cpu_cells;     /* staged volumes whose macro cells the CPU made */
};

/* What the views' rays did, summed over every view drawn since renderer_set_counting turned
 * counting on: device-independent work (a GPU's time divides by these, not by pixels). */
struct render_counts {
    uint64_t beta_samples; /* trilinear extinction samples */
    uint64_t light_reads;  /* light map lookups (a dense map: one filtered fetch each) */
    uint64_t cells_read;   /* macro cells read by empty-space skipping */
    uint64_t steps_leapt;  /* ray steps leapt without reading the volume */
    uint64_t rays;         /* pixels cast */
    uint64_t rays_marched; /* of them, those that met an occupied cell and were marched (with
                              skipping; without, every ray is) */
};

/* Hooks for light maps: a light map binds its own textures/buffers and uniforms before the
 * eye pass and names the shader variant that reads it.  NULL means no light map. */
struct render_light {
    const char *defines; /* e.g. "#define LIGHTMAP 1\n" */
    void (*bind)(const struct render_light *light, const struct gpu_program *prog);
};

struct renderer;

/* Creates the renderer and compiles the default program.  Returns NULL (logged) when a shader
 * does not compile. */
struct renderer *renderer_create(void);
void renderer_destroy(struct renderer *r);

/* The largest extinction half-float storage holds, 1/m (the largest finite half float). */
#define RENDER_HALF_MAX 65504.0f

/* Stores the following volumes (renderer_set_volume, renderer_set_next_volume) in half floats
 * (RG16F: half the memory, about three decimal digits; extinction beyond RENDER_HALF_MAX 1/m
 * clamps to it, NaN and negative stay as they are and read as 0) or, HALF false (the default),
 * in floats (RG32F). */
void renderer_set_half(struct renderer *r, bool half);
/* How renderer_stage_next copies the next volume into the pixel buffer: PACED, in slices of
 * renderer_stage_step's budget on the render thread between frames; else on the stage's
 * thread beside the frames.  Paced from the start on a software driver (gpu_software_driver:
 * there a copy thread competes with the rasteriser's for the cores); takes effect at the
 * next renderer_stage_next. */
void renderer_set_stage_paced(struct renderer *r, bool paced);
bool renderer_stage_paced(const struct renderer *r);
/* Whether renderer_stage_next has the stage make the next volume's macro cells on the CPU with
 * its copy (render_cells_cpu; on from the start), so that renderer_stage_step only uploads
 * them, or the GPU build them from the uploaded texture in pieces.  Half floats
 * (renderer_set_half) always take the GPU's.  The cells are the same either way.  Takes effect
 * at the next renderer_stage_next. */
void renderer_set_stage_cpu_cells(struct renderer *r, bool cpu);
/* Whether the eye pass's first pass (with empty-space skipping) lists the rays it leaves to the
 * second by a subgroup ballot, one atomic a subgroup and no barrier (GL_ARB_shader_ballot and
 * GL_ARB_gpu_shader_int64; on from the start where the driver offers both), or by a work
 * group's shared count between barriers.  The rays listed, and so the picture, are the same
 * either way; only their order in the list differs.  Returns whether the ballot is used. */
bool renderer_set_ballot(struct renderer *r, bool on);
/* The CPU time the stage's cells have taken so far, ms (on the stage's thread, or with a paced
 * copy within renderer_stage_step's slices of it). */
double renderer_stage_cells_ms(struct renderer *r);

/* Uploads the extinction volume (replacing the last one; the texture is reused when the size
 * and storage are unchanged).  The volume is not kept. */
bool renderer_set_volume(struct renderer *r, const struct ext_volume *vol);
/* The grid of the last volume set. */
const struct grid3 *renderer_grid(const struct renderer *r);
/* The extinction texture (for light map builds).  Valid until the next set_volume. */
const struct gpu_texture *renderer_volume_texture(const struct renderer *r);

/* effects.temporal: uploads the next time step's extinction into a second RG32F texture
 * (NULL drops it).  Its tints, if any, are not used: the blend takes step k's. */
bool renderer_set_next_volume(struct renderer *r, const struct ext_volume *vol);
/* The next volume through a pixel buffer, so that a later step change is a swap of textures
 * already on the GPU (nothing uploaded, nothing built in that frame).  renderer_stage_next
 * starts copying VOL's arrays (extinction, tints, layers, slices, surfaces) into a
 * persistently mapped buffer on a thread of the renderer's (no GL there), and its extinction
 * into ALSO (2 floats a voxel, may be NULL: a CPU copy the caller keeps), making its macro
 * cells with the copy (renderer_set_stage_cpu_cells); VOL and ALSO are
 * borrowed and must stay valid until renderer_stage_step said *READY or renderer_stage_cancel
 * returned.  *STARTED false: the buffer is busy (try again later).  The next volume held
 * before is gone from now on (renderer_has_next false). */
bool renderer_stage_next(struct renderer *r, const struct ext_volume *vol, float *also,
                         bool *started);
/* Moves the staged volume on: with a paced copy (renderer_set_stage_paced), first copies about
 * BUDGET bytes of it into the buffer a call (0: all, and on); once the copy is complete, uploads at
 * most BUDGET bytes of it (whole z layers, at least one; 0: all) from the buffer into the next
 * volume's textures, and after the last uploads the cells the stage made or builds them, a few
 * layers of them a call (BUDGET 0: all in the last upload's).  *READY: the next volume is whole on
 * the GPU (now or before).  Never waits for the copy.  False (logged) on a GL failure. */
bool renderer_stage_step(struct renderer *r, size_t budget, bool *ready);
/* Whether a staged volume is being copied or uploaded; whether it is still being copied (the
 * stage's thread is on it: renderer_stage_step cannot move it on yet). */
bool renderer_stage_busy(const struct renderer *r);
bool renderer_stage_copying(const struct renderer *r);
/* What the next renderer_stage_step works on, in words ("an upload slab", ...): what the
 * playback bench names as the longest piece between two frames. */
const char *renderer_stage_doing(const struct renderer *r);
/* Whether the staged volume is being uploaded (copied, not yet all uploaded). */
bool renderer_stage_uploading(const struct renderer *r);
/* Waits for a copy in flight and drops the staged volume (its source may then go). */
void renderer_stage_cancel(struct renderer *r);
/* Makes the staged next volume the volume (and the volume the spare one): its extinction,
 * tints, fields, surfaces, cells and grid, by exchanging textures.  False when no whole next
 * volume is held (nothing changes). */
bool renderer_swap_next(struct renderer *r);
/* The cells of the staged next volume alone (its light build), or NULL without one. */
const struct render_cells *renderer_next_cells(const struct renderer *r);
/* Whether a next volume is held, its texture (for its light map build) and grid. */
bool renderer_has_next(const struct renderer *r);
const struct gpu_texture *renderer_next_texture(const struct renderer *r);
const struct grid3 *renderer_next_grid(const struct renderer *r);

/* ---- colour-mapped layers (docs/analysis.md) ---------------------------------------------
 * Up to TRANSFER_LAYER_MAX scalar fields beside the extinction (ext_volume.layer, uploaded by
 * renderer_set_volume into one RGBA32F texture, a field per channel), each classified after
 * trilinear interpolation by its colour map (a row of an RGBA32F table, linear filtering). */
#define RENDER_LAYER_LUT 256

struct render_layer {
    bool on;
    bool tint;                        /* tints the clouds' light instead of emitting */
    enum transfer_field field;        /* drawn only while the volume's layer holds this field */
    float lo, hi;                     /* field values at the map's first and last entry */
    float strength;                   /* emit: extinction at alpha 1, 1/m; tint: its weight */
    float lut[RENDER_LAYER_LUT][4];   /* linear RGB and alpha, entry i at lo + i/(N-1) (hi-lo) */
};

/* The radiance that tone mapping at EXPOSURE (> 0) shows as the display colour C in [0, 1]
 * (sRGB): the inverse of image_tonemap, white kept just below its asymptote, as the panels'
 * texels (session/panel.c). */
float render_display_to_radiance(float c, float exposure);

/* L as the eye pass draws it: its transfer function tabulated, the extinction at alpha 1 its
 * density times its opacity (emit) or the tint's weight its opacity (tint).  An emitting
 * layer's colours are display colours: radiance that tone mapping at EXPOSURE turns back into
 * them, so that a layer as opaque as can be shows the legend's colours (a tint's are factors,
 * as they are).  No GL. */
void render_layer_from_transfer(const struct transfer_layer *l, float exposure,
                                struct render_layer *out);

/* Draws the following views with LAYERS[0 .. COUNT) (COUNT <= TRANSFER_LAYER_MAX; 0: none),
 * layer i over the volume's field i.  The maps are uploaded only when they changed.  An
 * emitting layer that is on turns empty-space skipping off for the eye pass (the cells know
 * only the clouds).  False (logged) when the table cannot be made. */
bool renderer_set_layers(struct renderer *r, const struct render_layer *layers, int count);

/* Slices (docs/analysis.md): planes through the volume's slice fields (ext_volume.slice, a
 * second RGBA32F texture), each ray compositing a slice where it crosses it inside the box and
 * before the ground or opaque geometry: its colour map's colour at the field's interpolated
 * value, dark on contour lines, at its opacity. */
struct render_slice {
    bool on;
    enum transfer_field field;      /* drawn only while the volume's slice holds this field */
    float normal[3], offset;        /* the plane normal . p = offset, world metres */
    float lo, hi;
    float opacity;                  /* [0, 1] */
    float contour_every;            /* field units; 0: none */
    float contour_values[TRANSFER_CONTOUR_MAX]; /* lines also at these values ... */
    int contour_count;                          /* ... the first this many */
    bool surface;                   /* the volume's slice surface i (a model level) in place
                                       of the plane; drawn only while the volume holds one */
    float lut[RENDER_LAYER_LUT][4]; /* as render_layer's (alpha unused) */
};

/* SL as the eye pass draws it, its colours display colours at EXPOSURE (as an emitting
 * layer's).  No GL. */
void render_slice_from_transfer(const struct transfer_slice *sl, float exposure,
                                struct render_slice *out);

/* Draws the following views with SLICES[0 .. COUNT) (COUNT <= TRANSFER_SLICE_MAX), slice i
 * over the volume's slice field i.  A slice that is on turns empty-space skipping off.  False
 * (logged) when the table cannot be made. */
bool renderer_set_slices(struct renderer *r, const struct render_slice *slices, int count);

/* Tabulates the eye phase functions. */
bool renderer_set_optics(struct renderer *r, const struct optics_params *optics);

/* Uses LIGHT for the following draws (NULL: no light map).  LIGHT must stay valid. */
void renderer_set_light(struct renderer *r, const struct render_light *light);

/* Draws VIEW into OUT, an RGBA32F 2D texture of the view's size (alpha = transmittance to the
 * background).  Creates or resizes OUT when its size differs. */
bool renderer_draw(struct renderer *r, const struct render_settings *s,
                   const struct render_view *view, struct gpu_texture *out);

/* Tone maps IN (RGBA32F) into OUT (RGBA8, created or resized to match). */
bool renderer_tonemap(struct renderer *r, const struct gpu_texture *in, float exposure,
                      struct gpu_texture *out);

/* Counts what the rays of every following view do (COUNT 1: one atomic add per ray and
 * counter), from zero; false stops.  renderer_counts reads the sums back: it waits for the
 * GPU, so call it for a report, not per frame.  False when counting was never on. */
bool renderer_set_counting(struct renderer *r, bool on);
bool renderer_counts(struct renderer *r, struct render_counts *out);

/* Tone maps IN (RGBA32F) on the GPU as image_tonemap does on the CPU (to within one step of
 * the last bit where pow differs) and reads the bytes back into RGBA (w x h x 4, the caller's),
 * rows bottom to top; *NONFINITE (may be NULL) the pixels with a non-finite colour, as
 * image_count_nonfinite counts them.  Waits for the GPU. */
bool renderer_tonemap_read(struct renderer *r, const struct gpu_texture *in, float exposure,
                           uint8_t *rgba, size_t *nonfinite);

/* Reads an RGBA32F texture back into IMG (initialised here). */
bool renderer_read(const struct gpu_texture *tex, struct image *img);

const struct render_stats *renderer_stats(const struct renderer *r);

/* Times every following view into LOG (NULL, the default: views are not timed): the view's
 * number in LOG is its place among the timed views.  Drawing never waits for a time; the
 * times arrive in LOG with renderer_collect_timings (gpu.h, "timers"; on software drivers
 * each timed view waits for itself).  LOG is borrowed: it must stay valid until
 * renderer_collect_timings(r, true) returned or R is destroyed. */
/* Counts the rows of every following view in P (NULL: none, the default): the views are then
 * drawn in bands of rows, each waited for, and the rows done so far are reported to P. */
struct progress;
void renderer_set_progress(struct renderer *r, struct progress *p);

void renderer_set_timing(struct renderer *r, struct gpu_timings *log);
/* Moves the view times the GPU has ready into their logs without waiting, or with WAIT all
 * of them (for a report at the end of a run).  Returns how many are still in flight. */
int renderer_collect_timings(struct renderer *r, bool wait);

/* ---- empty-space skipping -------------------------------------------------------------
 * Beside each extinction texture the renderer keeps a pyramid of macro cells.  Level 0 holds,
 * for each block of RENDER_CELL_VOXELS^3 voxels (RENDER_CELL_VOXELS_STRETCHED^3 on the model's
 * levels, where each cell row reads a run of uneven levels and small cells cost more reads
 * than they leap), the largest extinction (ice plus water; NaN
 * and negative as 0) that a trilinear sample anywhere within half a voxel of the block can
 * read: the block's voxels and one voxel around it.  Each further level holds the largest of
 * 2 x 2 x 2 cells of the one below, up to one cell.  A cell holding 0 or less is empty: the
 * eye pass leaps it (shaders/cells.glsl) and the light build reads no voxel in it, and both
 * come out the same as without the leap.  Last, each empty cell of level 0 gets its distance
 * to the nearest occupied one (RENDER_CELL_DISTANCE_MAX), stored as its negative, so that the
 * eye pass leaps all the empty cells around it at once. */

#define RENDER_CELL_VOXELS 4           /* on a uniform grid */
#define RENDER_CELL_VOXELS_STRETCHED 8 /* on the model's levels (grid3_stretched) */
#define RENDER_CELL_LEVELS 16
/* A clear level-0 cell holds −d, d its Chebyshev distance in cells to the nearest occupied
 * cell, at most this + 1 (shaders/cells_distance.comp): the eye pass leaps the cube of
 * 2 d − 1 cells around it at one read. */
#define RENDER_CELL_DISTANCE_MAX 15

struct render_cells {
    struct gpu_buffer buf;                /* the header, then a float per cell, level 0 first */
    int levels;                           /* 0: none built */
    int dims[RENDER_CELL_LEVELS][4];      /* cells along x, y, z; the level's first index */
    size_t count;                         /* cells of all levels */
    int cell_voxels;                      /* voxels along a level-0 cell's edge */
    int built_layers;                     /* a build in pieces: level 0's layers made */
    int built_rows;                       /* and the rows of cells made of the layers next */
};

struct render_cells_programs {
    struct gpu_program build[4]; /* level 0 of one volume, of two (TEMPORAL, bit 0); on a
                                    stretched grid (STRETCHED, bit 1) */
    struct gpu_program reduce;
    struct gpu_program distance;
};

bool render_cells_programs_init(struct render_cells_programs *p);
void render_cells_programs_finish(struct render_cells_programs *p);
/* The levels' sizes for a volume of N voxels and cells of CELL_VOXELS (no GL; for tests). */
void render_cells_layout(const int n[3], int cell_voxels, struct render_cells *c);
/* Builds C (reusing its buffer when the size matches) from BETA on GRID, with NEXT (may be
 * NULL, else of BETA's size) the larger of the two.  Cells are even in height (cell_voxels
 * times the mean level thickness): on a stretched grid each reads the levels it overlaps.
 * False (logged) when the buffer cannot be made. */
bool render_cells_build(struct render_cells *c, const struct render_cells_programs *p,
                        const struct gpu_texture *beta, const struct gpu_texture *next,
                        const struct grid3 *grid);
/* The same build in pieces: _begin lays C out (and sets its header), each _step makes LAYERS
 * more of level 0's layers of cells (0: all the rest; a multiple of cells_build.comp's
 * local_size_z), and the one after the last the coarser levels, setting *DONE.  The cells are
 * the one-piece build's, bit for bit; anything may run on the GPU between pieces. */
bool render_cells_build_begin(struct render_cells *c, const struct gpu_texture *beta,
                              const struct grid3 *grid);
bool render_cells_build_step(struct render_cells *c, const struct render_cells_programs *p,
                             const struct gpu_texture *beta, const struct gpu_texture *next,
                             const struct grid3 *grid, int layers, bool *done);
/* The same with ROWS of level 0's rows of cells (along y) a call too (a multiple of
 * cells_build.comp's local_size_y; 0: all): a layer's rows, then the next layers. */
bool render_cells_build_piece(struct render_cells *c, const struct render_cells_programs *p,
                              const struct gpu_texture *beta, const struct gpu_texture *next,
                              const struct grid3 *grid, int layers, int rows, bool *done);
void render_cells_finish(struct render_cells *c);
/* A stretched GRID's height table (shaders/zmap.glsl) into TEX (made or remade, RG32F 1-D),
 * and PROG's (NULL: none) uniforms zmap_n and zmap_inv_height as render_zmap_uniforms sets
 * them.  Needs the GL context.  False (logged) when the texture cannot be made. */
bool render_zmap_upload(const struct grid3 *grid, struct gpu_texture *tex,
                        const struct gpu_program *prog);
void render_zmap_uniforms(const struct grid3 *grid, const struct gpu_texture *tex,
                          const struct gpu_program *prog);
/* For each level k of GRID (n[2] of them) into ROW[k], a level-0 cell row of C that holds it:
 * where a level-0 cell of that row is empty, so is every voxel of level k beneath it. */
void render_cells_level_rows(const struct render_cells *c, const struct grid3 *grid, int *row);
/* Binds C's buffer at storage binding BINDING and sets PROG's uniform cell_size (a level-0
 * cell in metres on GRID). */
void render_cells_bind(const struct render_cells *c, const struct gpu_program *prog,
                       unsigned binding, const struct grid3 *grid);
/* Every cell's value, level 0 first (malloc'd, the caller frees; NULL logged).  Waits. */
float *render_cells_read(const struct render_cells *c);
/* C (laid out for BETA on GRID) as the cells of two volumes of that grid whose cells A and B
 * were built alone: the largest of the two, cell by cell, at every level.  The same cells as
 * render_cells_build of the pair (every cell is a maximum over the same voxels), from the
 * cells read back rather than the volumes.  A and B must have C's layout.  False (logged) on
 * failure. */
bool render_cells_max(struct render_cells *c, const struct render_cells *a,
                      const struct render_cells *b, const struct gpu_texture *beta,
                      const struct grid3 *grid);

/* The same cells made on the CPU from the extinction in memory (2 floats a voxel, as
 * ext_volume holds it), a z plane at a time, then uploaded whole (render_cells_upload): the
 * cells the GPU builds from a float texture of those values, bit for bit (not from a
 * half-float one, which rounds them).  HALO is the voxels around each cell that count along x
 * and y (and z on a uniform grid): 1 for the cells the renderer reads (0 only for tests).
 * No GL; the memory is the builder's, freed by render_cells_cpu_finish. */
struct render_cells_cpu {
    struct render_cells layout; /* the levels' sizes (its buffer unused) */
    struct grid3 grid;
    int halo;
    int planes_done; /* z planes of the volume reduced so far */
    float *planes;   /* per z plane, the maxima over each level-0 cell's x and y window */
    float *row;      /* scratch: one row of voxels, then a plane's maxima along x */
    float *cells;    /* every cell's value, level 0 first, once render_cells_cpu_levels ran */
};

/* Lays W out for a volume on GRID (its memory kept when the layout is the same).  False when
 * out of memory (not logged: the caller says what it does instead). */
bool render_cells_cpu_begin(struct render_cells_cpu *w, const struct grid3 *grid, int halo);
/* Z planes FROM .. TO - 1 of BETA (the whole volume's array) reduced along x and y. */
void render_cells_cpu_planes(struct render_cells_cpu *w, const float *beta, int from, int to);
/* Once every plane is reduced: level 0 from the planes, then the coarser levels, into
 * W->cells. */
void render_cells_cpu_levels(struct render_cells_cpu *w);
/* Level 0's clear distances in CELLS, laid out as C (render_cells_cpu_levels does this last):
 * each clear cell's 0 becomes −d, as cells_distance.comp makes them (the same values). */
void render_cells_distance_cpu(const struct render_cells *c, float *cells);
void render_cells_cpu_finish(struct render_cells_cpu *w);
/* The cells of VOL (and of NEXT, of VOL's grid, the larger of the two; may be NULL) in one
 * go: malloc'd, the caller frees, *LAYOUT their sizes; NULL (logged) when out of memory. */
float *render_cells_cpu(const struct ext_volume *vol, const struct ext_volume *next, int halo,
                        struct render_cells *layout);
/* C laid out for BETA on GRID (render_cells_build_begin) and filled with the COUNT VALUES of
 * every cell (render_cells_cpu's): complete.  Needs the GL context.  False (logged) when the
 * buffer cannot be made or COUNT is not C's. */
bool render_cells_upload(struct render_cells *c, const struct gpu_texture *beta,
                         const struct grid3 *grid, const float *values, size_t count);

/* The cells of the last volume set (levels 0 before one): valid until the next
 * renderer_set_volume. */
const struct render_cells *renderer_cells(const struct renderer *r);
/* The cells of the pair of volumes (the larger of step k's and the next one's), made when
 * first asked for after either changed; NULL without a next volume of the same size.  They
 * serve the next volume's light build too: a cell empty in the pair is empty in both. */
const struct render_cells *renderer_pair_cells(struct renderer *r);
/* The same cells in pieces (between frames): when both volumes' own cells are whole (a staged
 * next volume, on the grid of the one shown), in one piece from them (render_cells_max);
 * else LAYERS more of level 0's layers of cells a call (a multiple of cells_build.comp's
 * local_size_z; 0: all the rest), the coarser levels in the call after the last.  *DONE: they are
 * made (now or before, or there is no pair); until then renderer_pair_cells would make them again
 * whole.  Bit-identical to the whole build. False (logged) on a GL failure. */
bool renderer_pair_cells_step(struct renderer *r, int layers, bool *done);
/* Whether renderer_pair_cells would return cells made before (or NULL) without making any. */
bool renderer_pair_cells_ready(const struct renderer *r);

/* The rate of trilinear RG32F 3D texture fetches this device reaches, per second: a
 * fetch-only pass (shaders/fetch_peak.comp) over a volume that stays in the texture cache, the
 * best of three timed runs (GPU timer queries; wall time on a software driver).  What the eye
 * pass's fetches are measured against (anvil bench --gpu).  False (logged) when the program or
 * its textures cannot be made.  Needs the GL context. */
bool render_fetch_peak(double *per_second);

/* ---- opaque geometry -----------------------------------------------------------------
 * Meshes drawn in every view before the ray cast: each view's rays stop at their distance and
 * see their colour as the background (ground, terrain, coastlines, the menu, the wand). */

struct render_vertex {
    float pos[3];    /* world metres (before the mesh's model matrix) */
    float normal[3]; /* lit meshes: for the sun term */
    float color[4];  /* linear RGB albedo (lit) or radiance (emissive); alpha < 0.5 cuts */
    float uv[2];     /* texture coordinate (textured meshes) */
};

struct render_mesh;

/* Uploads a mesh (triangles, or line pairs when LINES).  EMISSIVE meshes show their colour
 * as radiance; the others are Lambertian, lit by the sun through the light map and by the
 * sky.  Returns NULL (logged) on failure.  Needs the GL context. */
struct render_mesh *render_mesh_create(const struct render_vertex *vertices, int vertex_count,
                                       const uint32_t *indices, int index_count, bool lines,
                                       bool emissive);
void render_mesh_destroy(struct render_mesh *m);
/* Column-major model matrix (default identity). */
void render_mesh_set_model(struct render_mesh *m, const float model[16]);
/* An RGBA8 texture multiplied into the colour (text); borrowed, NULL for none. */
void render_mesh_set_texture(struct render_mesh *m, const struct gpu_texture *texture);
void render_mesh_set_visible(struct render_mesh *m, bool visible);

/* Draws M in every following view until removed; the renderer borrows M. */
bool renderer_add_mesh(struct renderer *r, struct render_mesh *m);
void renderer_remove_mesh(struct renderer *r, struct render_mesh *m);
/* Puts NEW where OLD is drawn (the same place in the order), or adds NEW when OLD is not
 * there (NULL: OLD removed only).  False (logged) when there is no room. */
bool renderer_replace_mesh(struct renderer *r, struct render_mesh *old,
                           struct render_mesh *new_mesh);

#endif
