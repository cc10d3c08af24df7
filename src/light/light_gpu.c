#include "light/light_gpu.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "shaders/bindings.h"

struct light_gpu {
    struct render_light hook; /* first: the renderer's bind callback gets it back */
    /* Build programs by variant: bit 0 FORWARD, bit 1 PERIPHERAL, bit 2 PHASE_MIX, bit 3
     * MULTIPLE, bit 4 LATERAL (made on first use: an effect that is off is compiled out); the
     * diffuse column pass by PHASE_MIX (bit 0) and LATERAL (bit 1). */
    struct gpu_program build[32];
    struct gpu_program diffuse_pass[4];
    struct gpu_program lateral_pass;
    struct gpu_texture light;   /* R32F node volume */
    struct gpu_texture diffuse; /* RG32F node volume, M and N; only with multiple scattering */
    struct gpu_texture slice;   /* RGBA32F build scratch: each slice's tau, ice share and
                                   lateral escape rates */
    struct gpu_texture rates;   /* RG32F on the volume's grid: lateral escape rates times the
                                   extinction; they depend on the volume only */
    bool have_rates;            /* rates hold the volume below */
    unsigned rates_beta;        /* its texture, identity and generation */
    uint64_t rates_volume, rates_generation;
    struct gpu_texture adding;  /* RG32F build scratch of the column pass */
    bool built_multiple;
    struct gpu_buffer columns, nodes;
    struct light_compressed kept; /* compressed mode: the columns, also on the CPU (the probe) */
    struct light_grid grid;
    struct light_cache cache;
    enum light_gpu_mode mode;
    bool have_key_mode;
    enum light_gpu_mode built_mode;
    double built_epsilon;
    size_t compressed_bytes;
    struct gpu_timer_queue timers;
    struct gpu_timings *timing; /* where build times go; NULL: untimed */
    bool last_timed;            /* the last build was timed (its CPU part: last_cpu_ms) */
    double last_cpu_ms;
    char defines[64];
};

void light_gpu_bind(const struct light_gpu *lg, const struct gpu_program *prog, bool next)
{
    gpu_uniform_mat4(prog, next ? "light_world_to_tex_next" : "light_world_to_tex",
                     lg->grid.world_to_tex);
    gpu_uniform_ivec3(prog, next ? "light_n_next" : "light_n", lg->grid.n);
    if (lg->built_multiple)
        gpu_texture_bind(&lg->diffuse,
                         next ? BIND_LIGHTMAP_TEX_DIFFUSE_NEXT : BIND_LIGHTMAP_TEX_DIFFUSE);
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
    snprintf(defines, sizeof(defines), "#define FORWARD %d\n#define PERIPHERAL %d\n"
             "#define PHASE_MIX %d\n#define MULTIPLE %d\n#define LATERAL %d\n", v & 1,
             (v >> 1) & 1, (v >> 2) & 1, (v >> 3) & 1, (v >> 4) & 1);
    if (!gpu_program_init(&lg->build[v], "light_build.comp", defines))
        return NULL;
    return &lg->build[v];
}

/* The diffuse column pass: its only variant is the ice/water mix (the loss shares the forward
 * terms leave come as uniforms). */
static const struct gpu_program *diffuse_program(struct light_gpu *lg, bool mix, bool lateral)
{
    int v = (mix ? 1 : 0) | (lateral ? 2 : 0);
    if (lg->diffuse_pass[v].id)
        return &lg->diffuse_pass[v];
    char defines[64];
    snprintf(defines, sizeof(defines), "#define PHASE_MIX %d\n#define LATERAL %d\n", v & 1,
             v >> 1);
    if (!gpu_program_init(&lg->diffuse_pass[v], "light_diffuse.comp", defines))
        return NULL;
    return &lg->diffuse_pass[v];
}

/* The lateral escape rates of the volume (light_lateral.comp): one pass along x, one along
 * y, one invocation per row. */
static bool build_rates(struct light_gpu *lg, const struct light_gpu_source *src)
{
    const int *n = src->grid->n;
    bool same_size = lg->rates.id && memcmp(lg->rates.size, n, 3 * sizeof(int)) == 0;
    if (same_size && lg->have_rates && lg->rates_beta == src->beta->id &&
        lg->rates_volume == src->volume_id && lg->rates_generation == src->generation)
        return true; /* a new sun, the same volume: the rates stand */
    lg->have_rates = false;
    if (!same_size) {
        gpu_texture_finish(&lg->rates);
        if (!gpu_texture_init(&lg->rates, 3, n, GPU_RG32F, NULL))
            return false;
    }
    if (!lg->lateral_pass.id && !gpu_program_init(&lg->lateral_pass, "light_lateral.comp", ""))
        return false;
    const struct gpu_program *p = &lg->lateral_pass;
    gpu_uniform_ivec3(p, "vol_n", n);
    gpu_uniform_float(p, "clear_beta", LIGHT_CLEAR_BETA);
    gpu_texture_bind(src->beta, BIND_LATERAL_TEX_BETA);
    gpu_image_bind_rw(&lg->rates, BIND_LATERAL_IMG_RATES);
    for (int axis = 0; axis < 2; axis++) {
        gpu_uniform_int(p, "axis", axis);
        gpu_uniform_float(p, "spacing", (float)src->grid->spacing[axis]);
        gpu_dispatch(p, n[1 - axis] * n[2], 1, 1);
    }
    lg->have_rates = true;
    lg->rates_beta = src->beta->id;
    lg->rates_volume = src->volume_id;
    lg->rates_generation = src->generation;
    return true;
}

/* The variant of settings S: forward scattering, the peripheral ring, and the ice/water mix
 * (compiled out when both phases' cumulative phases are equal: the mix is then exact). */
static int build_variant(const struct light_settings *s)
{
    bool mix = !light_settings_phases_equal(s);
    return (s->forward ? 1 : 0) | (s->forward && s->peripheral ? 2 : 0) |
           ((s->forward || s->multiple) && mix ? 4 : 0) | (s->multiple ? 8 : 0) |
           (s->multiple && s->lateral ? 16 : 0);
}

struct light_gpu *light_gpu_create(void)
{
    struct light_gpu *lg = calloc(1, sizeof(*lg));
    if (!lg)
        return NULL;
    if (!build_program(lg, 7)) {
        free(lg);
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
    for (int v = 0; v < 32; v++)
        gpu_program_finish(&lg->build[v]);
    for (int v = 0; v < 4; v++)
        gpu_program_finish(&lg->diffuse_pass[v]);
    gpu_texture_finish(&lg->light);
    gpu_texture_finish(&lg->diffuse);
    light_compressed_finish(&lg->kept);
    gpu_texture_finish(&lg->slice);
    gpu_texture_finish(&lg->rates);
    gpu_program_finish(&lg->lateral_pass);
    gpu_texture_finish(&lg->adding);
    gpu_buffer_finish(&lg->columns);
    gpu_buffer_finish(&lg->nodes);
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

/* The two-stream pass down every column (light_diffuse.comp), after the beam. */
static bool build_diffuse(struct light_gpu *lg, const double sun[3],
                          const struct light_settings *s)
{
    const struct light_grid *g = &lg->grid;
    if (!node_texture(&lg->diffuse, g->n, GPU_RG32F) ||
        !node_texture(&lg->adding, g->n, GPU_RG32F))
        return false;
    const struct gpu_program *p =
        diffuse_program(lg, !light_settings_phases_equal(s), s->lateral);
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
    gpu_dispatch(p, g->n[0], g->n[1], 1);
    return true;
}

static bool build_dense(struct light_gpu *lg, const struct light_gpu_source *src,
                        const double sun[3], const struct light_settings *s)
{
    const struct light_grid *g = &lg->grid;
    if (!node_texture(&lg->light, g->n, GPU_R32F))
        return false;
    if (s->multiple) {
        if (!node_texture(&lg->slice, g->n, GPU_RGBA32F))
            return false;
    } else {
        gpu_texture_finish(&lg->diffuse);
        gpu_texture_finish(&lg->slice);
        gpu_texture_finish(&lg->adding);
    }
    if (s->multiple && s->lateral) {
        if (!build_rates(lg, src))
            return false;
    } else {
        gpu_texture_finish(&lg->rates);
        lg->have_rates = false;
    }
    const struct gpu_program *p = build_program(lg, build_variant(s));
    if (!p)
        return false;
    int substeps = s->substeps > 0 ? s->substeps : light_auto_substeps(g, src->grid);
    float vol_origin[3], inv_spacing[3];
    for (int a = 0; a < 3; a++) {
        vol_origin[a] = (float)src->grid->origin[a];
        inv_spacing[a] = (float)(1.0 / src->grid->spacing[a]);
    }
    double r = light_peripheral_offset(s->forward_angle_deg, g->step[2]);
    float per[2];
    light_grid_peripheral_taps(g, r, per);
    float cp[4] = {(float)s->cp.water_ctr, (float)s->cp.ice_ctr, (float)s->cp.water_per,
                   (float)s->cp.ice_per};
    gpu_uniform_ivec3(p, "vol_n", src->grid->n);
    gpu_uniform_vec3(p, "vol_origin", vol_origin);
    gpu_uniform_vec3(p, "vol_inv_spacing", inv_spacing);
    gpu_uniform_ivec3(p, "grid_n", g->n);
    gpu_uniform_vec3(p, "g_origin", g->origin);
    gpu_uniform_vec3(p, "g_du", g->du);
    gpu_uniform_vec3(p, "g_dv", g->dv);
    gpu_uniform_vec3(p, "g_dw", g->dw);
    gpu_uniform_int(p, "substeps", substeps);
    gpu_uniform_float(p, "dsub", (float)(g->step[2] / substeps));
    gpu_uniform_vec4(p, "cp", cp);
    gpu_uniform_vec2(p, "per_offset", per);
    gpu_texture_bind(src->beta, BIND_BUILD_TEX_BETA);
    if (s->multiple && s->lateral)
        gpu_texture_bind(&lg->rates, BIND_BUILD_TEX_RATES);
    gpu_image_bind_rw(&lg->light, BIND_BUILD_IMG_LIGHT);
    if (s->multiple)
        gpu_image_bind(&lg->slice, BIND_BUILD_IMG_SLICE, true);
    for (int k = 0; k < g->n[2]; k++) {
        gpu_uniform_int(p, "plane", k);
        gpu_dispatch(p, g->n[0], g->n[1], 1);
    }
    return !s->multiple || build_diffuse(lg, sun, s);
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
    if (lg->built_mode == LIGHT_GPU_COMPRESSED && lg->kept.columns)
        *beam = light_compressed_sample(&lg->kept, tex);
    else if (lg->light.id)
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

static bool build_compressed(struct light_gpu *lg, double epsilon)
{
    struct light_map dense; /* the compressor needs the light only: the diffuse volume stays */
    if (!read_back(lg, &dense, false))
        return false;
    struct light_compressed c;
    bool ok = light_compressed_build(&dense, epsilon, &c);
    light_map_finish(&dense);
    if (!ok)
        return false;
    size_t col_bytes = (size_t)c.grid.n[0] * c.grid.n[1] * 2 * sizeof(uint32_t);
    size_t node_bytes = c.node_count * 2 * sizeof(float);
    gpu_buffer_finish(&lg->columns);
    gpu_buffer_finish(&lg->nodes);
    ok = gpu_buffer_init(&lg->columns, col_bytes, c.columns) &&
         gpu_buffer_init(&lg->nodes, node_bytes, c.nodes);
    lg->compressed_bytes = light_compressed_bytes(&c);
    light_compressed_finish(&lg->kept);
    lg->kept = c; /* small by design: kept for light_gpu_sample */
    /* The dense volume was only the build's scratch: give its memory back. */
    gpu_texture_finish(&lg->light);
    return ok;
}

bool light_gpu_update(struct light_gpu *lg, const struct light_gpu_source *src,
                      const double sun[3], const struct light_settings *settings,
                      enum light_gpu_mode mode, bool *built)
{
    if (built)
        *built = false;
    struct light_key key;
    light_key_init(&key, src->grid, sun, src->volume_id, src->generation, settings);
    bool stale = light_cache_stale(&lg->cache, &key) || !lg->have_key_mode ||
                 lg->built_mode != mode ||
                 (mode == LIGHT_GPU_COMPRESSED && lg->built_epsilon != settings->epsilon);
    if (!stale)
        return true;
    if (!light_grid_init(&lg->grid, sun, src->grid, settings->resolution, settings->grid))
        return false;
    double cpu_start = time_now_ms();
    struct gpu_timings *log = lg->timing;
    if (log)
        gpu_timer_queue_begin(&lg->timers);
    bool ok = build_dense(lg, src, sun, settings);
    unsigned number = log ? gpu_timer_queue_end(&lg->timers, log) : 0;
    lg->last_timed = number != 0;
    lg->last_cpu_ms = 0.0;
    if (ok && mode == LIGHT_GPU_COMPRESSED) {
        /* The read-back waits for the GPU anyway: the CPU compresses what it built. */
        double start = time_now_ms();
        ok = build_compressed(lg, settings->epsilon);
        lg->last_cpu_ms = time_now_ms() - start;
        if (number)
            gpu_timings_add(log, number, lg->last_cpu_ms);
    } else {
        gpu_buffer_finish(&lg->columns);
        gpu_buffer_finish(&lg->nodes);
        lg->compressed_bytes = 0;
    }
    if (!ok) {
        light_cache_invalidate(&lg->cache);
        return false;
    }
    /* The cache keeps the CPU time of the update; the GPU's arrives in the timing log. */
    light_cache_built(&lg->cache, &key, time_now_ms() - cpu_start);
    lg->have_key_mode = true;
    lg->built_mode = mode;
    lg->built_epsilon = settings->epsilon;
    lg->built_multiple = settings->multiple;
    snprintf(lg->defines, sizeof(lg->defines), "#define LIGHTMAP %d\n#define MULTIPLE %d\n",
             mode == LIGHT_GPU_DENSE ? 1 : 2, settings->multiple ? 1 : 0);
    if (built)
        *built = true;
    return true;
}

const struct render_light *light_gpu_render_light(struct light_gpu *lg)
{
    return &lg->hook;
}

unsigned light_gpu_builds(const struct light_gpu *lg)
{
    return lg->cache.builds;
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
    *ms = lg->timers.last_ms + lg->last_cpu_ms;
    return true;
}

void light_gpu_bytes(const struct light_gpu *lg, size_t *dense, size_t *compressed)
{
    /* What the dense volume takes (or would take, in compressed mode, for comparison). */
    size_t nodes = (size_t)lg->grid.n[0] * lg->grid.n[1] * lg->grid.n[2];
    size_t diffuse = lg->built_multiple ? 2 * nodes * sizeof(float) : 0;
    *dense = nodes * sizeof(float) + diffuse;
    *compressed = lg->compressed_bytes ? lg->compressed_bytes + diffuse : 0;
}
