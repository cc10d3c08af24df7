#include "light/light_gpu.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "light/light_volume_gpu.h"
#include "shaders/bindings.h"

/* A build in pieces: what it is for, and how far it got.  Each phase's work is cut along the
 * volume's or the map's planes, every piece the same dispatches the one-piece build makes over
 * part of the range (an invocation reads nothing another of the same dispatch writes, so the
 * cut changes no value). */
enum job_phase { JOB_RATES, JOB_SLICES, JOB_SWEEP, JOB_DIFFUSE, JOB_VOLUME, JOB_COMPRESS,
                 JOB_DONE };

struct light_gpu_job {
    bool active;
    enum job_phase phase;
    int at;                       /* the first plane (level, row) of the phase not done yet */
    int part;                     /* compression: 0, 1 the light's and the diffuse light's
                                     counts, 2, 3 their nodes */
    uint32_t total[2];            /* compression: the nodes each part counted */
    struct light_gpu_source src;
    double sun[3];
    struct light_settings settings, beam; /* beam: without the columns' diffuse pass */
    struct light_key key;
    enum light_gpu_mode mode;
    bool half, volume, skip, stretched;
    int substeps;
    double cpu_ms;                /* CPU time spent in its pieces so far */
};

/* What one piece of a phase covers: levels of the volume (both passes of the lateral rates),
 * slices, planes of the sweep, rows of columns of the diffuse pass and of the compression,
 * iterations of the diffuse light volume's solve. */
#define JOB_RATE_LEVELS 8 /* a multiple of light_lateral.comp's local_size_z */
#define JOB_SLICE_PLANES 2
#define JOB_SWEEP_PLANES 4
#define JOB_DIFFUSE_ROWS 8  /* a multiple of light_diffuse.comp's local_size_y */
#define JOB_COMPRESS_ROWS 8 /* a multiple of light_compress.comp's local_size_y */
#define JOB_VOLUME_ITERATIONS 4 /* of the diffuse light volume's solve */

struct light_gpu {
    struct render_light hook; /* first: the renderer's bind callback gets it back */
    /* Programs by variant, made on first use (an effect that is off is compiled out): the
     * slices by MULTIPLE (bit 0), LATERAL (bit 1) and SKIP (bit 2); the sweep by FORWARD
     * (bit 0), PERIPHERAL (bit 1), PHASE_MIX (bit 2); the diffuse column pass by PHASE_MIX
     * (bit 0) and LATERAL (bit 1). */
    struct gpu_program slices[16];      /* bit 3: STRETCHED */
    struct gpu_texture zmap;            /* the volume's height table (STRETCHED) */
    struct gpu_program build[16];       /* bit 3: HALF */
    struct gpu_program diffuse_pass[8]; /* bit 2: HALF */
    struct gpu_program lateral_pass[2]; /* without and with SKIP */
    struct gpu_texture light;   /* R32F node volume */
    struct gpu_texture diffuse; /* RG32F node volume, M and N; only with multiple scattering
                                   (in compressed mode the build's scratch) */
    struct gpu_program compress[4], scan; /* PASS 1, 2 of the light; of the diffuse light */
    struct gpu_texture slice;   /* build scratch, freed after the build: each slice's tau
                                   and ice share (RG32F), with multiple scattering its lateral
                                   escape rates too (RGBA32F) */
    struct gpu_texture rates;   /* RG32F on the volume's grid: lateral escape rates times the
                                   extinction; they depend on the volume only */
    bool have_rates;            /* rates hold the volume below */
    unsigned rates_beta;        /* its texture, identity and generation */
    uint64_t rates_volume, rates_generation;
    struct gpu_texture adding;  /* RG32F build scratch of the column pass, freed after it */
    bool built_multiple;        /* the columns' diffuse light was built */
    struct light_volume_gpu volume; /* effects.multiple = "volume": the 3-D diffuse light */
    bool built_volume;          /* the last build made it (and not the columns') */
    struct gpu_buffer columns, nodes;
    struct light_grid grid;
    struct light_cache cache;
    enum light_gpu_mode mode;
    bool have_key_mode;
    enum light_gpu_mode built_mode;
    bool half, built_half;      /* the dense map in half floats (light_gpu_set_half) */
    double built_epsilon;
    size_t compressed_bytes;   /* the columns and nodes, the diffuse light's included */
    uint32_t compressed_nodes, diffuse_nodes; /* nodes of the light and of the diffuse light */
    uint32_t diffuse_columns_at, diffuse_nodes_at; /* where its part starts in the buffers */
    struct gpu_timer_queue timers;
    struct gpu_timings *timing; /* where build times go; NULL: untimed */
    bool last_timed;            /* the last build was timed */
    char defines[64];
    struct light_gpu_job job;   /* the build under way (light_gpu_build_begin) */
};

void light_gpu_bind(const struct light_gpu *lg, const struct gpu_program *prog, bool next)
{
    gpu_uniform_mat4(prog, next ? "light_world_to_tex_next" : "light_world_to_tex",
                     lg->grid.world_to_tex);
    gpu_uniform_ivec3(prog, next ? "light_n_next" : "light_n", lg->grid.n);
    if (lg->built_volume) {
        const struct grid3 *vg = &lg->volume.grid;
        float lo[3], size[3];
        for (int a = 0; a < 3; a++) {
            lo[a] = (float)vg->origin[a];
            size[a] = (float)(vg->n[a] * vg->spacing[a]);
        }
        gpu_texture_bind(&lg->volume.field,
                         next ? BIND_LIGHTMAP_TEX_DIFFUSE_NEXT : BIND_LIGHTMAP_TEX_DIFFUSE);
        gpu_uniform_vec3(prog, next ? "volume_box_min_next" : "volume_box_min", lo);
        gpu_uniform_vec3(prog, next ? "volume_box_size_next" : "volume_box_size", size);
    } else if (lg->built_multiple && lg->built_mode == LIGHT_GPU_DENSE) {
        gpu_texture_bind(&lg->diffuse,
                         next ? BIND_LIGHTMAP_TEX_DIFFUSE_NEXT : BIND_LIGHTMAP_TEX_DIFFUSE);
    } else if (lg->built_multiple) {
        gpu_uniform_uint(prog, next ? "light_diffuse_columns_next" : "light_diffuse_columns",
                         lg->diffuse_columns_at);
        gpu_uniform_uint(prog, next ? "light_diffuse_nodes_next" : "light_diffuse_nodes",
                         lg->diffuse_nodes_at);
    }
    if (lg->built_mode == LIGHT_GPU_DENSE) {
        gpu_texture_bind(&lg->light, next ? BIND_LIGHTMAP_TEX_LIGHT_NEXT : BIND_LIGHTMAP_TEX_LIGHT);
    } else {
        gpu_buffer_bind(&lg->columns,
                        next ? BIND_LIGHTMAP_BUF_COLUMNS_NEXT : BIND_LIGHTMAP_BUF_COLUMNS);
        gpu_buffer_bind(&lg->nodes, next ? BIND_LIGHTMAP_BUF_NODES_NEXT : BIND_LIGHTMAP_BUF_NODES);
    }
}

static void bind(const struct render_light *light, const struct gpu_program *prog)
{
    light_gpu_bind((const struct light_gpu *)light, prog, false);
}

int light_gpu_variant(const struct light_gpu *lg)
{
    if (!lg->have_key_mode)
        return 0;
    return lg->built_mode == LIGHT_GPU_DENSE ? 1 : 2;
}

static const struct gpu_program *build_program(struct light_gpu *lg, int v)
{
    if (lg->build[v].id)
        return &lg->build[v];
    char defines[128];
    snprintf(defines, sizeof(defines),
             "#define FORWARD %d\n#define PERIPHERAL %d\n#define PHASE_MIX %d\n#define HALF %d\n",
             v & 1, (v >> 1) & 1, (v >> 2) & 1, (v >> 3) & 1);
    if (!gpu_program_init(&lg->build[v], "light_build.comp", defines))
        return NULL;
    return &lg->build[v];
}

static const struct gpu_program *slices_program(struct light_gpu *lg, bool multiple,
                                                bool lateral, bool skip, bool stretched)
{
    int v = (multiple ? 1 : 0) | (multiple && lateral ? 2 : 0) | (skip ? 4 : 0) |
            (stretched ? 8 : 0);
    if (lg->slices[v].id)
        return &lg->slices[v];
    char defines[128];
    snprintf(defines, sizeof(defines),
             "#define MULTIPLE %d\n#define LATERAL %d\n#define SKIP %d\n#define STRETCHED %d\n",
             v & 1, (v >> 1) & 1, (v >> 2) & 1, v >> 3);
    if (!gpu_program_init(&lg->slices[v], "light_slices.comp", defines))
        return NULL;
    return &lg->slices[v];
}

/* The diffuse column pass: its only variant is the ice/water mix (the loss shares the forward
 * terms leave come as uniforms). */
static const struct gpu_program *diffuse_program(struct light_gpu *lg, bool mix, bool lateral,
                                                bool half)
{
    int v = (mix ? 1 : 0) | (lateral ? 2 : 0) | (half ? 4 : 0);
    if (lg->diffuse_pass[v].id)
        return &lg->diffuse_pass[v];
    char defines[64];
    snprintf(defines, sizeof(defines), "#define PHASE_MIX %d\n#define LATERAL %d\n#define HALF %d\n",
             v & 1, (v >> 1) & 1, v >> 2);
    if (!gpu_program_init(&lg->diffuse_pass[v], "light_diffuse.comp", defines))
        return NULL;
    return &lg->diffuse_pass[v];
}

/* Voxels of a row one invocation of light_lateral.comp looks after (its SEGMENT). */
#define LATERAL_SEGMENT 32

/* Whether the lateral escape rates in LG hold SRC's volume (a new sun, the same volume: the
 * rates stand). */
static bool rates_fresh(const struct light_gpu *lg, const struct light_gpu_source *src)
{
    return lg->rates.id && memcmp(lg->rates.size, src->grid->n, 3 * sizeof(int)) == 0 &&
           lg->have_rates && lg->rates_beta == src->beta->id &&
           lg->rates_volume == src->volume_id && lg->rates_generation == src->generation;
}

/* Readies the rates texture and its program for a new set of rates. */
static bool rates_setup(struct light_gpu *lg, const struct light_gpu_source *src)
{
    const int *n = src->grid->n;
    bool same_size = lg->rates.id && memcmp(lg->rates.size, n, 3 * sizeof(int)) == 0;
    lg->have_rates = false;
    if (!same_size) {
        gpu_texture_finish(&lg->rates);
        if (!gpu_texture_init(&lg->rates, 3, n, GPU_RG32F, NULL))
            return false;
    }
    bool skip = src->cells && src->cells->levels > 0;
    struct gpu_program *p = &lg->lateral_pass[skip ? 1 : 0];
    if (!p->id && !gpu_program_init(p, "light_lateral.comp", skip ? "#define SKIP 1\n" : ""))
        return false;
    gpu_texture_clear(&lg->rates);
    return true;
}

_Static_assert(GRID3_LEVELS_MAX == 4 * 64, "light_lateral.comp's level_rows[64] holds every level");

/* The lateral escape rates of the volume (light_lateral.comp) along AXIS (0: x, 1: y) on
 * levels FROM .. FROM + COUNT - 1: one invocation per stretch of a row (each walks the runs that
 * start in it).  Every binding is made again: a frame may have come between two pieces. */
static void rates_levels(struct light_gpu *lg, const struct light_gpu_source *src, int axis,
                         int from, int count)
{
    const int *n = src->grid->n;
    bool skip = src->cells && src->cells->levels > 0;
    const struct gpu_program *p = &lg->lateral_pass[skip ? 1 : 0];
    gpu_uniform_ivec3(p, "vol_n", n);
    gpu_uniform_float(p, "clear_beta", LIGHT_CLEAR_BETA);
    gpu_texture_bind(src->beta, BIND_LATERAL_TEX_BETA);
    gpu_image_bind_rw(&lg->rates, BIND_LATERAL_IMG_RATES);
    if (skip) {
        gpu_buffer_bind(&src->cells->buf, BIND_LATERAL_BUF_CELLS);
        int rows[GRID3_LEVELS_MAX] = {0};
        render_cells_level_rows(src->cells, src->grid, rows);
        gpu_uniform_ivec4_array(p, "level_rows", GRID3_LEVELS_MAX / 4, rows);
    }
    gpu_uniform_int(p, "axis", axis);
    gpu_uniform_int(p, "base_z", from);
    gpu_uniform_float(p, "spacing", (float)src->grid->spacing[axis]);
    /* rows x stretches of LATERAL_SEGMENT voxels x levels */
    gpu_dispatch(p, n[1 - axis], (n[axis] + LATERAL_SEGMENT - 1) / LATERAL_SEGMENT, count);
}

static void rates_built(struct light_gpu *lg, const struct light_gpu_source *src)
{
    lg->have_rates = true;
    lg->rates_beta = src->beta->id;
    lg->rates_volume = src->volume_id;
    lg->rates_generation = src->generation;
}

/* The sweep's variant for settings S: forward scattering, the peripheral ring, and the
 * ice/water mix (compiled out when both phases' cumulative phases are equal: the mix is then
 * exact). */
static int build_variant(const struct light_settings *s)
{
    bool mix = !light_settings_phases_equal(s);
    return (s->forward ? 1 : 0) | (s->forward && s->peripheral ? 2 : 0) |
           (s->forward && mix ? 4 : 0);
}

struct light_gpu *light_gpu_create(void)
{
    struct light_gpu *lg = calloc(1, sizeof(*lg));
    if (!lg)
        return NULL;
    if (!build_program(lg, 7) || !slices_program(lg, false, false, true, false)) {
        light_gpu_destroy(lg);
        return NULL;
    }
    light_cache_init(&lg->cache);
    gpu_timer_queue_init(&lg->timers, GPU_TIMER_AUTO);
    lg->hook.bind = bind;
    lg->hook.defines = lg->defines;
    return lg;
}

void light_gpu_destroy(struct light_gpu *lg)
{
    if (!lg)
        return;
    for (int v = 0; v < 16; v++)
        gpu_program_finish(&lg->build[v]);
    for (int v = 0; v < 8; v++) {
        gpu_program_finish(&lg->slices[v]);
        gpu_program_finish(&lg->slices[8 + v]);
        gpu_program_finish(&lg->diffuse_pass[v]);
    }
    gpu_texture_finish(&lg->zmap);
    gpu_texture_finish(&lg->light);
    gpu_texture_finish(&lg->diffuse);
    for (int v = 0; v < 4; v++)
        gpu_program_finish(&lg->compress[v]);
    gpu_program_finish(&lg->scan);
    gpu_texture_finish(&lg->slice);
    gpu_texture_finish(&lg->rates);
    for (int v = 0; v < 2; v++)
        gpu_program_finish(&lg->lateral_pass[v]);
    gpu_texture_finish(&lg->adding);
    gpu_buffer_finish(&lg->columns);
    gpu_buffer_finish(&lg->nodes);
    light_volume_gpu_finish(&lg->volume);
    gpu_timer_queue_finish(&lg->timers);
    free(lg);
}

/* (Re)allocates TEX as a 3D texture of the grid's size and FORMAT unless it already is. */
static bool node_texture(struct gpu_texture *tex, const int n[3], enum gpu_format format)
{
    if (tex->id && memcmp(tex->size, n, 3 * sizeof(int)) == 0 && tex->format == format)
        return true;
    gpu_texture_finish(tex);
    return gpu_texture_init(tex, 3, n, format, NULL);
}

/* The two-stream pass down the columns of rows FROM .. FROM + COUNT - 1 (light_diffuse.comp),
 * after the beam. */
static bool build_diffuse(struct light_gpu *lg, const double sun[3],
                          const struct light_settings *s, bool half, int from, int count)
{
    const struct light_grid *g = &lg->grid;
    if (!node_texture(&lg->diffuse, g->n, half ? GPU_RG16F : GPU_RG32F) ||
        !node_texture(&lg->adding, g->n, GPU_RG32F))
        return false;
    const struct gpu_program *p =
        diffuse_program(lg, !light_settings_phases_equal(s), s->lateral, half);
    if (!p)
        return false;
    struct light_diffuse_terms t;
    light_diffuse_terms_init(s, sun, &t);
    gpu_uniform_ivec3(p, "grid_n", g->n);
    gpu_uniform_vec2(p, "loss", t.loss);
    gpu_uniform_vec2(p, "back", t.back);
    gpu_uniform_vec2(p, "gamma", t.gamma);
    gpu_uniform_float(p, "mu0", t.mu0);
    gpu_image_bind(&lg->light, BIND_DIFFUSE_IMG_LIGHT, false);
    gpu_image_bind(&lg->slice, BIND_DIFFUSE_IMG_SLICE, false);
    gpu_image_bind_rw(&lg->adding, BIND_DIFFUSE_IMG_ADDING);
    gpu_image_bind(&lg->diffuse, BIND_DIFFUSE_IMG_DIFFUSE, true);
    gpu_uniform_int(p, "base_y", from);
    gpu_dispatch(p, g->n[0], count, 1);
    return true;
}

/* The dense build's textures and programs for job J (its beam settings), and its first phase:
 * the lateral rates when they do not stand, else the slices. */
static bool job_setup(struct light_gpu *lg, struct light_gpu_job *j)
{
    const struct light_grid *g = &lg->grid;
    const struct light_settings *s = &j->beam;
    const struct light_gpu_source *src = &j->src;
    if (!node_texture(&lg->light, g->n, j->half ? GPU_R16F : GPU_R32F) ||
        !node_texture(&lg->slice, g->n, s->multiple ? GPU_RGBA32F : GPU_RG32F))
        return false;
    if (!s->multiple)
        gpu_texture_finish(&lg->diffuse);
    j->phase = JOB_SLICES;
    if (s->multiple && s->lateral) {
        if (!rates_fresh(lg, src)) {
            if (!rates_setup(lg, src))
                return false;
            j->phase = JOB_RATES;
        }
    } else {
        gpu_texture_finish(&lg->rates);
        lg->have_rates = false;
    }
    j->at = 0;
    j->skip = src->cells && src->cells->levels > 0;
    j->stretched = grid3_stretched(src->grid);
    const struct gpu_program *sp =
        slices_program(lg, s->multiple, s->lateral, j->skip, j->stretched);
    const struct gpu_program *p = build_program(lg, build_variant(s) | (j->half ? 8 : 0));
    if (!sp || !p)
        return false;
    if (j->stretched && !render_zmap_upload(src->grid, &lg->zmap, sp))
        return false;
    j->substeps = s->substeps > 0 ? s->substeps : light_auto_substeps(g, src->grid);
    return true;
}

/* The extinction of slices FROM .. FROM + COUNT - 1 (slice k - 1 .. k is slice k - 1): the
 * costly part, all in parallel. */
static void slices_range(struct light_gpu *lg, const struct light_gpu_job *j, int from, int count)
{
    const struct light_grid *g = &lg->grid;
    const struct light_settings *s = &j->beam;
    const struct light_gpu_source *src = &j->src;
    const struct gpu_program *sp =
        slices_program(lg, s->multiple, s->lateral, j->skip, j->stretched);
    float vol_origin[3], inv_spacing[3];
    for (int a = 0; a < 3; a++) {
        vol_origin[a] = (float)src->grid->origin[a];
        inv_spacing[a] = (float)(1.0 / src->grid->spacing[a]);
    }
    gpu_uniform_ivec3(sp, "vol_n", src->grid->n);
    gpu_uniform_vec3(sp, "vol_origin", vol_origin);
    gpu_uniform_vec3(sp, "vol_inv_spacing", inv_spacing);
    if (j->stretched)
        gpu_texture_bind(&lg->zmap, BIND_SLICES_TEX_ZMAP);
    gpu_uniform_ivec3(sp, "grid_n", g->n);
    gpu_uniform_vec3(sp, "g_origin", g->origin);
    gpu_uniform_vec3(sp, "g_du", g->du);
    gpu_uniform_vec3(sp, "g_dv", g->dv);
    gpu_uniform_vec3(sp, "g_dw", g->dw);
    gpu_uniform_int(sp, "substeps", j->substeps);
    gpu_uniform_float(sp, "dsub", (float)(g->step[2] / j->substeps));
    gpu_uniform_int(sp, "base_z", from);
    gpu_texture_bind(src->beta, BIND_SLICES_TEX_BETA);
    if (s->multiple && s->lateral)
        gpu_texture_bind(&lg->rates, BIND_SLICES_TEX_RATES);
    if (j->skip)
        gpu_buffer_bind(&src->cells->buf, BIND_SLICES_BUF_CELLS);
    gpu_image_bind(&lg->slice, BIND_SLICES_IMG_SLICE, true);
    gpu_dispatch(sp, g->n[0], g->n[1], count);
}

/* Whether the sweep may stop between planes without changing a value: with the peripheral ring
 * it does anyway (a plane per dispatch); else a piece starts from the plane before as stored,
 * which is the value carried only when the map holds floats. */
static bool sweep_cuts(const struct light_gpu_job *j)
{
    return (j->beam.forward && j->beam.peripheral) || !j->half;
}

/* The sweep over planes FROM .. FROM + COUNT - 1: a plane per dispatch with the peripheral ring
 * (it reads the plane before's neighbours), else every column through them in one. */
static void sweep_range(struct light_gpu *lg, const struct light_gpu_job *j, int from, int count)
{
    const struct light_grid *g = &lg->grid;
    const struct light_settings *s = &j->beam;
    const struct gpu_program *p = build_program(lg, build_variant(s) | (j->half ? 8 : 0));
    double r = light_peripheral_offset(s->forward_angle_deg, g->step[2]);
    float per[2];
    light_grid_peripheral_taps(g, r, per);
    float cp[4] = {(float)s->cp.water_ctr, (float)s->cp.ice_ctr, (float)s->cp.water_per,
                   (float)s->cp.ice_per};
    gpu_uniform_ivec3(p, "grid_n", g->n);
    gpu_uniform_vec4(p, "cp", cp);
    gpu_uniform_vec2(p, "per_offset", per);
    gpu_texture_bind(&lg->slice, BIND_BUILD_TEX_SLICE);
    gpu_image_bind_rw(&lg->light, BIND_BUILD_IMG_LIGHT);
    int per_plane = s->forward && s->peripheral ? 1 : count;
    gpu_uniform_int(p, "planes", per_plane);
    for (int k = from; k < from + count; k += per_plane) {
        gpu_uniform_int(p, "plane", k);
        gpu_dispatch(p, g->n[0], g->n[1], 1);
    }
}

static bool compress_piece(struct light_gpu *lg, struct light_gpu_job *j, bool whole);

/* Advances job J by one piece of its phase (WHOLE: the phase's rest at once, as the one-piece
 * build does), moving to the next phase when its range is done. */
static bool job_piece(struct light_gpu *lg, struct light_gpu_job *j, bool whole)
{
    const int *gn = lg->grid.n;
    switch (j->phase) {
    case JOB_RATES: {
        int levels = j->src.grid->n[2];
        int axis = j->at / levels, from = j->at % levels;
        int count = whole ? levels - from : JOB_RATE_LEVELS;
        if (count > levels - from)
            count = levels - from;
        rates_levels(lg, &j->src, axis, from, count);
        j->at += count;
        if (whole && axis == 0) {
            rates_levels(lg, &j->src, 1, 0, levels);
            j->at = 2 * levels;
        }
        if (j->at >= 2 * levels) {
            rates_built(lg, &j->src);
            j->phase = JOB_SLICES;
            j->at = 0;
        }
        return true;
    }
    case JOB_SLICES: {
        int total = gn[2] - 1;
        int count = whole ? total - j->at : JOB_SLICE_PLANES;
        if (count > total - j->at)
            count = total - j->at;
        if (count > 0)
            slices_range(lg, j, j->at, count);
        j->at += count;
        if (j->at >= total) {
            j->phase = JOB_SWEEP;
            j->at = 0;
        }
        return true;
    }
    case JOB_SWEEP: {
        int total = gn[2];
        int count = whole || !sweep_cuts(j) ? total - j->at : JOB_SWEEP_PLANES;
        if (count > total - j->at)
            count = total - j->at;
        sweep_range(lg, j, j->at, count);
        j->at += count;
        if (j->at >= total) {
            j->phase = JOB_DIFFUSE;
            j->at = 0;
        }
        return true;
    }
    case JOB_DIFFUSE: {
        int total = gn[1];
        int count = whole || !j->beam.multiple ? total - j->at : JOB_DIFFUSE_ROWS;
        if (count > total - j->at)
            count = total - j->at;
        bool ok = !j->beam.multiple ||
                  build_diffuse(lg, j->sun, &j->beam, j->half, j->at, count);
        j->at += count;
        if (ok && j->at < total)
            return true;
        /* The scratch served this build only: give its memory back. */
        gpu_texture_finish(&lg->slice);
        gpu_texture_finish(&lg->adding);
        j->phase = JOB_VOLUME;
        j->at = 0;
        return ok;
    }
    case JOB_VOLUME: {
        /* The source and the system (a piece), then the solve's iterations. */
        bool ok = true, done = true;
        if (j->volume && j->at == 0) {
            ok = light_volume_gpu_build_begin(&lg->volume, j->src.beta, j->src.grid, &lg->light,
                                              &lg->grid, &j->settings, NULL);
            j->at = 1;
            if (ok && !whole)
                return true;
        }
        if (j->volume && ok)
            ok = light_volume_gpu_build_step(&lg->volume, whole ? 0 : JOB_VOLUME_ITERATIONS,
                                             &done);
        else if (!j->volume)
            gpu_texture_finish(&lg->volume.field);
        if (ok && !done)
            return true;
        j->phase = JOB_COMPRESS;
        j->at = 0;
        return ok;
    }
    case JOB_COMPRESS: {
        if (j->mode == LIGHT_GPU_COMPRESSED)
            return compress_piece(lg, j, whole);
        gpu_buffer_finish(&lg->columns);
        gpu_buffer_finish(&lg->nodes);
        lg->compressed_bytes = 0;
        j->phase = JOB_DONE;
        return true;
    }
    case JOB_DONE:
        break;
    }
    return true;
}

/* Reads the light volume back, and the diffuse one too when WITH_DIFFUSE and it exists. */
static bool read_back(const struct light_gpu *lg, struct light_map *map, bool with_diffuse)
{
    memset(map, 0, sizeof(*map));
    if (!lg->light.id) {
        log_error("light map: no dense volume on the GPU (none built yet, or compressed mode)");
        return false;
    }
    map->grid = lg->grid;
    size_t count = (size_t)lg->grid.n[0] * lg->grid.n[1] * lg->grid.n[2];
    map->light = malloc(count * sizeof(float));
    if (!map->light) {
        log_error("light map: out of memory reading %zu nodes back", count);
        return false;
    }
    gpu_texture_read(&lg->light, map->light, count * sizeof(float));
    if (with_diffuse && lg->diffuse.id) {
        map->diffuse = malloc(2 * count * sizeof(float));
        if (!map->diffuse) {
            log_error("light map: out of memory reading %zu nodes back", count);
            light_map_finish(map);
            return false;
        }
        gpu_texture_read(&lg->diffuse, map->diffuse, 2 * count * sizeof(float));
    }
    return true;
}

/* The 2 x 2 x 2 nodes around TEX of the texture T (COMPONENTS floats a node), trilinear as
 * light_map_sample is, into OUT. */
static void sample_block(const struct gpu_texture *t, const int n[3], const float tex[3],
                         int components, float *out)
{
    int i[3];
    float w[3], v[8 * 2];
    for (int a = 0; a < 3; a++)
        i[a] = light_tex_node(tex[a], n[a], &w[a]);
    gpu_texture_read_region(t, i, (const int[3]){2, 2, 2}, v,
                            sizeof(float) * 8 * (size_t)components);
    for (int c = 0; c < components; c++) {
        float e[2][2];
        for (int dk = 0; dk < 2; dk++)
            for (int dj = 0; dj < 2; dj++) {
                float a0 = v[components * (0 + 2 * (dj + 2 * dk)) + c];
                float a1 = v[components * (1 + 2 * (dj + 2 * dk)) + c];
                e[dk][dj] = a0 + w[0] * (a1 - a0);
            }
        float c0 = e[0][0] + w[1] * (e[0][1] - e[0][0]);
        float c1 = e[1][0] + w[1] * (e[1][1] - e[1][0]);
        out[c] = c0 + w[2] * (c1 - c0);
    }
}

bool light_gpu_sample(const struct light_gpu *lg, const double p[3], float *beam,
                      float diffuse[2], bool *have_diffuse)
{
    *have_diffuse = false;
    diffuse[0] = diffuse[1] = 0.0f;
    if (!lg->cache.valid)
        return false;
    double td[3];
    light_grid_world_to_tex(&lg->grid, p, td);
    const float tex[3] = {(float)td[0], (float)td[1], (float)td[2]};
    if (lg->built_mode == LIGHT_GPU_COMPRESSED && lg->compressed_bytes) {
        /* The compressed map is small by design: read back whole, evaluated as the eye pass
         * does (the light's columns, and the diffuse light's). */
        struct light_compressed c;
        if (!light_gpu_read_compressed(lg, &c))
            return false;
        *beam = light_compressed_sample(&c, tex);
        if (c.diffuse_columns) {
            light_compressed_sample_diffuse(&c, tex, diffuse);
            *have_diffuse = true;
        }
        light_compressed_finish(&c);
        return true;
    }
    if (lg->light.id)
        sample_block(&lg->light, lg->grid.n, tex, 1, beam);
    else
        return false;
    if (lg->built_multiple && lg->diffuse.id) {
        sample_block(&lg->diffuse, lg->grid.n, tex, 2, diffuse);
        *have_diffuse = true;
    }
    return true;
}

bool light_gpu_read(const struct light_gpu *lg, struct light_map *map)
{
    return read_back(lg, map, true);
}

bool light_gpu_read_rates(const struct light_gpu *lg, float **out)
{
    *out = NULL;
    if (!lg->have_rates || !lg->rates.id) {
        log_error("light map: no lateral escape rates on the GPU");
        return false;
    }
    size_t n = (size_t)lg->rates.size[0] * lg->rates.size[1] * lg->rates.size[2] * 2;
    if (!(*out = malloc(n * sizeof(float)))) {
        log_error("light map: out of memory for the lateral escape rates");
        return false;
    }
    gpu_texture_read(&lg->rates, *out, n * sizeof(float));
    return true;
}

/* Counts the nodes of part CH's (0 the light, 1 the diffuse light) columns on rows FROM ..
 * FROM + COUNT - 1 of the dense map into the columns buffer from word BASE on
 * (light_compress.comp, PASS 1). */
static void count_rows(struct light_gpu *lg, int ch, uint32_t base, double epsilon, int from,
                       int count)
{
    const int *n = lg->grid.n;
    const struct gpu_program *p = &lg->compress[2 * ch];
    gpu_image_bind(ch ? &lg->diffuse : &lg->light, BIND_COMPRESS_IMG_VALUES, false);
    gpu_buffer_bind(&lg->columns, BIND_COMPRESS_BUF_COLUMNS);
    gpu_uniform_ivec3(p, "grid_n", n);
    gpu_uniform_double(p, "epsilon", epsilon);
    gpu_uniform_uint(p, "base", base);
    gpu_uniform_int(p, "base_y", from);
    gpu_dispatch(p, n[0], count, 1);
}

/* The part's counts from word BASE on turned into first indices (light_scan.comp). */
static void scan_part(struct light_gpu *lg, uint32_t base)
{
    const int *n = lg->grid.n;
    gpu_buffer_bind(&lg->columns, BIND_SCAN_BUF_COLUMNS);
    gpu_uniform_uint(&lg->scan, "column_count", (unsigned)((size_t)n[0] * n[1]));
    gpu_uniform_uint(&lg->scan, "base", base);
    gpu_dispatch(&lg->scan, 1024, 1, 1);
}

/* Writes part CH's nodes of the columns on rows FROM .. FROM + COUNT - 1, from float NODE_BASE
 * of the nodes buffer on (PASS 2). */
static void write_rows(struct light_gpu *lg, int ch, uint32_t base, uint32_t node_base,
                       double epsilon, int from, int count)
{
    const int *n = lg->grid.n;
    const struct gpu_program *p = &lg->compress[2 * ch + 1];
    gpu_image_bind(ch ? &lg->diffuse : &lg->light, BIND_COMPRESS_IMG_VALUES, false);
    gpu_buffer_bind(&lg->columns, BIND_COMPRESS_BUF_COLUMNS);
    gpu_buffer_bind(&lg->nodes, BIND_COMPRESS_BUF_NODES);
    gpu_uniform_ivec3(p, "grid_n", n);
    gpu_uniform_double(p, "epsilon", epsilon);
    gpu_uniform_uint(p, "base", base);
    gpu_uniform_uint(p, "node_base", node_base);
    gpu_uniform_int(p, "base_y", from);
    gpu_dispatch(p, n[0], count, 1);
}

/* The compression's programs and columns buffer, before its first piece. */
static bool compress_setup(struct light_gpu *lg, bool diffuse)
{
    const int *n = lg->grid.n;
    size_t ncol = (size_t)n[0] * n[1];
    if ((double)ncol * (n[2] + 1) * (diffuse ? 3 : 1) >= 4294967295.0) {
        log_error("light map: %dx%dx%d nodes are too many to compress (at most 2^32 nodes)",
                  n[0], n[1], n[2]);
        return false;
    }
    for (int v = 0; v < (diffuse ? 4 : 2); v++) {
        char defines[64];
        snprintf(defines, sizeof(defines), "#define PASS %d\n#define CHANNELS %d\n", 1 + v % 2,
                 1 + v / 2);
        if (!lg->compress[v].id && !gpu_program_init(&lg->compress[v], "light_compress.comp",
                                                     defines))
            return false;
    }
    if (!lg->scan.id && !gpu_program_init(&lg->scan, "light_scan.comp", NULL))
        return false;
    gpu_buffer_finish(&lg->columns);
    gpu_buffer_finish(&lg->nodes);
    /* The light's columns and their total, then the diffuse light's. */
    uint32_t dbase = (uint32_t)(2 * ncol + 1);
    return gpu_buffer_init(&lg->columns, (diffuse ? 2 : 1) * (size_t)dbase * sizeof(uint32_t),
                           NULL);
}

/* One piece of the dense map's compression on the GPU (WHOLE: a whole sweep), as the reference
 * compressor does: the light's (depth, light) nodes, and with multiple scattering the diffuse
 * light's (depth, M, N), each part's columns and nodes after the light's in the same two
 * buffers.  Every column's nodes are counted, a rows' piece at a time, the counts turned into
 * first indices, then the nodes written; the node buffer is made for the totals the GPU found,
 * the one thing read back (it waits for the build).  The dense volumes are freed after. */
static bool compress_piece(struct light_gpu *lg, struct light_gpu_job *j, bool whole)
{
    const int *n = lg->grid.n;
    size_t ncol = (size_t)n[0] * n[1];
    bool diffuse = lg->diffuse.id != 0;
    uint32_t dbase = (uint32_t)(2 * ncol + 1);
    double epsilon = j->settings.epsilon;
    if (j->part == 0 && j->at == 0 && !compress_setup(lg, diffuse))
        return false;
    int ch = j->part % 2;
    uint32_t base = ch ? dbase : 0;
    int count = whole ? n[1] - j->at : JOB_COMPRESS_ROWS;
    if (count > n[1] - j->at)
        count = n[1] - j->at;
    if (j->part < 2)
        count_rows(lg, ch, base, epsilon, j->at, count);
    else
        write_rows(lg, ch, base, ch ? 2 * j->total[0] : 0, epsilon, j->at, count);
    j->at += count;
    if (j->at < n[1])
        return true;
    j->at = 0;
    if (j->part < 2)
        scan_part(lg, base);
    j->part += diffuse ? 1 : 2;
    if (j->part == 2) {
        j->total[0] = j->total[1] = 0;
        gpu_buffer_read(&lg->columns, 2 * ncol * sizeof(uint32_t), sizeof(uint32_t),
                        &j->total[0]);
        if (diffuse)
            gpu_buffer_read(&lg->columns, (dbase + 2 * ncol) * sizeof(uint32_t),
                            sizeof(uint32_t), &j->total[1]);
        size_t floats = 2 * (size_t)j->total[0] + 3 * (size_t)j->total[1];
        return gpu_buffer_init(&lg->nodes, (floats ? floats : 1) * sizeof(float), NULL);
    }
    if (j->part < 4)
        return true;
    size_t floats = 2 * (size_t)j->total[0] + 3 * (size_t)j->total[1];
    lg->compressed_nodes = j->total[0];
    lg->diffuse_nodes = j->total[1];
    lg->diffuse_columns_at = dbase;
    lg->diffuse_nodes_at = 2 * j->total[0];
    lg->compressed_bytes = (diffuse ? 2 : 1) * ncol * 2 * sizeof(uint32_t) + floats * sizeof(float);
    /* The dense volumes were only the build's scratch: give their memory back. */
    gpu_texture_finish(&lg->light);
    gpu_texture_finish(&lg->diffuse);
    j->phase = JOB_DONE;
    return true;
}

/* The key of a build of SETTINGS for SRC and SUN, and whether LG's map is not that. */
static bool stale_for(struct light_gpu *lg, const struct light_gpu_source *src,
                      const double sun[3], const struct light_settings *settings,
                      enum light_gpu_mode mode, struct light_key *key)
{
    light_key_init(key, src->grid, sun, src->volume_id, src->generation, settings);
    return light_cache_stale(&lg->cache, key) || !lg->have_key_mode || lg->built_mode != mode ||
           lg->built_half != lg->half ||
           (mode == LIGHT_GPU_COMPRESSED && lg->built_epsilon != settings->epsilon);
}

/* Starts the job for KEY: the grid, its settings, the textures.  The map held until now is
 * being overwritten from here on: the cache forgets it. */
static bool job_start(struct light_gpu *lg, const struct light_gpu_source *src,
                      const double sun[3], const struct light_settings *settings,
                      enum light_gpu_mode mode, const struct light_key *key)
{
    struct light_gpu_job *j = &lg->job;
    memset(j, 0, sizeof(*j));
    light_cache_invalidate(&lg->cache);
    if (!light_grid_init(&lg->grid, sun, src->grid, settings->resolution, settings->grid))
        return false;
    j->src = *src;
    memcpy(j->sun, sun, sizeof(j->sun));
    j->settings = *settings;
    j->key = *key;
    j->mode = mode;
    /* Half floats are a storage of the dense map: a compressed build stays in floats. */
    j->half = lg->half && mode == LIGHT_GPU_DENSE;
    /* With the diffuse light volume the columns' diffuse pass is not needed: the beam alone,
     * then the volume from it (before compression frees the dense beam). */
    j->volume = settings->multiple && settings->volume;
    j->beam = *settings;
    if (j->volume)
        j->beam.multiple = false;
    if (!job_setup(lg, j))
        return false;
    j->active = true;
    return true;
}

/* The finished job's map becomes LG's: its key, variant and defines. */
static void job_finished(struct light_gpu *lg, double cpu_ms)
{
    struct light_gpu_job *j = &lg->job;
    j->active = false;
    /* The cache keeps the CPU time of the build; the GPU's arrives in the timing log. */
    light_cache_built(&lg->cache, &j->key, cpu_ms);
    lg->have_key_mode = true;
    lg->built_mode = j->mode;
    lg->built_epsilon = j->settings.epsilon;
    lg->built_multiple = j->beam.multiple;
    lg->built_volume = j->volume;
    lg->built_half = lg->half;
    snprintf(lg->defines, sizeof(lg->defines), "#define LIGHTMAP %d\n#define MULTIPLE %d\n",
             j->mode == LIGHT_GPU_DENSE ? 1 : 2, j->volume ? 2 : j->settings.multiple ? 1 : 0);
}

static void job_failed(struct light_gpu *lg)
{
    lg->job.active = false;
    light_cache_invalidate(&lg->cache);
}

bool light_gpu_update(struct light_gpu *lg, const struct light_gpu_source *src,
                      const double sun[3], const struct light_settings *settings,
                      enum light_gpu_mode mode, bool *built)
{
    if (built)
        *built = false;
    struct light_key key;
    bool stale = stale_for(lg, src, sun, settings, mode, &key);
    if (!stale)
        return true;
    double cpu_start = time_now_ms();
    struct gpu_timings *log = lg->timing;
    if (log)
        gpu_timer_queue_begin(&lg->timers);
    /* One piece: every phase whole (a build in pieces under way is dropped). */
    bool ok = job_start(lg, src, sun, settings, mode, &key);
    while (ok && lg->job.phase != JOB_DONE)
        ok = job_piece(lg, &lg->job, true);
    unsigned number = log ? gpu_timer_queue_end(&lg->timers, log) : 0;
    lg->last_timed = number != 0;
    if (!ok) {
        job_failed(lg);
        return false;
    }
    job_finished(lg, time_now_ms() - cpu_start);
    if (built)
        *built = true;
    return true;
}

bool light_gpu_build_begin(struct light_gpu *lg, const struct light_gpu_source *src,
                           const double sun[3], const struct light_settings *settings,
                           enum light_gpu_mode mode, bool *needed)
{
    struct light_key key;
    bool stale = stale_for(lg, src, sun, settings, mode, &key);
    struct light_gpu_job *j = &lg->job;
    if (j->active && light_key_equal(&j->key, &key) && j->mode == mode &&
        j->half == (lg->half && mode == LIGHT_GPU_DENSE)) {
        j->src = *src; /* the same volume; its textures may have moved */
        *needed = true;
        return true;
    }
    *needed = stale;
    if (!stale) {
        j->active = false;
        return true;
    }
    if (!job_start(lg, src, sun, settings, mode, &key)) {
        job_failed(lg);
        return false;
    }
    return true;
}

bool light_gpu_build_step(struct light_gpu *lg, double budget_ms, bool *done)
{
    struct light_gpu_job *j = &lg->job;
    *done = !j->active;
    if (!j->active)
        return true;
    /* Pieces while the next, as long as the last, still fits: each waited for, so that its
     * cost is known (on a CPU rasteriser a dispatch runs when flushed). */
    double t0 = time_now_ms();
    for (;;) {
        double t = time_now_ms();
        bool ok = job_piece(lg, j, false);
        gpu_finish();
        double now = time_now_ms();
        j->cpu_ms += now - t;
        if (!ok) {
            job_failed(lg);
            return false;
        }
        if (j->phase == JOB_DONE)
            break;
        if (now - t0 + (now - t) > budget_ms)
            return true;
    }
    /* Pieces spread over frames are not timed on the GPU (a query spans one stretch). */
    lg->last_timed = false;
    job_finished(lg, j->cpu_ms);
    *done = true;
    return true;
}

/* The job's phases in light_build_phase's order, after its start. */
_Static_assert(JOB_RATES + 1 == LIGHT_BUILD_RATES && JOB_SLICES + 1 == LIGHT_BUILD_SLICES &&
                   JOB_SWEEP + 1 == LIGHT_BUILD_SWEEP && JOB_DIFFUSE + 1 == LIGHT_BUILD_DIFFUSE &&
                   JOB_VOLUME + 1 == LIGHT_BUILD_VOLUME &&
                   JOB_COMPRESS + 1 == LIGHT_BUILD_COMPRESS,
               "job_phase and light_build_phase in one order");

enum light_build_phase light_gpu_build_phase(const struct light_gpu *lg)
{
    /* A job that reaches JOB_DONE is no longer active. */
    if (!lg->job.active || lg->job.phase == JOB_DONE)
        return LIGHT_BUILD_START;
    return (enum light_build_phase)(lg->job.phase + 1);
}

static const char *const phase_names[LIGHT_BUILD_PHASES] = {
    "start", "lateral rates", "slices", "sweep", "the columns' diffuse light",
    "the diffuse light volume's solve", "compression"};

const char *light_build_phase_name(enum light_build_phase phase)
{
    return phase >= 0 && phase < LIGHT_BUILD_PHASES ? phase_names[phase] : "?";
}

const char *light_gpu_build_doing(const struct light_gpu *lg)
{
    static const char *const doing[LIGHT_BUILD_PHASES] = {
        "the light build's start", "light build: lateral rates", "light build: slices",
        "light build: sweep", "light build: the columns' diffuse light",
        "light build: the diffuse light volume's solve", "light build: compression"};
    return doing[light_gpu_build_phase(lg)];
}

bool light_gpu_building(const struct light_gpu *lg)
{
    return lg->job.active;
}

void light_gpu_build_cancel(struct light_gpu *lg)
{
    lg->job.active = false;
}

const struct render_light *light_gpu_render_light(struct light_gpu *lg)
{
    return &lg->hook;
}

unsigned light_gpu_builds(const struct light_gpu *lg)
{
    return lg->cache.builds;
}

void light_gpu_set_half(struct light_gpu *lg, bool half)
{
    lg->half = half;
}

void light_gpu_set_timing(struct light_gpu *lg, struct gpu_timings *log)
{
    lg->timing = log;
}

int light_gpu_collect_timings(struct light_gpu *lg, bool wait)
{
    return gpu_timer_queue_collect(&lg->timers, wait);
}

bool light_gpu_last_build_ms(struct light_gpu *lg, double *ms)
{
    /* The last build is the newest measurement: known once none is in flight. */
    if (!lg->last_timed || light_gpu_collect_timings(lg, false) > 0)
        return false;
    *ms = lg->timers.last_ms;
    return true;
}

void light_gpu_bytes(const struct light_gpu *lg, size_t *dense, size_t *compressed)
{
    /* What the dense map takes (or would take, in compressed mode, for comparison): the light
     * in R32F and the diffuse light in RG32F. */
    size_t nodes = (size_t)lg->grid.n[0] * lg->grid.n[1] * lg->grid.n[2];
    size_t diffuse = lg->built_multiple ? 2 * nodes * sizeof(float) : 0;
    *dense = nodes * sizeof(float) + diffuse;
    if (lg->built_half && lg->built_mode == LIGHT_GPU_DENSE)
        *dense /= 2;
    *compressed = lg->compressed_bytes;
    if (lg->built_volume) {
        size_t field = grid3_count(&lg->volume.grid) * 4 * sizeof(float);
        *dense += field;
        if (*compressed)
            *compressed += field;
    }
}

bool light_gpu_read_compressed(const struct light_gpu *lg, struct light_compressed *out)
{
    memset(out, 0, sizeof(*out));
    if (!lg->compressed_bytes) {
        log_error("light map: no compressed map on the GPU (none built, or dense mode)");
        return false;
    }
    out->grid = lg->grid;
    out->epsilon = lg->built_epsilon;
    out->node_count = lg->compressed_nodes;
    size_t ncol = (size_t)lg->grid.n[0] * lg->grid.n[1];
    out->columns = malloc(2 * ncol * sizeof(uint32_t));
    out->nodes = malloc((out->node_count ? out->node_count : 1) * 2 * sizeof(float));
    if (!out->columns || !out->nodes) {
        log_error("light map: out of memory reading %zu nodes back", out->node_count);
        light_compressed_finish(out);
        return false;
    }
    gpu_buffer_read(&lg->columns, 0, 2 * ncol * sizeof(uint32_t), out->columns);
    gpu_buffer_read(&lg->nodes, 0, out->node_count * 2 * sizeof(float), out->nodes);
    if (lg->built_multiple) {
        out->diffuse_node_count = lg->diffuse_nodes;
        out->diffuse_columns = malloc(2 * ncol * sizeof(uint32_t));
        out->diffuse_nodes = malloc((out->diffuse_node_count ? out->diffuse_node_count : 1) * 3 *
                                    sizeof(float));
        if (!out->diffuse_columns || !out->diffuse_nodes) {
            log_error("light map: out of memory reading %zu nodes back", out->diffuse_node_count);
            light_compressed_finish(out);
            return false;
        }
        gpu_buffer_read(&lg->columns, lg->diffuse_columns_at * sizeof(uint32_t),
                        2 * ncol * sizeof(uint32_t), out->diffuse_columns);
        gpu_buffer_read(&lg->nodes, lg->diffuse_nodes_at * sizeof(float),
                        out->diffuse_node_count * 3 * sizeof(float), out->diffuse_nodes);
    }
    return true;
}

bool light_gpu_read_volume(const struct light_gpu *lg, struct light_volume *out)
{
    if (!lg->built_volume)
        return false;
    return light_volume_gpu_read(&lg->volume, out);
}
