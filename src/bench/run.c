/* anvil bench's work: the views benchmark, the quality sweep and the experiments, written
 * into one folder (run.h). */
#include "bench/run.h"

#include <assert.h>
#include <libgen.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bench/bench.h"
#include "bench/device.h"
#include "bench/experiments.h"
#include "bench/cluster.h"
#include "bench/movie.h"
#include "bench/paraview.h"
#include "bench/load.h"
#include "bench/playback.h"
#include "bench/scale.h"
#include "bench/tables.h"
#include "common/log.h"
#include "common/progress.h"
#include "config/config.h"
#include "gpu/gpu.h"
#include "light/light_gpu.h"
#include "render/render.h"

void bench_options_defaults(struct bench_options *o)
{
    memset(o, 0, sizeof(*o));
    o->views = o->quality = o->movie = o->scale = o->cluster = true;
}

__attribute__((format(printf, 2, 3))) static void echo(const struct bench_options *o,
                                                       const char *fmt, ...)
{
    if (!o->report)
        return;
    va_list ap;
    va_start(ap, fmt);
    vfprintf(o->report, fmt, ap);
    va_end(ap);
}

/* Writes BUF (LEN bytes) to DIR/NAME, atomically. */
static bool write_text(const struct bench_options *o, const char *name, const char *buf,
                       size_t len)
{
    char path[PATH_MAX];
    snprintf(path, sizeof(path), "%s/%s", o->out, name);
    bool ok = file_write_atomic(path, buf, len);
    if (ok)
        echo(o, "wrote %s\n", path);
    return ok;
}

/* ---- views ------------------------------------------------------------------------------ */

/* The views benchmark at one image size W x H into OUT (the folder of ParaView's side). */
static bool views_at(const struct bench_options *o, const char *device, struct renderer *r,
                     struct light_gpu *lg, int w, int h, const char *out, FILE *table)
{
    struct config cfg;
    char *extra[] = {"render.ground_on=false"};
    if (!bench_scene_config("storm", o->configs, o->quick, extra, 1, &cfg))
        return false;
    int repeats = o->quick ? 1 : 3;
    struct ext_volume vol = {0};
    struct bench_scene sc;
    bool ok = bench_scene_prepare("storm", &cfg, w, h, &vol, &sc) &&
              renderer_set_optics(r, &cfg.optics.params) && renderer_set_volume(r, &vol);
    static const int counts[] = {1, 2, 8, 12};
    struct bench_views_row rows[4];
    ok = ok && bench_views(r, lg, &sc, counts, 4, w, h, repeats, rows);
    if (!ok) {
        ext_volume_finish(&vol);
        return false;
    }
    fprintf(table, "\n### %d × %d\n\n", w, h);
    bench_write_views_table(table, &sc, rows, 4, w, h, repeats, device);
    if (o->report)
        bench_write_views_summary(o->report, rows, 4, device);
    if (o->paraview) {
        struct bench_paraview_desc pd = {
            .script = o->paraview_script,
            .cache_dir = o->cache,
            .out_dir = out,
            .sun_azimuth_deg = cfg.light.azimuth_deg,
            .sun_elevation_deg = cfg.light.elevation_deg,
            .width = w,
            .height = h,
            .repeats = repeats,
            .report = o->report,
        };
        ok = bench_make_dir(out) && bench_paraview_views(&pd, &vol, rows, 4);
    }
    ext_volume_finish(&vol);
    return ok;
}

/* The views benchmark at 160 x 120 and 640 x 480 (quick: 64 x 48), into views-table.md;
 * ParaView's side of the second size goes to OUT/640x480/. */
static bool run_views(const struct bench_options *o, const char *device, struct renderer *r,
                      struct light_gpu *lg)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    bench_table_head(f, o->quick, "views");
    bool ok;
    if (o->quick) {
        ok = views_at(o, device, r, lg, 64, 48, o->out, f);
    } else {
        char second[PATH_MAX];
        snprintf(second, sizeof(second), "%s/640x480", o->out);
        ok = views_at(o, device, r, lg, 160, 120, o->out, f) &&
             views_at(o, device, r, lg, 640, 480, second, f);
    }
    fclose(f);
    ok = ok && write_text(o, "views-table.md", buf, len);
    free(buf);
    return ok;
}

/* ---- quality ---------------------------------------------------------------------------- */

/* Writes IMG to DIR/NAME-WHAT.pfm.  False, logged, on a failed write. */
static bool write_pfm(const char *dir, const char *name, const char *what, const struct image *img)
{
    char path[PATH_MAX];
    snprintf(path, sizeof(path), "%s/%s-%s.pfm", dir, name, what);
    return image_write_pfm(img, path);
}

/* --images: scene NAME's reference and its standard error, and the pictures of its default
 * and of the 3-D diffusion tier (when the sweep has it), as the sweep compares them. */
static bool write_images(const char *dir, const char *name, struct renderer *r,
                         struct light_gpu *lg, const struct bench_scene *sc,
                         const struct bench_variant *variants, int n, const struct image *ref,
                         const struct image *err)
{
    if (!bench_make_dir(dir))
        return false;
    bool ok =
        write_pfm(dir, name, "reference", ref) && write_pfm(dir, name, "reference.stderr", err);
    for (int i = 0; ok && i < n; i++) {
        bool volume = bench_is_volume_tier(&variants[i]) && !variants[i].is_default;
        if (!variants[i].is_default && !volume)
            continue;
        struct image img = {0};
        ok = bench_render(r, lg, sc, &variants[i], &img) &&
             write_pfm(dir, name, volume ? "volume" : "default", &img);
        image_finish(&img);
    }
    return ok;
}

/* The sweep around the defaults of scene NAME (its config CFG) into OUT: the Monte Carlo
 * reference, the renderer's own converged image, every variant's error and timings, the
 * pooled timings and the Pareto front. */
static bool sweep_scene(const struct bench_options *o, const char *name, const struct config *cfg,
                        struct renderer *r, struct light_gpu *lg, struct bench_scene_results *out)
{
    int w = o->quick ? 48 : 96, h = o->quick ? 36 : 72;
    struct ext_volume vol = {0};
    struct bench_scene sc;
    struct image ref = {0}, err = {0}, self = {0};
    bool ok = false;
    if (!bench_scene_prepare(name, cfg, w, h, &vol, &sc))
        goto done;
    bool cached = false;
    /* The ball is cheap to trace (0.2 s at 256 samples on 2 cores) and its picture faint: at
     * the base count its reference's noise is as large as the errors being compared, so it
     * gets 64 times the samples (an eighth of the noise). */
    int spp = strcmp(name, "sphere") == 0 ? 64 * o->spp : o->spp;
    out->spp = spp;
    if (!bench_reference(&sc, spp, o->cache, &ref, &err, &cached))
        goto done;
    double noise = 0.0;
    for (int i = 0; i < w * h; i++)
        for (int c = 0; c < 3; c++)
            noise += (double)err.rgba[4 * i + c] * err.rgba[4 * i + c];
    out->sigma = sqrt(noise / (3.0 * w * h));
    if (!renderer_set_optics(r, &cfg->optics.params) || !renderer_set_volume(r, &vol))
        goto done;
    struct bench_variant variants[BENCH_MAX_VARIANTS];
    int n = bench_variants(&sc, o->quick, variants, BENCH_MAX_VARIANTS);
    /* The renderer's own model converged: finest ray step and light map, default knobs. */
    struct bench_variant fine = variants[0];
    float voxel = (float)fmin(vol.grid.spacing[0], fmin(vol.grid.spacing[1], vol.grid.spacing[2]));
    fine.step_m = 0.125f * voxel;
    fine.mode = LIGHT_GPU_DENSE;
    for (int a = 0; a < 3; a++)
        fine.light.resolution[a] = o->quick ? 128 : 256;
    if (!bench_render(r, lg, &sc, &fine, &self))
        goto done;
    snprintf(out->name, sizeof(out->name), "%s", name);
    out->n = 0;
    /* Timings round-robin over the variants: 5 builds and 5 views each (1 and 1 quick). */
    int rounds = o->quick ? 1 : 5, build_rounds = rounds;
    struct progress pr;
    char what[64];
    snprintf(what, sizeof(what), "bench %s", name);
    progress_begin(&pr, what, "run", (uint64_t)(n * (1 + rounds)));
    for (int i = 0; i < n; i++) {
        if (!bench_measure(r, lg, &sc, &variants[i], &ref, &err, &self, &out->res[i])) {
            progress_end(&pr);
            goto done;
        }
        progress_update(&pr, (uint64_t)i + 1);
    }
    out->n = n;
    if (o->images && !write_images(o->images, name, r, lg, &sc, variants, n, &ref, &err))
        goto done;
    for (int k = 0; k < rounds; k++) {
        for (int i = 0; i < n; i++) {
            if (!bench_time_once(r, lg, &sc, k < build_rounds, &out->res[i])) {
                progress_end(&pr);
                goto done;
            }
            progress_update(&pr, (uint64_t)(n * (1 + k) + i + 1));
        }
    }
    progress_end(&pr);
    for (int i = 0; i < n; i++) {
        bench_timings_finish(&out->res[i]);
        log_info("bench: %s %s %s: build %.1f ms, view %.1f ms, RMSE %.4g (%.2f sigma)", name,
                 variants[i].knob, variants[i].value, out->res[i].build_ms,
                 out->res[i].view_ms, out->res[i].rmse, out->res[i].rmse_rel);
    }
    bench_pool_timings(out->res, out->n);
    bench_pareto(out->res, out->n);
    ok = true;
done:
    image_finish(&ref);
    image_finish(&err);
    image_finish(&self);
    ext_volume_finish(&vol);
    return ok;
}

static bool run_quality(const struct bench_options *o, const char *device, struct renderer *r,
                        struct light_gpu *lg)
{
    static struct bench_scene_results scenes[BENCH_MAX_SCENES];
    int n = 0;
    for (int i = 0; i < o->n_scenes; i++) {
        /* The renderer lights the cloud with the sun only, so the comparison does too: no
         * sky (the reference would add sky light scattered by the cloud) and no ground. */
        char *extra[] = {"render.sky=[0,0,0]", "render.ground_on=false"};
        struct config cfg;
        if (!bench_scene_config(o->scenes[i], o->configs, o->quick, extra, 2, &cfg))
            return false;
        const char *missing = bench_scene_missing_data(&cfg);
        if (missing) {
            log_warn("bench: %s not found: the %s scene is left out", missing, o->scenes[i]);
            continue;
        }
        if (!sweep_scene(o, o->scenes[i], &cfg, r, lg, &scenes[n]))
            return false;
        n++;
    }
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    bench_write_accuracy_csv(f, scenes, n);
    fclose(f);
    bool ok = write_text(o, "accuracy.csv", buf, len);
    free(buf);

    f = open_memstream(&buf, &len);
    bench_table_head(f, o->quick, "quality");
    bench_write_accuracy_table(f, scenes, n, device, o->spp);
    fclose(f);
    ok = write_text(o, "accuracy-table.md", buf, len) && ok;
    echo(o, "%.*s", (int)len, buf);
    free(buf);

    const char *names[BENCH_MAX_SCENES];
    const struct bench_result *res[BENCH_MAX_SCENES];
    int counts[BENCH_MAX_SCENES];
    for (int i = 0; i < n; i++) {
        names[i] = scenes[i].name;
        res[i] = scenes[i].res;
        counts[i] = scenes[i].n;
    }
    for (int self = 0; self < 2; self++) {
        char path[PATH_MAX], title[256];
        snprintf(path, sizeof(path), "%s/accuracy%s.png", o->out, self ? "-self" : "");
        snprintf(title, sizeof(title), "%s vs time",
                 self ? "error against the converged renderer" : "error against Monte Carlo");
        if (bench_plot_png(path, title, n, names, res, counts, self))
            echo(o, "wrote %s\n", path);
        else
            ok = false;
    }
    return ok;
}

/* ---- experiments ------------------------------------------------------------------------ */

static bool run_angles(const struct bench_options *o, const char *device, struct renderer *r,
                       struct light_gpu *lg)
{
    struct bench_angles a;
    struct bench_experiments_desc d = {.quick = o->quick, .spp = o->spp, .cache_dir = o->cache};
    if (!bench_angles_measure(r, lg, &d, &a))
        return false;
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    bench_table_head(f, o->quick, "quality");
    bench_write_angles_table(f, &a, device, o->spp);
    fclose(f);
    bool ok = write_text(o, "angles-table.md", buf, len);
    echo(o, "%.*s", (int)len, buf);
    free(buf);
    return ok;
}

/* The layer and the wall with the diffuse light volume, all on the CPU (volume-table.md). */
static bool run_volume(const struct bench_options *o)
{
    struct bench_angles a;
    struct bench_volume_timing t = {0};
    struct bench_experiments_desc d = {.quick = o->quick,
                                       .spp = o->spp,
                                       .cache_dir = o->cache,
                                       .cpu_volume = true,
                                       .timing = &t};
    if (!bench_angles_measure(NULL, NULL, &d, &a))
        return false;
    struct bench_volume_timing storm;
    int cells[3];
    if (!bench_volume_time_storm(o->configs, o->quick, &storm, cells))
        return false;
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    bench_table_head(f, o->quick, "volume");
    fprintf(f, "The default storm%s at its default light map, one CPU thread: the light map's "
               "build with the columns' diffuse pass %.0f ms, the diffuse light volume's "
               "(%d x %d x %d cells, %d conjugate gradient iterations) %.0f ms on top, %.2f "
               "times.\n\n",
            o->quick ? " (the quick run's)" : "", storm.map_ms, cells[0], cells[1], cells[2],
            storm.iterations, storm.volume_ms,
            storm.map_ms > 0.0 ? storm.volume_ms / storm.map_ms : 0.0);
    fprintf(f, "The diffuse light volume (docs/lightmap.md, \"The diffuse light volume\"): the "
               "light map's beam, its losses the source of a diffusion solve on a grid of half "
               "the volume's resolution, both drawn by a fine CPU ray march.  Over the %d "
               "scenes below the light map's CPU build (with the columns' diffuse pass) took "
               "%.0f ms and the volume's %.0f ms on top (%.2f times; %d conjugate gradient "
               "iterations in all).\n\n",
            t.builds, t.map_ms, t.volume_ms, t.map_ms > 0.0 ? t.volume_ms / t.map_ms : 0.0,
            t.iterations);
    bench_write_angles_table(f, &a, "CPU (the volume's pictures drawn by bench_volume_image)",
                             o->spp);
    /* The same with the renderer's eye pass reading the GPU's volume, where GL can be had. */
    struct gpu_context *ctx = gpu_context_create(&(struct gpu_context_desc){.backend = "egl"});
    bool ok = true;
    if (ctx) {
        struct renderer *r = renderer_create();
        struct light_gpu *lg = light_gpu_create();
        struct bench_experiments_desc g = {
            .quick = o->quick, .spp = o->spp, .cache_dir = o->cache, .volume = true};
        ok = r && lg && bench_angles_measure(r, lg, &g, &a);
        if (ok) {
            fprintf(f, "\n## The renderer with effects.multiple = \"volume\"\n\nThe same "
                       "scenes drawn by the eye pass, reading the volume the GPU built.  ");
            bench_write_angles_table(f, &a, gpu_renderer_name(), o->spp);
        }
        light_gpu_destroy(lg);
        renderer_destroy(r);
        gpu_context_destroy(ctx);
    } else {
        fprintf(f, "\n(No GL context: the renderer's pictures with the volume are left out.)\n");
    }
    fclose(f);
    if (!ok) {
        free(buf);
        return false;
    }
    ok = write_text(o, "volume-table.md", buf, len);
    echo(o, "%.*s", (int)len, buf);
    free(buf);
    return ok;
}

/* ---- scale ------------------------------------------------------------------------------ */

static bool run_scale(const struct bench_options *o, const char *device)
{
    struct bench_scale_desc d = {.quick = o->quick, .configs = o->configs};
    struct bench_scale_row rows[BENCH_SCALE_SCENES];
    int n = 0;
    if (!bench_scale(&d, rows, &n))
        return false;
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    bench_table_head(f, o->quick, "scale");
    bench_write_scale_table(f, &d, rows, n, device);
    fclose(f);
    bool ok = write_text(o, "scale-table.md", buf, len);
    echo(o, "%.*s", (int)len, buf);
    free(buf);
    return ok;
}

/* ---- load ------------------------------------------------------------------------------- */

static bool run_load(const struct bench_options *o)
{
    struct bench_load_desc d = {.quick = o->quick};
    struct bench_load_result r;
    if (!bench_load(&d, &r))
        return false;
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    bench_table_head(f, o->quick, "load");
    bench_write_load_table(f, &d, &r);
    fclose(f);
    bool ok = write_text(o, "load-table.md", buf, len);
    echo(o, "%.*s", (int)len, buf);
    free(buf);
    return ok;
}

/* ---- playback --------------------------------------------------------------------------- */

static bool run_playback(const struct bench_options *o, const char *device,
                         struct gpu_context *ctx)
{
    struct bench_playback_desc d = {.quick = o->quick, .context = ctx, .device = device};
    struct bench_playback_result r;
    if (!bench_playback(&d, &r))
        return false;
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    bench_table_head(f, o->quick, "playback");
    bench_write_playback_table(f, &d, &r);
    fclose(f);
    bool ok = write_text(o, "playback-table.md", buf, len);
    echo(o, "%.*s", (int)len, buf);
    free(buf);
    return ok;
}

/* ---- the GPU benchmark ------------------------------------------------------------------ */

static bool run_device(const struct bench_options *o)
{
    struct bench_device_desc d = {.quick = o->quick, .displays = o->displays};
    struct bench_device_result res;
    if (!bench_device(&d, &res))
        return false;
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    fprintf(f, "<!-- generated by `anvil bench%s --gpu`; do not edit by hand -->\n",
            o->quick ? " --quick" : "");
    bench_write_device_table(f, &d, &res);
    fclose(f);
    bool ok = write_text(o, "gpu-table.md", buf, len);
    echo(o, "%.*s", (int)len, buf);
    free(buf);
    return ok;
}

enum bench_status bench_run(const struct bench_options *opts)
{
    assert(opts && opts->out && opts->configs);
    assert(opts->views || opts->quality || opts->movie || opts->scale || opts->cluster ||
           opts->device || opts->load || opts->playback || opts->volume);
    assert(!(opts->cluster || opts->device) || opts->displays);
    assert(!opts->paraview || opts->paraview_script);
    struct bench_options o = *opts;
    char cache[PATH_MAX];
    if (!o.cache || !o.cache[0]) {
        char exe[PATH_MAX];
        ssize_t len = readlink("/proc/self/exe", exe, sizeof(exe) - 1);
        if (len > 0) {
            exe[len] = '\0';
            snprintf(cache, sizeof(cache), "%s/bench-cache", dirname(exe));
        } else {
            snprintf(cache, sizeof(cache), "bench-cache");
        }
        o.cache = cache;
    }
    if (!o.spp)
        o.spp = o.quick ? 32 : 256;
    if (o.n_scenes == 0) {
        for (int i = 0; i < BENCH_MAX_SCENES; i++)
            o.scenes[i] = bench_scene_names[i];
        o.n_scenes = BENCH_MAX_SCENES;
    }
    if (!bench_make_dir(o.out))
        return BENCH_FAILED;
    if (o.load && !o.views && !o.quality && !o.movie && !o.scale && !o.cluster && !o.device)
        return run_load(&o) ? BENCH_DONE : BENCH_FAILED; /* no GL needed */
    if (o.volume && !o.views && !o.quality && !o.movie && !o.scale && !o.cluster && !o.device)
        return run_volume(&o) ? BENCH_DONE : BENCH_FAILED; /* no GL needed */
    struct gpu_context *ctx = gpu_context_create(&(struct gpu_context_desc){.backend = "egl"});
    if (!ctx)
        return BENCH_NO_GPU;
    const char *device = gpu_renderer_name();
    struct renderer *r = renderer_create();
    struct light_gpu *lg = light_gpu_create();
    enum bench_status status = BENCH_FAILED;
    if (!r || !lg)
        goto done;
    if (strstr(device, "llvmpipe"))
        echo(&o, "note: %s is a CPU rasteriser; the milliseconds below are only meaningful as "
                 "ratios\n", device);
    if (o.views && !run_views(&o, device, r, lg))
        goto done;
    if (o.quality && !(run_quality(&o, device, r, lg) && run_angles(&o, device, r, lg)))
        goto done;
    if (o.scale && !run_scale(&o, device))
        goto done;
    if (o.device && !run_device(&o))
        goto done;
    if (o.playback && !run_playback(&o, device, ctx))
        goto done;
    struct bench_movie_result movie;
    if (o.movie && !bench_movie(&(struct bench_movie_desc){.quick = o.quick,
                                                           .out = o.out,
                                                           .device = device,
                                                           .context = ctx,
                                                           .report = o.report},
                                &movie))
        goto done;
    bool cluster_only = !o.views && !o.quality && !o.movie && !o.scale && !o.device;
    if (o.cluster && !cluster_only && !bench_cluster_possible())
        log_warn("bench: the cluster benchmark is left out (it needs anvil built with MPI and "
                 "mpirun on PATH: libopenmpi-dev, openmpi-bin)");
    else if (o.cluster && !bench_cluster(&(struct bench_cluster_desc){.quick = o.quick,
                                                                     .out = o.out,
                                                                     .displays = o.displays,
                                                                     .device = device,
                                                                     .report = o.report}))
        goto done;
    status = BENCH_DONE;
done:
    light_gpu_destroy(lg);
    renderer_destroy(r);
    gpu_context_destroy(ctx);
    return status;
}
