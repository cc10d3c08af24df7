#include "render/render.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cglm/cglm.h>

#include "common/log.h"
#include "common/mat4d.h"
#include "common/progress.h"
#include "render/stage.h"
#include "shaders/bindings.h"

#define PHASE_TABLE_SIZE 512
#define MAX_VARIANTS 32
#define MAX_MESHES 64

struct render_mesh {
    struct gpu_mesh mesh;
    float model[16];
    bool emissive, visible;
    const struct gpu_texture *texture;
};

struct variant {
    char defines[384];
    struct gpu_program prog;
    uint64_t used; /* renderer.variant_clock when last asked for */
};

/* What a volume's textures hold besides the extinction. */
struct held_fields {
    bool tint;
    bool layer[TRANSFER_LAYER_MAX], slice[TRANSFER_SLICE_MAX], surface[TRANSFER_SLICE_MAX];
    enum transfer_field layer_field[TRANSFER_LAYER_MAX], slice_field[TRANSFER_SLICE_MAX];
};

struct renderer {
    struct gpu_texture beta;
    struct gpu_texture tint; /* RGBA8 3D, only while the volume has tints (TINT 1) */
    bool have_tint;
    struct grid3 grid;
    bool have_volume;
    struct gpu_texture zmap; /* the grid's height table, while it is stretched (STRETCHED 1) */
    struct gpu_texture layer_fields; /* RGBA32F 3D: the volume's layers' fields (LAYERS) */
    enum transfer_field layer_field[TRANSFER_LAYER_MAX];
    bool layer_held[TRANSFER_LAYER_MAX]; /* the volume has layer i's field */
    struct gpu_texture layer_lut;    /* RGBA32F 2D: a colour map per row */
    struct render_layer layers[TRANSFER_LAYER_MAX];
    int layer_count;
    struct gpu_texture slice_fields; /* RGBA32F 3D: the volume's slices' fields (SLICES) */
    struct gpu_texture slice_surfaces; /* RGBA32F 2D: the slices' level surfaces, world z */
    bool surface_held[TRANSFER_SLICE_MAX];
    enum transfer_field slice_field[TRANSFER_SLICE_MAX];
    bool slice_held[TRANSFER_SLICE_MAX];
    struct render_slice slices[TRANSFER_SLICE_MAX];
    int slice_count;
    bool lut_stale;
    struct gpu_texture beta_next; /* effects.temporal: step k + 1 (TEMPORAL 1) */
    struct grid3 grid_next;
    bool have_next;
    /* A staged next volume (renderer_stage_next) is a whole one, ready to be swapped in:
     * its tints, fields, surfaces and cells beside beta_next, what they hold in NEXT_HELD. */
    struct gpu_texture tint_next, layer_fields_next, slice_fields_next, slice_surfaces_next;
    struct render_cells next_cells;
    struct held_fields next_held;
    bool next_whole;
    struct render_stage stage;
    enum { STAGE_IDLE, STAGE_COPYING, STAGE_UPLOADING, STAGE_CELLS } stage_state;
    struct grid3 stage_grid;
    struct held_fields stage_held;
    size_t stage_done; /* bytes of the staged volume uploaded so far */
    bool stage_paced;  /* the copy in slices in renderer_stage_step (renderer_set_stage_paced) */
    bool stage_cpu_cells; /* the stage makes the cells (renderer_set_stage_cpu_cells) */
    bool ballot_offered;  /* GL_ARB_shader_ballot with 64-bit integers */
    bool ballot;          /* the first pass lists its rays by ballot (renderer_set_ballot) */
    struct gpu_texture phase;
    float mean_cosine[2]; /* g of the ice and the water phase (MULTIPLE) */
    struct gpu_program tonemap, tonemap_packed;
    struct gpu_texture packed;   /* R32UI: the tone-mapped bytes of a file */
    struct gpu_buffer nonfinite; /* their count of non-finite pixels */
    struct variant variants[MAX_VARIANTS];
    int n_variants;
    uint64_t variant_clock;
    const struct render_light *light;
    struct render_mesh *meshes[MAX_MESHES];
    int n_meshes;
    struct gpu_program opaque[MAX_VARIANTS]; /* per light map variant */
    char opaque_defines[MAX_VARIANTS][256];
    int n_opaque;
    struct gpu_target target;
    struct render_cells_programs cell_programs;
    struct render_cells cells;      /* of beta */
    struct render_cells pair_cells; /* of beta and beta_next (effects.temporal) */
    bool pair_stale;                /* either changed since pair_cells were made */
    bool pair_building;             /* pair_cells under way in pieces (renderer_pair_cells_step) */
    bool counting;                  /* COUNT 1 (renderer_set_counting) */
    bool half;                      /* volumes in RG16F (renderer_set_half) */
    struct gpu_buffer counters;     /* 6 counts of two words each */
    struct gpu_buffer rays;         /* SKIP: the rays the second pass marches */
    struct gpu_timer_queue timers;
    struct gpu_timings *timing; /* where the views' times go; NULL: untimed */
    struct progress *progress;  /* rows drawn are counted here (renderer_set_progress) */
    uint64_t progress_rows;
    struct render_stats stats;
};

static const struct gpu_program *variant(struct renderer *r, const char *defines)
{
    if (!defines)
        defines = "";
    r->variant_clock++;
    for (int i = 0; i < r->n_variants; i++) {
        if (strcmp(r->variants[i].defines, defines) == 0) {
            r->variants[i].used = r->variant_clock;
            return &r->variants[i].prog;
        }
    }
    /* Full: the least recently used goes, in place, so that the programs a draw holds (used
     * just now) stay where they are. */
    int slot = r->n_variants;
    if (slot == MAX_VARIANTS) {
        slot = 0;
        for (int i = 1; i < MAX_VARIANTS; i++)
            if (r->variants[i].used < r->variants[slot].used)
                slot = i;
        gpu_program_finish(&r->variants[slot].prog);
        r->variants[slot].defines[0] = '\0';
    }
    struct variant *v = &r->variants[slot];
    if (!gpu_program_init(&v->prog, "raycast.comp", defines))
        return NULL;
    snprintf(v->defines, sizeof(v->defines), "%s", defines);
    v->used = r->variant_clock;
    if (slot == r->n_variants)
        r->n_variants++;
    return &v->prog;
}

struct renderer *renderer_create(void)
{
    struct renderer *r = calloc(1, sizeof(*r));
    if (!r)
        return NULL;
    if (!variant(r, NULL) || !gpu_program_init(&r->tonemap, "tonemap.comp", NULL) ||
        !gpu_program_init(&r->tonemap_packed, "tonemap.comp", "#define PACKED 1\n") ||
        !render_cells_programs_init(&r->cell_programs)) {
        renderer_destroy(r);
        return NULL;
    }
    float steps[IMAGE_TONEMAP_STEPS];
    image_tonemap_steps(steps);
    gpu_uniform_float_array(&r->tonemap_packed, "steps", IMAGE_TONEMAP_STEPS, steps);
    struct optics_params optics;
    optics_params_defaults(&optics);
    if (!renderer_set_optics(r, &optics)) {
        renderer_destroy(r);
        return NULL;
    }
    gpu_timer_queue_init(&r->timers, GPU_TIMER_AUTO);
    r->stage_paced = gpu_software_driver();
    r->stage_cpu_cells = true;
    r->ballot_offered = gpu_has_extension("GL_ARB_shader_ballot") &&
                        gpu_has_extension("GL_ARB_gpu_shader_int64");
    r->ballot = r->ballot_offered;
    return r;
}

void renderer_destroy(struct renderer *r)
{
    if (!r)
        return;
    gpu_texture_finish(&r->beta);
    gpu_texture_finish(&r->beta_next);
    render_stage_finish(&r->stage); /* before the textures the uploads write go */
    gpu_texture_finish(&r->tint_next);
    gpu_texture_finish(&r->layer_fields_next);
    gpu_texture_finish(&r->slice_fields_next);
    gpu_texture_finish(&r->slice_surfaces_next);
    render_cells_finish(&r->next_cells);
    gpu_texture_finish(&r->zmap);
    gpu_texture_finish(&r->tint);
    gpu_texture_finish(&r->layer_fields);
    gpu_texture_finish(&r->slice_fields);
    gpu_texture_finish(&r->slice_surfaces);
    gpu_texture_finish(&r->layer_lut);
    gpu_texture_finish(&r->phase);
    gpu_program_finish(&r->tonemap);
    gpu_program_finish(&r->tonemap_packed);
    gpu_texture_finish(&r->packed);
    gpu_buffer_finish(&r->nonfinite);
    for (int i = 0; i < r->n_variants; i++)
        gpu_program_finish(&r->variants[i].prog);
    for (int i = 0; i < r->n_opaque; i++)
        gpu_program_finish(&r->opaque[i]);
    gpu_target_finish(&r->target);
    render_cells_finish(&r->cells);
    render_cells_finish(&r->pair_cells);
    render_cells_programs_finish(&r->cell_programs);
    gpu_buffer_finish(&r->counters);
    gpu_buffer_finish(&r->rays);
    gpu_timer_queue_finish(&r->timers);
    free(r);
}

void renderer_set_half(struct renderer *r, bool half)
{
    r->half = half;
}

void renderer_set_stage_paced(struct renderer *r, bool paced)
{
    r->stage_paced = paced;
}

bool renderer_stage_paced(const struct renderer *r)
{
    return r->stage_paced;
}

void renderer_set_stage_cpu_cells(struct renderer *r, bool cpu)
{
    r->stage_cpu_cells = cpu;
}

bool renderer_set_ballot(struct renderer *r, bool on)
{
    r->ballot = on && r->ballot_offered;
    return r->ballot;
}

double renderer_stage_cells_ms(struct renderer *r)
{
    return render_stage_cells_ms(&r->stage);
}

/* Puts VOL's extinction into TEX (made or remade for its size and the renderer's storage).
 * Half floats: clamped to RENDER_HALF_MAX first (a larger float would become infinity), a few
 * layers at a time, so the copy stays small. */
static bool put_beta(struct renderer *r, struct gpu_texture *tex, const struct ext_volume *vol)
{
    const int *n = vol->grid.n;
    enum gpu_format f = r->half ? GPU_RG16F : GPU_RG32F;
    if (!tex->id || memcmp(tex->size, n, sizeof(int) * 3) != 0 || tex->format != f) {
        gpu_texture_finish(tex);
        if (!gpu_texture_init(tex, 3, n, f, NULL))
            return false;
    }
    if (!r->half) {
        gpu_texture_upload(tex, vol->beta);
        return true;
    }
    size_t layer = (size_t)n[0] * n[1] * 2;
    int step = 8;
    float *tmp = malloc(layer * (size_t)step * sizeof(float));
    if (!tmp) {
        log_error("out of memory converting the volume to half floats");
        return false;
    }
    for (int z = 0; z < n[2]; z += step) {
        int count = n[2] - z < step ? n[2] - z : step;
        const float *src = vol->beta + layer * (size_t)z;
        for (size_t i = 0; i < layer * (size_t)count; i++)
            tmp[i] = src[i] > RENDER_HALF_MAX ? RENDER_HALF_MAX : src[i];
        gpu_texture_upload_layers(tex, z, count, tmp);
    }
    free(tmp);
    return true;
}

/* Four fields (NULL: none) of N voxels into one RGBA32F texture TEX, a field per channel
 * (none at all: the texture goes). */
static bool put_fields(struct gpu_texture *tex, const int n[3], float *const fields[4])
{
    if (!fields[0] && !fields[1] && !fields[2] && !fields[3]) {
        gpu_texture_finish(tex);
        return true;
    }
    if (!tex->id || memcmp(tex->size, n, sizeof(int) * 3) != 0) {
        gpu_texture_finish(tex);
        if (!gpu_texture_init(tex, 3, n, GPU_RGBA32F, NULL))
            return false;
    }
    /* Eight z layers at a time: the interleaved copy stays small. */
    size_t plane = (size_t)n[0] * n[1];
    int step = 8;
    float *tmp = malloc(plane * (size_t)step * 4 * sizeof(float));
    if (!tmp) {
        log_error("out of memory uploading the layers' fields");
        return false;
    }
    for (int z = 0; z < n[2]; z += step) {
        int count = n[2] - z < step ? n[2] - z : step;
        size_t base = plane * (size_t)z;
        for (size_t v = 0; v < plane * (size_t)count; v++)
            for (int i = 0; i < 4; i++)
                tmp[4 * v + i] = fields[i] ? fields[i][base + v] : 0.0f;
        gpu_texture_upload_layers(tex, z, count, tmp);
    }
    free(tmp);
    return true;
}

/* Four surfaces (NULL: none) of N[0] x N[1] heights into one RGBA32F 2-D texture TEX, a
 * surface per channel (none at all: the texture goes). */
static bool put_surfaces(struct gpu_texture *tex, const int n[3], float *const surf[4])
{
    if (!surf[0] && !surf[1] && !surf[2] && !surf[3]) {
        gpu_texture_finish(tex);
        return true;
    }
    const int size[3] = {n[0], n[1], 1};
    size_t plane = (size_t)n[0] * n[1];
    float *tmp = malloc(plane * 4 * sizeof(float));
    if (!tmp) {
        log_error("out of memory uploading the slices' surfaces");
        return false;
    }
    for (size_t c = 0; c < plane; c++)
        for (int i = 0; i < 4; i++)
            tmp[4 * c + i] = surf[i] ? surf[i][c] : 0.0f;
    bool ok = true;
    if (tex->id && tex->size[0] == n[0] && tex->size[1] == n[1]) {
        gpu_texture_upload(tex, tmp);
    } else {
        gpu_texture_finish(tex);
        ok = gpu_texture_init(tex, 2, size, GPU_RGBA32F, tmp);
    }
    free(tmp);
    return ok;
}

/* The layers' and the slices' fields of VOL. */
static bool put_layer_fields(struct renderer *r, const struct ext_volume *vol)
{
    static_assert(TRANSFER_LAYER_MAX == 4 && TRANSFER_SLICE_MAX == 4, "a field per channel");
    for (int i = 0; i < TRANSFER_LAYER_MAX; i++) {
        r->layer_held[i] = vol->layer[i] != NULL;
        r->layer_field[i] = vol->layer_field[i];
        r->slice_held[i] = vol->slice[i] != NULL;
        r->slice_field[i] = vol->slice_field[i];
        r->surface_held[i] = vol->slice_surface[i] != NULL;
    }
    return put_fields(&r->layer_fields, vol->grid.n, vol->layer) &&
           put_fields(&r->slice_fields, vol->grid.n, vol->slice) &&
           put_surfaces(&r->slice_surfaces, vol->grid.n, vol->slice_surface);
}

float render_display_to_radiance(float c, float exposure)
{
    double v = c < 0.0f ? 0.0 : c > 1.0f ? 1.0 : c;
    double d = (v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4)) * 0.999;
    return (float)(d / (1.0 - d) / exposure);
}

void render_layer_from_transfer(const struct transfer_layer *l, float exposure,
                                struct render_layer *out)
{
    memset(out, 0, sizeof(*out));
    const struct transfer_function *tf = &l->tf;
    out->on = l->enabled && l->opacity > 0.0;
    out->tint = l->mode == TRANSFER_LAYER_TINT;
    out->field = tf->field;
    out->lo = (float)tf->lo;
    out->hi = (float)tf->hi;
    out->strength = (float)(out->tint ? l->opacity : tf->density * l->opacity);
    for (int i = 0; i < RENDER_LAYER_LUT; i++)
        for (int c = 0; c < TRANSFER_CHANNELS; c++) {
            float x = (float)i / (RENDER_LAYER_LUT - 1);
            float v = transfer_eval(tf, (enum transfer_channel)c, x);
            bool factor = c == TRANSFER_ALPHA || out->tint;
            out->lut[i][c] = factor ? v : render_display_to_radiance(v, exposure);
        }
}

/* The colour maps of the layers (rows 0 to 3) and the slices (rows 4 to 7), when changed. */
static bool put_luts(struct renderer *r)
{
    if (!r->lut_stale && r->layer_lut.id)
        return true;
    static float table[TRANSFER_LAYER_MAX + TRANSFER_SLICE_MAX][RENDER_LAYER_LUT][4];
    memset(table, 0, sizeof(table));
    for (int i = 0; i < r->layer_count; i++)
        memcpy(table[i], r->layers[i].lut, sizeof(table[i]));
    for (int i = 0; i < r->slice_count; i++)
        memcpy(table[TRANSFER_LAYER_MAX + i], r->slices[i].lut, sizeof(table[i]));
    r->lut_stale = false;
    if (r->layer_lut.id) {
        gpu_texture_upload(&r->layer_lut, table);
        return true;
    }
    const int size[3] = {RENDER_LAYER_LUT, TRANSFER_LAYER_MAX + TRANSFER_SLICE_MAX, 1};
    return gpu_texture_init(&r->layer_lut, 2, size, GPU_RGBA32F, table);
}

bool renderer_set_layers(struct renderer *r, const struct render_layer *layers, int count)
{
    assert(count >= 0 && count <= TRANSFER_LAYER_MAX);
    if (count == r->layer_count &&
        (count == 0 || memcmp(layers, r->layers, (size_t)count * sizeof(*layers)) == 0))
        return true;
    memset(r->layers, 0, sizeof(r->layers));
    if (count > 0)
        memcpy(r->layers, layers, (size_t)count * sizeof(*layers));
    r->layer_count = count;
    r->lut_stale = true;
    return true;
}

void render_slice_from_transfer(const struct transfer_slice *sl, float exposure,
                                struct render_slice *out)
{
    memset(out, 0, sizeof(*out));
    const struct transfer_function *tf = &sl->tf;
    out->on = sl->enabled && sl->opacity > 0.0;
    out->field = tf->field;
    double d = 0.0;
    for (int a = 0; a < 3; a++) {
        out->normal[a] = (float)sl->normal[a];
        d += sl->normal[a] * sl->point[a];
    }
    out->offset = (float)d;
    out->lo = (float)tf->lo;
    out->hi = (float)tf->hi;
    out->opacity = (float)sl->opacity;
    out->contour_every = (float)sl->contour_every;
    out->contour_count = sl->contour_count;
    for (int k = 0; k < sl->contour_count && k < TRANSFER_CONTOUR_MAX; k++)
        out->contour_values[k] = (float)sl->contour_values[k];
    out->surface = sl->level > 0;
    for (int i = 0; i < RENDER_LAYER_LUT; i++)
        for (int c = 0; c < TRANSFER_CHANNELS; c++) {
            float x = (float)i / (RENDER_LAYER_LUT - 1);
            float v = transfer_eval(tf, (enum transfer_channel)c, x);
            out->lut[i][c] = c == TRANSFER_ALPHA ? v : render_display_to_radiance(v, exposure);
        }
}

bool renderer_set_slices(struct renderer *r, const struct render_slice *slices, int count)
{
    assert(count >= 0 && count <= TRANSFER_SLICE_MAX);
    if (count == r->slice_count &&
        (count == 0 || memcmp(slices, r->slices, (size_t)count * sizeof(*slices)) == 0))
        return true;
    memset(r->slices, 0, sizeof(r->slices));
    if (count > 0)
        memcpy(r->slices, slices, (size_t)count * sizeof(*slices));
    r->slice_count = count;
    r->lut_stale = true;
    return true;
}

/* Whether slice I is drawn: on, over the field the volume holds, and over its surface where
 * it follows one. */
static bool slice_drawn(const struct renderer *r, int i)
{
    const struct render_slice *sl = &r->slices[i];
    return sl->on && r->slice_held[i] && r->slice_field[i] == sl->field &&
           (!sl->surface || (r->surface_held[i] && r->slice_surfaces.id));
}

/* How many of the first slices the next draw reads (the SLICES define). */
static int slices_shown(const struct renderer *r)
{
    int n = 0;
    if (!r->slice_fields.id)
        return 0;
    for (int i = 0; i < r->slice_count; i++)
        if (slice_drawn(r, i))
            n = i + 1;
    return n;
}

static void slice_uniforms(const struct renderer *r, const struct gpu_program *prog, int n,
                           const struct render_view *view)
{
    float planes[4][4] = {{0}}, lo[4] = {0}, scale[4] = {0}, opacity[4] = {0}, every[4] = {0};
    float follow[4] = {0}, values[TRANSFER_CONTOUR_MAX][4] = {{0}}, value_count[4] = {0};
    for (int i = 0; i < n; i++) {
        const struct render_slice *sl = &r->slices[i];
        if (!slice_drawn(r, i))
            continue;
        follow[i] = sl->surface ? 1.0f : 0.0f;
        value_count[i] = (float)sl->contour_count;
        for (int k = 0; k < sl->contour_count; k++)
            values[k][i] = sl->contour_values[k];
        memcpy(planes[i], sl->normal, sizeof(sl->normal));
        planes[i][3] = sl->offset;
        lo[i] = sl->lo;
        scale[i] = sl->hi > sl->lo ? 1.0f / (sl->hi - sl->lo) : 0.0f;
        opacity[i] = sl->opacity;
        every[i] = sl->contour_every;
    }
    static const char *const names[4] = {"slice_plane[0]", "slice_plane[1]", "slice_plane[2]",
                                         "slice_plane[3]"};
    for (int i = 0; i < 4; i++)
        gpu_uniform_vec4(prog, names[i], planes[i]);
    gpu_uniform_vec4(prog, "slice_lo", lo);
    gpu_uniform_vec4(prog, "slice_scale", scale);
    gpu_uniform_vec4(prog, "slice_opacity", opacity);
    gpu_uniform_vec4(prog, "slice_contour", every);
    gpu_uniform_vec4(prog, "slice_follow", follow);
    static_assert(TRANSFER_CONTOUR_MAX == 6, "raycast.comp's slice_values");
    static const char *const value_names[TRANSFER_CONTOUR_MAX] = {
        "slice_values[0]", "slice_values[1]", "slice_values[2]",
        "slice_values[3]", "slice_values[4]", "slice_values[5]"};
    for (int k = 0; k < TRANSFER_CONTOUR_MAX; k++)
        gpu_uniform_vec4(prog, value_names[k], values[k]);
    gpu_uniform_vec4(prog, "slice_value_count", value_count);
    gpu_uniform_int(prog, "slice_row", TRANSFER_LAYER_MAX); /* put_luts */
}

/* The layers the next draw shows: on, and over a field the volume holds.  Returns how many of
 * the first layers the pass reads (the LAYERS define) and whether one of them emits. */
static int layers_shown(const struct renderer *r, bool *emits)
{
    int n = 0;
    *emits = false;
    if (!r->layer_fields.id)
        return 0;
    for (int i = 0; i < r->layer_count; i++) {
        const struct render_layer *l = &r->layers[i];
        if (l->on && l->strength > 0.0f && r->layer_held[i] && r->layer_field[i] == l->field) {
            n = i + 1;
            *emits |= !l->tint;
        }
    }
    return n;
}

static void layer_uniforms(const struct renderer *r, const struct gpu_program *prog, int n)
{
    float lo[4] = {0}, scale[4] = {0}, strength[4] = {0}, tint[4] = {0};
    for (int i = 0; i < n; i++) {
        const struct render_layer *l = &r->layers[i];
        if (!(l->on && r->layer_held[i] && r->layer_field[i] == l->field))
            continue;
        lo[i] = l->lo;
        scale[i] = l->hi > l->lo ? 1.0f / (l->hi - l->lo) : 0.0f;
        strength[i] = l->strength;
        tint[i] = l->tint ? 1.0f : 0.0f;
    }
    gpu_uniform_vec4(prog, "layer_lo", lo);
    gpu_uniform_vec4(prog, "layer_scale", scale);
    gpu_uniform_vec4(prog, "layer_strength", strength);
    gpu_uniform_vec4(prog, "layer_tint", tint);
    const float size[2] = {(float)RENDER_LAYER_LUT,
                           (float)(TRANSFER_LAYER_MAX + TRANSFER_SLICE_MAX)};
    gpu_uniform_vec2(prog, "layer_lut_size", size);
}

bool renderer_set_volume(struct renderer *r, const struct ext_volume *vol)
{
    double start = time_now_ms();
    const int *n = vol->grid.n;
    if (!put_beta(r, &r->beta, vol))
        return false;
    r->have_tint = vol->tint != NULL;
    if (vol->tint && r->tint.id && memcmp(r->tint.size, n, sizeof(int) * 3) == 0) {
        gpu_texture_upload(&r->tint, vol->tint);
    } else if (vol->tint) {
        gpu_texture_finish(&r->tint);
        if (!gpu_texture_init(&r->tint, 3, n, GPU_RGBA8, vol->tint))
            return false;
    } else {
        gpu_texture_finish(&r->tint);
    }
    if (!put_layer_fields(r, vol))
        return false;
    r->grid = vol->grid;
    if (!grid3_stretched(&r->grid))
        gpu_texture_finish(&r->zmap);
    else if (!render_zmap_upload(&r->grid, &r->zmap, NULL))
        return false;
    r->have_volume = true;
    r->pair_stale = true;
    r->pair_building = false;
    size_t voxels = (size_t)n[0] * n[1] * n[2];
    r->stats.upload_bytes += voxels * (r->half ? 4 : 8) + (vol->tint ? voxels * 4 : 0) +
                             (r->layer_fields.id ? voxels * 16 : 0) +
                             (r->slice_fields.id ? voxels * 16 : 0);
    r->stats.uploads++;
    if (!render_cells_build(&r->cells, &r->cell_programs, &r->beta, NULL, &r->grid))
        return false;
    r->stats.upload_ms = time_now_ms() - start;
    return true;
}

bool renderer_set_next_volume(struct renderer *r, const struct ext_volume *vol)
{
    renderer_stage_cancel(r);
    r->next_whole = false;
    if (!vol) {
        gpu_texture_finish(&r->beta_next);
        r->have_next = false;
        return true;
    }
    const int *n = vol->grid.n;
    r->have_next = false;
    if (!put_beta(r, &r->beta_next, vol))
        return false;
    r->grid_next = vol->grid;
    r->have_next = true;
    r->pair_stale = true;
    r->pair_building = false;
    r->stats.upload_bytes += (size_t)n[0] * n[1] * n[2] * (r->half ? 4 : 8);
    r->stats.uploads++;
    return true;
}

/* ---- the next volume through a pixel buffer: a step change that is a swap ------------------ */

static void held_of(const struct ext_volume *vol, struct held_fields *h)
{
    h->tint = vol->tint != NULL;
    for (int i = 0; i < TRANSFER_LAYER_MAX; i++) {
        h->layer[i] = vol->layer[i] != NULL;
        h->layer_field[i] = vol->layer_field[i];
    }
    for (int i = 0; i < TRANSFER_SLICE_MAX; i++) {
        h->slice[i] = vol->slice[i] != NULL;
        h->slice_field[i] = vol->slice_field[i];
        h->surface[i] = vol->slice_surface[i] != NULL;
    }
}

/* TEX made (or kept) as a DIMS-D texture of SIZE and format F; WANT false: none. */
static bool ensure_volume_texture(struct gpu_texture *tex, bool want, int dims, const int n[3],
                                  enum gpu_format f)
{
    const int size[3] = {n[0], n[1], dims == 3 ? n[2] : 1};
    if (!want) {
        gpu_texture_finish(tex);
        return true;
    }
    if (tex->id && tex->dims == dims && memcmp(tex->size, size, sizeof(size)) == 0 &&
        tex->format == f)
        return true;
    gpu_texture_finish(tex);
    return gpu_texture_init(tex, dims, size, f, NULL);
}

bool renderer_stage_next(struct renderer *r, const struct ext_volume *vol, float *also,
                         bool *started)
{
    *started = false;
    if (r->stage_state != STAGE_IDLE)
        return true;
    bool failed = false;
    if (!render_stage_begin(&r->stage, vol, also, r->half, r->stage_paced, r->stage_cpu_cells,
                            &failed))
        return !failed;
    r->have_next = false; /* beta_next is about to hold another volume */
    r->next_whole = false;
    r->pair_stale = true;
    r->pair_building = false;
    r->stage_grid = vol->grid;
    held_of(vol, &r->stage_held);
    r->stage_state = STAGE_COPYING;
    r->stage_done = 0;
    *started = true;
    return true;
}

bool renderer_stage_busy(const struct renderer *r)
{
    return r->stage_state != STAGE_IDLE;
}

bool renderer_stage_copying(const struct renderer *r)
{
    return r->stage_state == STAGE_COPYING;
}

void renderer_stage_cancel(struct renderer *r)
{
    if (r->stage_state == STAGE_IDLE)
        return;
    if (r->stage_state != STAGE_CELLS) {
        render_stage_wait(&r->stage);
        render_stage_release(&r->stage);
    }
    r->stage_state = STAGE_IDLE;
    r->have_next = false;
    r->next_whole = false;
}

/* The staged volume's regions in upload order: the texture, its buffer offset, the bytes of
 * one z layer of it (a 2-D texture is one layer). */
struct stage_piece {
    struct gpu_texture *tex;
    size_t offset, layer_bytes;
    int layers;
};

static int stage_pieces(struct renderer *r, struct stage_piece out[5])
{
    const struct render_stage_layout *lay = &r->stage.lay;
    const int *n = r->stage_grid.n;
    size_t plane = (size_t)n[0] * n[1];
    struct stage_piece all[5] = {
        {&r->beta_next, lay->beta, plane * 8, n[2]},
        {&r->tint_next, lay->tint, plane * 4, n[2]},
        {&r->layer_fields_next, lay->layers, plane * 16, n[2]},
        {&r->slice_fields_next, lay->slices, plane * 16, n[2]},
        {&r->slice_surfaces_next, lay->surfaces, plane * 16, 1},
    };
    int count = 0;
    for (int i = 0; i < 5; i++)
        if (all[i].offset != RENDER_STAGE_NONE)
            out[count++] = all[i];
    return count;
}

/* Layers of level-0 macro cells one renderer_stage_step makes (cells_build.comp's
 * local_size_z). */
#define STAGE_CELL_LAYERS 4
/* And rows of them (a multiple of its local_size_y): a 500 x 500 volume's 125 rows of cells
 * in two pieces a layer. */
#define STAGE_CELL_ROWS 64

bool renderer_stage_step(struct renderer *r, size_t budget, bool *ready)
{
    *ready = false;
    if (r->stage_state == STAGE_IDLE) {
        *ready = r->have_next && r->next_whole;
        return true;
    }
    if (r->stage_state == STAGE_COPYING) {
        if (r->stage.paced && !render_stage_copied(&r->stage)) {
            /* A slice of the copy is this call's piece (BUDGET 0: all of it, and on). */
            size_t copied = 0;
            render_stage_copy_some(&r->stage, budget == 0 ? SIZE_MAX : budget, &copied);
            if (budget != 0)
                return true;
        }
        if (!render_stage_copied(&r->stage))
            return true;
        const struct render_stage_layout *lay = &r->stage.lay;
        const int *n = r->stage_grid.n;
        if (!ensure_volume_texture(&r->beta_next, true, 3, n, r->half ? GPU_RG16F : GPU_RG32F) ||
            !ensure_volume_texture(&r->tint_next, lay->tint != RENDER_STAGE_NONE, 3, n,
                                   GPU_RGBA8) ||
            !ensure_volume_texture(&r->layer_fields_next, lay->layers != RENDER_STAGE_NONE, 3, n,
                                   GPU_RGBA32F) ||
            !ensure_volume_texture(&r->slice_fields_next, lay->slices != RENDER_STAGE_NONE, 3,
                                   n, GPU_RGBA32F) ||
            !ensure_volume_texture(&r->slice_surfaces_next, lay->surfaces != RENDER_STAGE_NONE,
                                   2, n, GPU_RGBA32F)) {
            renderer_stage_cancel(r);
            return false;
        }
        r->stage_state = STAGE_UPLOADING;
        if (budget != 0)
            return true; /* the textures made (once): the slabs from the next call */
    }
    /* Whole z layers, as many as BUDGET allows (at least one): a long upload is spread over
     * several calls. */
    struct stage_piece pieces[5];
    int count = stage_pieces(r, pieces);
    size_t start = r->stage_done, at = 0, total = 0;
    for (int i = 0; i < count; i++)
        total += pieces[i].layer_bytes * (size_t)pieces[i].layers;
    for (int i = 0; i < count; i++) {
        const struct stage_piece *p = &pieces[i];
        size_t bytes = p->layer_bytes * (size_t)p->layers;
        if (r->stage_done < at + bytes) {
            while (r->stage_done < at + bytes &&
                   (budget == 0 || r->stage_done == start || r->stage_done - start < budget)) {
                int z = (int)((r->stage_done - at) / p->layer_bytes);
                size_t left = budget == 0 ? bytes : budget - (r->stage_done - start);
                int layers = (int)(left / p->layer_bytes);
                if (layers < 1)
                    layers = 1;
                if (layers > p->layers - z)
                    layers = p->layers - z;
                gpu_texture_upload_from(p->tex, &r->stage.pbo,
                                        p->offset + (size_t)z * p->layer_bytes, z, layers);
                r->stage_done += (size_t)layers * p->layer_bytes;
            }
        }
        at += bytes;
    }
    if (r->stage_done < total)
        return true;
    if (r->stage_state == STAGE_UPLOADING) {
        /* Uploaded: the cells next, the stage's in one piece, else a few layers a call. */
        render_stage_release(&r->stage);
        r->stage_state = STAGE_CELLS;
        size_t made;
        if (!render_stage_cells(&r->stage, &made) &&
            !render_cells_build_begin(&r->next_cells, &r->beta_next, &r->stage_grid)) {
            r->stage_state = STAGE_IDLE;
            return false;
        }
        if (budget != 0)
            return true;
    }
    size_t cell_count = 0;
    const float *cells = render_stage_cells(&r->stage, &cell_count);
    bool built = false;
    if (cells) {
        /* Made with the copy: a few MB to upload. */
        if (!render_cells_upload(&r->next_cells, &r->beta_next, &r->stage_grid, cells,
                                 cell_count)) {
            r->stage_state = STAGE_IDLE;
            return false;
        }
        r->stats.upload_bytes += cell_count * sizeof(float);
        r->stats.cpu_cells++;
        built = true;
    }
    while (!built) {
        if (!render_cells_build_piece(&r->next_cells, &r->cell_programs, &r->beta_next, NULL,
                                      &r->stage_grid, budget == 0 ? 0 : STAGE_CELL_LAYERS,
                                      budget == 0 ? 0 : STAGE_CELL_ROWS, &built)) {
            r->stage_state = STAGE_IDLE;
            return false;
        }
        if (budget != 0)
            break;
    }
    if (!built)
        return true;
    r->stage_state = STAGE_IDLE;
    r->grid_next = r->stage_grid;
    r->next_held = r->stage_held;
    r->have_next = true;
    r->next_whole = true;
    r->pair_stale = true;
    r->pair_building = false;
    r->stats.upload_bytes += total;
    r->stats.uploads++;
    *ready = true;
    return true;
}

static void swap_textures(struct gpu_texture *a, struct gpu_texture *b)
{
    struct gpu_texture t = *a;
    *a = *b;
    *b = t;
}

bool renderer_swap_next(struct renderer *r)
{
    if (!r->have_next || !r->next_whole || r->stage_state != STAGE_IDLE)
        return false;
    swap_textures(&r->beta, &r->beta_next);
    swap_textures(&r->tint, &r->tint_next);
    swap_textures(&r->layer_fields, &r->layer_fields_next);
    swap_textures(&r->slice_fields, &r->slice_fields_next);
    swap_textures(&r->slice_surfaces, &r->slice_surfaces_next);
    struct render_cells cells = r->cells;
    r->cells = r->next_cells;
    r->next_cells = cells;
    struct grid3 grid = r->grid;
    r->grid = r->grid_next;
    r->grid_next = grid;
    /* The height table (a few KiB) follows the grid where the levels differ. */
    if (!grid3_stretched(&r->grid))
        gpu_texture_finish(&r->zmap);
    else if (!grid3_equal(&r->grid, &r->grid_next) &&
             !render_zmap_upload(&r->grid, &r->zmap, NULL))
        return false;
    const struct held_fields *h = &r->next_held;
    r->have_tint = h->tint;
    for (int i = 0; i < TRANSFER_LAYER_MAX; i++) {
        r->layer_held[i] = h->layer[i];
        r->layer_field[i] = h->layer_field[i];
    }
    for (int i = 0; i < TRANSFER_SLICE_MAX; i++) {
        r->slice_held[i] = h->slice[i];
        r->slice_field[i] = h->slice_field[i];
        r->surface_held[i] = h->surface[i];
    }
    /* The old step's textures stay allocated for the next staged volume, but hold nothing. */
    r->have_volume = true;
    r->have_next = false;
    r->next_whole = false;
    r->pair_stale = true;
    r->pair_building = false;
    return true;
}

const struct render_cells *renderer_next_cells(const struct renderer *r)
{
    return r->have_next && r->next_whole ? &r->next_cells : NULL;
}

const struct render_cells *renderer_cells(const struct renderer *r)
{
    return &r->cells;
}

static bool pair_possible(const struct renderer *r)
{
    return r->have_next && r->have_volume &&
           memcmp(r->beta.size, r->beta_next.size, sizeof(r->beta.size)) == 0;
}

const struct render_cells *renderer_pair_cells(struct renderer *r)
{
    if (!pair_possible(r))
        return NULL;
    if (r->pair_stale) {
        r->pair_building = false; /* the pieces so far are made again, whole */
        if (!render_cells_build(&r->pair_cells, &r->cell_programs, &r->beta, &r->beta_next,
                                &r->grid))
            return NULL;
        r->pair_stale = false;
    }
    return &r->pair_cells;
}

bool renderer_pair_cells_step(struct renderer *r, int layers, bool *done)
{
    *done = true;
    if (!pair_possible(r) || !r->pair_stale)
        return true;
    *done = false;
    const struct render_cells *a = &r->cells, *b = &r->next_cells;
    if (!r->pair_building && r->next_whole && a->levels > 0 && b->levels > 0 &&
        a->count == b->count && a->cell_voxels == b->cell_voxels &&
        grid3_equal(&r->grid, &r->grid_next)) {
        /* Both volumes' cells are made: the pair's are their maxima. */
        if (!render_cells_max(&r->pair_cells, a, b, &r->beta, &r->grid))
            return false;
        r->stats.upload_bytes += r->pair_cells.count * sizeof(float);
        r->pair_stale = false;
        *done = true;
        return true;
    }
    if (!r->pair_building) {
        if (!render_cells_build_begin(&r->pair_cells, &r->beta, &r->grid))
            return false;
        r->pair_building = true;
    }
    bool built = false;
    if (!render_cells_build_piece(&r->pair_cells, &r->cell_programs, &r->beta, &r->beta_next,
                                  &r->grid, layers, layers > 0 ? STAGE_CELL_ROWS : 0, &built)) {
        r->pair_building = false;
        return false;
    }
    if (built) {
        r->pair_building = false;
        r->pair_stale = false;
        *done = true;
    }
    return true;
}

bool renderer_pair_cells_ready(const struct renderer *r)
{
    return !pair_possible(r) || !r->pair_stale;
}

bool renderer_stage_uploading(const struct renderer *r)
{
    return r->stage_state == STAGE_UPLOADING;
}

const char *renderer_stage_doing(const struct renderer *r)
{
    switch (r->stage_state) {
    case STAGE_COPYING:
        return r->stage.paced ? "a slice of the copy" : "the copy's end";
    case STAGE_UPLOADING:
        return "an upload slab";
    case STAGE_CELLS: {
        size_t count;
        return render_stage_cells(&r->stage, &count) ? "the staged cells' upload"
                                                     : "a piece of the staged cells";
    }
    case STAGE_IDLE:
        break;
    }
    return "nothing";
}

bool renderer_has_next(const struct renderer *r)
{
    return r->have_next;
}

const struct gpu_texture *renderer_next_texture(const struct renderer *r)
{
    return &r->beta_next;
}

const struct grid3 *renderer_next_grid(const struct renderer *r)
{
    return &r->grid_next;
}

const struct grid3 *renderer_grid(const struct renderer *r)
{
    return &r->grid;
}

const struct gpu_texture *renderer_volume_texture(const struct renderer *r)
{
    return &r->beta;
}

bool renderer_set_optics(struct renderer *r, const struct optics_params *optics)
{
    float table[PHASE_TABLE_SIZE * 2];
    optics_eye_phase_table(optics, PHASE_TABLE_SIZE, table);
    r->mean_cosine[0] = (float)optics->g_ice;
    r->mean_cosine[1] = (float)optics->g_water;
    if (r->phase.id) {
        gpu_texture_upload(&r->phase, table);
        return true;
    }
    int size[3] = {PHASE_TABLE_SIZE, 1, 1};
    return gpu_texture_init(&r->phase, 1, size, GPU_RG32F, table);
}

void renderer_set_light(struct renderer *r, const struct render_light *light)
{
    r->light = light;
}

static bool ensure_texture(struct gpu_texture *t, int w, int h, enum gpu_format f)
{
    if (t->id && t->size[0] == w && t->size[1] == h && t->format == f)
        return true;
    gpu_texture_finish(t);
    int size[3] = {w, h, 1};
    return gpu_texture_init(t, 2, size, f, NULL);
}

static const struct gpu_program *opaque_program(struct renderer *r, const char *defines)
{
    for (int i = 0; i < r->n_opaque; i++) {
        if (strcmp(r->opaque_defines[i], defines) == 0)
            return &r->opaque[i];
    }
    if (r->n_opaque == MAX_VARIANTS) {
        log_error("too many opaque shader variants");
        return NULL;
    }
    if (!gpu_program_init_graphics(&r->opaque[r->n_opaque], "opaque.vert", "opaque.frag",
                                   defines))
        return NULL;
    snprintf(r->opaque_defines[r->n_opaque], 256, "%s", defines);
    return &r->opaque[r->n_opaque++];
}

/* OUT = M^-1 (column-major), by Gauss-Jordan elimination in double: a perspective projection
 * with far / near ~1e5 loses a float inverse's last digits, and the rays with them
 * (shaders/common.glsl view_ray).  A singular M (a caller's mistake) gives the identity. */
static void invert_double(const float m[16], float out[16])
{
    double d[16], inv[16];
    for (int i = 0; i < 16; i++)
        d[i] = m[i];
    if (!mat4d_invert(d, inv)) {
        for (int i = 0; i < 16; i++)
            out[i] = i % 5 == 0 ? 1.0f : 0.0f;
        return;
    }
    for (int i = 0; i < 16; i++)
        out[i] = (float)inv[i];
}

/* Draws the visible meshes into the renderer's target: radiance and ray distance. */
static bool draw_opaque(struct renderer *r, const struct render_settings *s,
                        const struct render_view *view, mat4 vp, const float inv_proj[16],
                        const float inv_view[16], const char *defines)
{
    const struct gpu_program *p = opaque_program(r, defines);
    if (!p || !gpu_target_ensure(&r->target, view->width, view->height))
        return false;
    int size[2] = {view->width, view->height};
    gpu_uniform_mat4(p, "view_proj", (const float *)vp);
    gpu_uniform_mat4(p, "inv_proj", inv_proj);
    gpu_uniform_mat4(p, "inv_view", inv_view);
    gpu_uniform_ivec2(p, "image_size", size);
    gpu_uniform_vec3(p, "sun_dir", s->sun_dir);
    gpu_uniform_vec3(p, "sun_radiance", s->sun_radiance);
    gpu_uniform_vec3(p, "sky_radiance", s->sky);
    if (s->temporal)
        gpu_uniform_float(p, "temporal_f", s->temporal_f);
    if (r->light && r->light->bind)
        r->light->bind(r->light, p);
    const float clear[4] = {0, 0, 0, 0};
    gpu_target_begin(&r->target, clear, 1e30f);
    for (int i = 0; i < r->n_meshes; i++) {
        const struct render_mesh *m = r->meshes[i];
        if (!m->visible)
            continue;
        gpu_uniform_mat4(p, "model", m->model);
        gpu_uniform_int(p, "emissive", m->emissive ? 1 : 0);
        gpu_uniform_int(p, "textured", m->texture ? 1 : 0);
        if (m->texture)
            gpu_texture_bind(m->texture, BIND_OPAQUE_TEX_MESH);
        gpu_mesh_draw(&m->mesh, p);
    }
    gpu_target_end(&r->target);
    return true;
}

/* The uniforms and units every eye pass program of a draw reads. */
static void eye_uniforms(struct renderer *r, const struct gpu_program *prog,
                         const struct render_settings *s, const struct render_view *view,
                         const float inv_proj[16], const float inv_view[16],
                         const struct render_cells *cells)
{
    const struct grid3 *g = &r->grid;
    float box_min[3], box_size[3];
    float voxel[3];
    for (int i = 0; i < 3; i++) {
        box_min[i] = (float)g->origin[i];
        box_size[i] = (float)(g->n[i] * g->spacing[i]);
        voxel[i] = (float)g->spacing[i];
    }
    /* 0: the shader takes half the voxel crossing along each ray, and an optically thick step
     * in parts of at most one light map node. */
    float step = s->step_m > 0.0f ? s->step_m : 0.0f;
    int image_size[2] = {view->width, view->height};

    gpu_uniform_mat4(prog, "inv_proj", inv_proj);
    gpu_uniform_mat4(prog, "inv_view", inv_view);
    gpu_uniform_vec3(prog, "box_min", box_min);
    gpu_uniform_vec3(prog, "box_size", box_size);
    gpu_uniform_float(prog, "step_len", step);
    /* A pixel's width: the narrower of its two sides, constant (orthographic, proj[15] = 1)
     * or growing with the distance (perspective); the slices' contours and the level of
     * detail (LOD) read it. */
    float px = 2.0f / (fabsf(view->proj[0]) * (float)view->width);
    float py = 2.0f / (fabsf(view->proj[5]) * (float)view->height);
    float foot = fminf(px, py);
    float footprint[2] = {view->proj[15] != 0.0f ? foot : 0.0f,
                          view->proj[15] != 0.0f ? 0.0f : foot};
    gpu_uniform_vec2(prog, "pixel_footprint", footprint);
    if (s->lod_pixels > 0.0f) {
        /* The grown steps stop at half the ray's crossing of the thinnest level. */
        gpu_uniform_float(prog, "lod_pixels", s->lod_pixels);
        gpu_uniform_float(prog, "lod_level_dz", (float)grid3_min_dz(g));
    }
    gpu_uniform_vec3(prog, "voxel_size", voxel);
    gpu_uniform_int(prog, "max_steps", RENDER_MAX_STEPS);
    gpu_uniform_float(prog, "termination", s->termination);
    gpu_uniform_vec3(prog, "sun_dir", s->sun_dir);
    gpu_uniform_vec3(prog, "sun_radiance", s->sun_radiance);
    gpu_uniform_vec3(prog, "sky_radiance", s->sky);
    gpu_uniform_vec3(prog, "ground_albedo", s->ground);
    gpu_uniform_int(prog, "ground_on", s->ground_on ? 1 : 0);
    gpu_uniform_float(prog, "phase_size", (float)PHASE_TABLE_SIZE);
    /* One phase for all (PHASE_MIX 0): its mean cosine for both. */
    float g1 = s->single_phase_ice ? r->mean_cosine[0] : r->mean_cosine[1];
    float mean_cosine[2] = {s->single_phase ? g1 : r->mean_cosine[0],
                            s->single_phase ? g1 : r->mean_cosine[1]};
    gpu_uniform_vec2(prog, "mean_cosine", mean_cosine);
    gpu_uniform_ivec2(prog, "image_size", image_size);
    int zero[2] = {0, 0};
    gpu_uniform_ivec2(prog, "pixel_offset", zero);
    /* Also the blend of a light map pair (LIGHTMAP_PAIR), which comes only with temporal. */
    if (s->temporal)
        gpu_uniform_float(prog, "temporal_f", s->temporal_f);
    if (cells)
        render_cells_bind(cells, prog, BIND_EYE_BUF_CELLS, g);
    if (grid3_stretched(g)) {
        render_zmap_uniforms(g, &r->zmap, prog);
        gpu_texture_bind(&r->zmap, BIND_EYE_TEX_ZMAP);
    }
    if (r->light && r->light->bind)
        r->light->bind(r->light, prog);
}

/* The list of rays the second pass marches, large enough for a view of PIXELS, emptied. */
static bool reset_rays(struct renderer *r, size_t pixels)
{
    size_t bytes = 16 + 8 * pixels;
    if (r->rays.bytes < bytes) {
        gpu_buffer_finish(&r->rays);
        if (!gpu_buffer_init(&r->rays, bytes, NULL))
            return false;
    }
    const uint32_t head[4] = {0, 1, 1, 0}; /* no work groups yet, one along y and z, no rays */
    gpu_buffer_upload(&r->rays, 0, sizeof(head), head);
    return true;
}

bool renderer_draw(struct renderer *r, const struct render_settings *s,
                   const struct render_view *view, struct gpu_texture *out)
{
    if (!r->have_volume) {
        log_error("nothing to draw: no volume was set");
        return false;
    }
    if (!ensure_texture(out, view->width, view->height, GPU_RGBA32F))
        return false;
    const char *light_defines = r->light && r->light->defines ? r->light->defines : "";
    bool opaque = false;
    for (int i = 0; i < r->n_meshes; i++)
        opaque |= r->meshes[i]->visible;
    char defines[512];
    /* Temporal interpolation needs the next volume; without it the pass is the plain one. */
    bool temporal = s->temporal && r->have_next;
    /* Effects that are off are compiled out (app/effects.h). */
    const char *phase = !s->single_phase    ? ""
                        : s->single_phase_ice ? "#define PHASE_MIX 0\n#define PHASE_ICE 1\n"
                                              : "#define PHASE_MIX 0\n#define PHASE_ICE 0\n";
    /* Empty-space skipping reads the cells of what the pass samples: with temporal the pair's.
     * It takes two passes (raycast.comp, PASS 1 and 2); without it one (PASS 0). */
    bool emits;
    int layers = layers_shown(r, &emits);
    int slices = slices_shown(r);
    char layer_define[64] = "";
    snprintf(layer_define, sizeof(layer_define), "%s%d\n#define SLICES %d\n",
             "#define LAYERS ", layers, slices);
    if (layers == 0 && slices == 0)
        layer_define[0] = '\0';
    if ((layers > 0 || slices > 0) && !put_luts(r))
        return false;
    /* An emitting layer fills space the cells call empty, and a slice lies in it too: no
     * skipping then. */
    const struct render_cells *cells = NULL;
    if (!s->no_skip && !emits && slices == 0)
        cells = temporal ? renderer_pair_cells(r) : (r->cells.levels ? &r->cells : NULL);
    const struct gpu_program *progs[2] = {NULL, NULL};
    for (int pass = 0; pass < (cells ? 2 : 1); pass++) {
        snprintf(defines, sizeof(defines), "%s%s%s%s%s%s%s%s%s%s%s%s#define PASS %d\n",
                 cells && pass == 0 && r->ballot ? "#define BALLOT 1\n" : "", light_defines,
                 grid3_stretched(&r->grid) ? "#define STRETCHED 1\n" : "",
                 opaque ? "#define OPAQUE 1\n" : "", phase,
                 s->no_ground_shadow ? "#define GROUND_SHADOW 0\n" : "",
                 r->have_tint ? "#define TINT 1\n" : "", temporal ? "#define TEMPORAL 1\n" : "",
                 cells ? "#define SKIP 1\n" : "", r->counting ? "#define COUNT 1\n" : "",
                 s->lod_pixels > 0.0f ? "#define LOD 1\n" : "", layer_define, cells ? pass + 1 : 0);
        progs[pass] = variant(r, defines);
        if (!progs[pass])
            return false;
    }

    /* cglm's SIMD code needs aligned matrices; the caller's need not be. */
    mat4 proj, viewm, vp;
    memcpy(proj, view->proj, sizeof(proj));
    memcpy(viewm, view->view, sizeof(viewm));
    glm_mat4_mul(proj, viewm, vp);
    /* Rays come from the two inverses apart (shaders/common.glsl view_ray). */
    float inv_proj[16], inv_view[16];
    invert_double(view->proj, inv_proj);
    invert_double(view->view, inv_view);
    for (int pass = 0; pass < (cells ? 2 : 1); pass++) {
        eye_uniforms(r, progs[pass], s, view, inv_proj, inv_view, cells);
        if (layers > 0 || slices > 0)
            layer_uniforms(r, progs[pass], layers);
        if (slices > 0)
            slice_uniforms(r, progs[pass], slices, view);
    }
    if (layers > 0)
        gpu_texture_bind(&r->layer_fields, BIND_EYE_TEX_LAYERS);
    if (slices > 0) {
        gpu_texture_bind(&r->slice_fields, BIND_EYE_TEX_SLICES);
        if (r->slice_surfaces.id)
            gpu_texture_bind(&r->slice_surfaces, BIND_EYE_TEX_SLICE_SURFACES);
    }
    if (layers > 0 || slices > 0)
        gpu_texture_bind(&r->layer_lut, BIND_EYE_TEX_LAYER_LUT);
    gpu_texture_bind(&r->beta, BIND_EYE_TEX_BETA);
    gpu_texture_bind(&r->phase, BIND_EYE_TEX_PHASE);
    if (r->have_tint)
        gpu_texture_bind(&r->tint, BIND_EYE_TEX_TINT);
    if (temporal)
        gpu_texture_bind(&r->beta_next, BIND_EYE_TEX_BETA_NEXT);
    gpu_image_bind(out, BIND_EYE_IMG_OUT, true);
    if (r->counting)
        gpu_buffer_bind(&r->counters, BIND_EYE_BUF_COUNTERS);
    if (cells) {
        if (!reset_rays(r, (size_t)view->width * view->height))
            return false;
        gpu_buffer_bind(&r->rays, BIND_EYE_BUF_RAYS);
    }

    if (r->timing)
        gpu_timer_queue_begin(&r->timers);
    if (opaque) {
        if (!draw_opaque(r, s, view, vp, inv_proj, inv_view, light_defines))
            return false;
        gpu_texture_bind(&r->target.color, BIND_EYE_TEX_OPAQUE_COLOR);
        gpu_texture_bind(&r->target.value, BIND_EYE_TEX_OPAQUE_DISTANCE);
    }
    /* Bands of rows, each waited for, so that a long view says how far it is (a band is
     * whole work groups: every pixel is computed exactly as in one dispatch); else one. */
    const int band = r->progress ? 128 : view->height;
    for (int y = 0; y < view->height; y += band) {
        int rows = view->height - y < band ? view->height - y : band;
        gpu_uniform_int(progs[0], "row_offset", y);
        gpu_dispatch(progs[0], view->width, rows, 1);
        if (cells) {
            gpu_dispatch_indirect(progs[1], &r->rays, 0);
            if (y + rows < view->height && !reset_rays(r, (size_t)view->width * view->height))
                return false;
        }
        if (r->progress) {
            gpu_finish();
            r->progress_rows += (uint64_t)rows;
            progress_update(r->progress, r->progress_rows);
        }
    }
    r->stats.views++;
    if (r->timing)
        gpu_timer_queue_end(&r->timers, r->timing);
    return true;
}

bool renderer_tonemap(struct renderer *r, const struct gpu_texture *in, float exposure,
                      struct gpu_texture *out)
{
    if (!ensure_texture(out, in->size[0], in->size[1], GPU_RGBA8))
        return false;
    gpu_uniform_ivec2(&r->tonemap, "image_size", in->size);
    gpu_uniform_float(&r->tonemap, "exposure", exposure);
    gpu_image_bind(in, BIND_TONEMAP_IMG_IN, false);
    gpu_image_bind(out, BIND_TONEMAP_IMG_OUT, true);
    gpu_dispatch(&r->tonemap, in->size[0], in->size[1], 1);
    return true;
}

bool renderer_tonemap_read(struct renderer *r, const struct gpu_texture *in, float exposure,
                           uint8_t *rgba, size_t *nonfinite)
{
    if (!ensure_texture(&r->packed, in->size[0], in->size[1], GPU_R32UI))
        return false;
    uint32_t zero = 0;
    if (!r->nonfinite.id && !gpu_buffer_init(&r->nonfinite, sizeof(zero), &zero))
        return false;
    gpu_buffer_upload(&r->nonfinite, 0, sizeof(zero), &zero);
    const struct gpu_program *p = &r->tonemap_packed;
    gpu_uniform_ivec2(p, "image_size", in->size);
    gpu_uniform_float(p, "exposure", exposure);
    gpu_image_bind(in, BIND_TONEMAP_IMG_IN, false);
    gpu_image_bind(&r->packed, BIND_TONEMAP_IMG_OUT, true);
    gpu_buffer_bind(&r->nonfinite, BIND_TONEMAP_BUF_NONFINITE);
    gpu_dispatch(p, in->size[0], in->size[1], 1);
    /* r | g << 8 | b << 16 | a << 24 in a little-endian word: the bytes r, g, b, a. */
    size_t n = (size_t)in->size[0] * in->size[1];
    gpu_texture_read(&r->packed, rgba, n * 4);
    const uint32_t one = 1;
    if (*(const uint8_t *)&one == 0) { /* a big-endian host: the word's bytes the other way */
        for (size_t i = 0; i < n; i++) {
            uint8_t *p4 = rgba + 4 * i, t0 = p4[0], t1 = p4[1];
            p4[0] = p4[3], p4[1] = p4[2], p4[2] = t1, p4[3] = t0;
        }
    }
    if (nonfinite) {
        uint32_t count = 0;
        gpu_buffer_read(&r->nonfinite, 0, sizeof(count), &count);
        *nonfinite = count;
    }
    return true;
}

bool renderer_read(const struct gpu_texture *tex, struct image *img)
{
    if (!image_init(img, tex->size[0], tex->size[1]))
        return false;
    gpu_texture_read(tex, img->rgba, (size_t)img->width * img->height * 4 * sizeof(float));
    return true;
}

bool renderer_set_counting(struct renderer *r, bool on)
{
    r->counting = false;
    if (!on)
        return true;
    uint32_t zero[12] = {0};
    if (!r->counters.id && !gpu_buffer_init(&r->counters, sizeof(zero), zero))
        return false;
    gpu_buffer_upload(&r->counters, 0, sizeof(zero), zero);
    r->counting = true;
    return true;
}

bool renderer_counts(struct renderer *r, struct render_counts *out)
{
    memset(out, 0, sizeof(*out));
    if (!r->counters.id)
        return false;
    uint32_t w[12];
    gpu_buffer_read(&r->counters, 0, sizeof(w), w);
    uint64_t v[6];
    for (int i = 0; i < 6; i++)
        v[i] = (uint64_t)w[2 * i] | (uint64_t)w[2 * i + 1] << 32;
    out->beta_samples = v[0];
    out->light_reads = v[1];
    out->cells_read = v[2];
    out->steps_leapt = v[3];
    out->rays = v[4];
    out->rays_marched = v[5];
    return true;
}

const struct render_stats *renderer_stats(const struct renderer *r)
{
    return &r->stats;
}

struct render_mesh *render_mesh_create(const struct render_vertex *vertices, int vertex_count,
                                       const uint32_t *indices, int index_count, bool lines,
                                       bool emissive)
{
    struct render_mesh *m = calloc(1, sizeof(*m));
    if (!m) {
        log_error("out of memory for a mesh");
        return NULL;
    }
    static const int attribs[4] = {3, 3, 4, 2};
    if (!gpu_mesh_init(&m->mesh, (const float *)vertices, vertex_count, attribs, 4, indices,
                       index_count, lines)) {
        free(m);
        return NULL;
    }
    glm_mat4_identity((vec4 *)m->model);
    m->emissive = emissive;
    m->visible = true;
    return m;
}

void render_mesh_destroy(struct render_mesh *m)
{
    if (!m)
        return;
    gpu_mesh_finish(&m->mesh);
    free(m);
}

void render_mesh_set_model(struct render_mesh *m, const float model[16])
{
    memcpy(m->model, model, sizeof(m->model));
}

void render_mesh_set_texture(struct render_mesh *m, const struct gpu_texture *texture)
{
    m->texture = texture;
}

void render_mesh_set_visible(struct render_mesh *m, bool visible)
{
    m->visible = visible;
}

bool renderer_add_mesh(struct renderer *r, struct render_mesh *m)
{
    for (int i = 0; i < r->n_meshes; i++) {
        if (r->meshes[i] == m)
            return true;
    }
    if (r->n_meshes == MAX_MESHES) {
        log_error("too many opaque meshes (at most %d)", MAX_MESHES);
        return false;
    }
    r->meshes[r->n_meshes++] = m;
    return true;
}

bool renderer_replace_mesh(struct renderer *r, struct render_mesh *old,
                           struct render_mesh *new_mesh)
{
    for (int i = 0; old && i < r->n_meshes; i++) {
        if (r->meshes[i] == old) {
            if (new_mesh) {
                r->meshes[i] = new_mesh;
                return true;
            }
            renderer_remove_mesh(r, old);
            return true;
        }
    }
    return !new_mesh || renderer_add_mesh(r, new_mesh);
}

void renderer_remove_mesh(struct renderer *r, struct render_mesh *m)
{
    for (int i = 0; i < r->n_meshes; i++) {
        if (r->meshes[i] == m) {
            memmove(&r->meshes[i], &r->meshes[i + 1],
                    sizeof(r->meshes[0]) * (size_t)(r->n_meshes - i - 1));
            r->n_meshes--;
            return;
        }
    }
}

void renderer_set_progress(struct renderer *r, struct progress *p)
{
    r->progress = p;
    r->progress_rows = 0;
}

void renderer_set_timing(struct renderer *r, struct gpu_timings *log)
{
    r->timing = log;
}

int renderer_collect_timings(struct renderer *r, bool wait)
{
    return gpu_timer_queue_collect(&r->timers, wait);
}
