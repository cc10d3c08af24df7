/* What the eye pass and the light build cost as the volume grows and empties (scale.h). */
#include "bench/scale.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bench/scenes.h"
#include "common/log.h"
#include "gpu/gpu.h"
#include "light/light_gpu.h"
#include "render/image.h"
#include "render/render.h"

#define ROUNDS_MAX 16

struct scene_state {
    struct ext_volume vol;
    struct bench_scene sc;
    struct renderer *r;
    struct light_gpu *lg;
    double view[ROUNDS_MAX], noskip[ROUNDS_MAX], large[ROUNDS_MAX], build[ROUNDS_MAX];
    double out_cpu[ROUNDS_MAX], out_gpu[ROUNDS_MAX];
};

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median_of(const double *v, int n)
{
    double w[ROUNDS_MAX];
    memcpy(w, v, sizeof(double) * (size_t)n);
    qsort(w, (size_t)n, sizeof(double), compare_doubles);
    return n % 2 ? w[n / 2] : 0.5 * (w[n / 2 - 1] + w[n / 2]);
}

/* The config of scene KIND. */
static bool scene_config(const struct bench_scale_desc *d, enum bench_scale_kind kind,
                         struct config *cfg, char *name, size_t name_size)
{
    static char empty[] = "scene.kind=empty";
    static char big[] = "scene.size=[500,500,100]";
    static char big_quick[] = "scene.size=[96,96,48]";
    static char compressed[] = "lightmap.mode=compressed";
    static char epsilon[] = "lightmap.epsilon=0.00392156862745098";
    static char half[] = "render.precision=half";
    static char lod[] = "render.lod=" BENCH_SCALE_LOD_PIXELS;
    char *sets[2];
    int n = 0;
    const char *scene = "storm";
    if (kind == BENCH_SCALE_EMPTY)
        sets[n++] = empty;
    else if (kind == BENCH_SCALE_LARGE || kind == BENCH_SCALE_LARGE_LOD)
        sets[n++] = d->quick ? big_quick : big;
    else if (kind == BENCH_SCALE_COMPRESSED)
        sets[n++] = compressed, sets[n++] = epsilon;
    else if (kind == BENCH_SCALE_HALF)
        sets[n++] = half;
    else if (kind == BENCH_SCALE_KATRINA)
        scene = "katrina";
    if (kind == BENCH_SCALE_LOD || kind == BENCH_SCALE_LARGE_LOD)
        sets[n++] = lod;
    if (!bench_scene_config(scene, d->configs, d->quick, sets, n, cfg))
        return false;
    const int *s = cfg->scene.size;
    const char *what = kind == BENCH_SCALE_EMPTY        ? "empty box"
                       : kind == BENCH_SCALE_COMPRESSED ? "storm, compressed map (ε 1/255)"
                       : kind == BENCH_SCALE_HALF       ? "storm, half floats"
                       : kind == BENCH_SCALE_LOD || kind == BENCH_SCALE_LARGE_LOD
                           ? "storm, render.lod = " BENCH_SCALE_LOD_PIXELS ","
                           : "storm";
    if (kind == BENCH_SCALE_KATRINA)
        snprintf(name, name_size, "Katrina sample");
    else
        snprintf(name, name_size, "%s %dx%dx%d", what, s[0], s[1], s[2]);
    return true;
}

/* The picture of scene ST once, untimed. */
static bool picture(struct scene_state *st, struct image *img)
{
    struct gpu_texture t = {0};
    double ms;
    bool ok = bench_timed_draw(st->r, &st->sc.settings, &st->sc.view, &t, &ms) &&
              renderer_read(&t, img);
    gpu_texture_finish(&t);
    return ok;
}

/* RMS of A - B over the RMS of B, colour channels; *WORST the largest |A - B| over B's
 * largest value. */
static double rms_error(const struct image *a, const struct image *b, double *worst)
{
    double d = 0.0, s = 0.0, big = 0.0, top = 0.0;
    for (size_t i = 0; i < (size_t)a->width * a->height * 4; i++) {
        if (i % 4 == 3)
            continue;
        double e = (double)a->rgba[i] - b->rgba[i];
        d += e * e;
        s += (double)b->rgba[i] * b->rgba[i];
        big = fmax(big, fabs(e));
        top = fmax(top, fabs((double)b->rgba[i]));
    }
    *worst = top > 0.0 ? big / top : 0.0;
    return s > 0.0 ? sqrt(d / s) : 0.0;
}

static bool counted_draw(struct scene_state *st, bool skip, struct render_counts *out)
{
    struct render_settings s = st->sc.settings;
    s.no_skip = !skip;
    struct gpu_texture target = {0};
    double ms;
    bool ok = renderer_set_counting(st->r, true) &&
              bench_timed_draw(st->r, &s, &st->sc.view, &target, &ms) &&
              renderer_counts(st->r, out);
    renderer_set_counting(st->r, false);
    gpu_texture_finish(&target);
    return ok;
}

static double clear_share(const struct render_cells *c)
{
    float *v = render_cells_read(c);
    if (!v)
        return 0.0;
    size_t n0 = (size_t)c->dims[0][0] * c->dims[0][1] * c->dims[0][2], clear = 0;
    for (size_t i = 0; i < n0; i++)
        clear += v[i] <= 0.0f;
    free(v);
    return n0 ? (double)clear / (double)n0 : 0.0;
}

/* Round K's times of turning the large view T into 8-bit pixels both ways. */
static bool output_times(struct scene_state *s, const struct gpu_texture *t, int k)
{
    size_t n = (size_t)t->size[0] * t->size[1];
    uint8_t *bytes = malloc(n * 4);
    struct image img = {0};
    if (!bytes)
        return false;
    gpu_finish();
    double t0 = time_now_ms();
    bool ok = renderer_read(t, &img);
    for (size_t i = 0; ok && i < n; i++)
        for (int c = 0; c < 4; c++)
            bytes[4 * i + c] = c < 3 ? image_tonemap(img.rgba[4 * i + c], 1.0f) : 255;
    double t1 = time_now_ms();
    ok = ok && renderer_tonemap_read(s->r, t, 1.0f, bytes, NULL);
    double t2 = time_now_ms();
    s->out_cpu[k] = t1 - t0;
    s->out_gpu[k] = t2 - t1;
    image_finish(&img);
    free(bytes);
    return ok;
}

bool bench_scale(const struct bench_scale_desc *d, struct bench_scale_row *rows, int *n_rows)
{
    int w = d->width ? d->width : d->quick ? 160 : 640;
    int h = d->height ? d->height : d->quick ? 120 : 480;
    int rounds = d->rounds ? d->rounds : d->quick ? 1 : 5;
    rounds = rounds > ROUNDS_MAX ? ROUNDS_MAX : rounds;
    int lw = d->quick ? 320 : 1280, lh = d->quick ? 256 : 1024;
    struct scene_state st[BENCH_SCALE_SCENES];
    memset(st, 0, sizeof(st));
    memset(rows, 0, sizeof(*rows) * BENCH_SCALE_SCENES);
    int n = 0;
    bool ok = false;
    for (int i = 0; i < BENCH_SCALE_SCENES; i++) {
        struct config cfg;
        char name[64];
        enum bench_scale_kind kind = (enum bench_scale_kind)i;
        if (!scene_config(d, kind, &cfg, name, sizeof(name)))
            goto done;
        if (kind == BENCH_SCALE_KATRINA) {
            const char *missing = d->quick ? "" : bench_scene_missing_data(&cfg);
            if (missing) {
                if (missing[0])
                    log_warn("bench: %s not found: the Katrina scene is left out", missing);
                continue;
            }
        }
        struct scene_state *s = &st[n];
        struct bench_scale_row *row = &rows[n];
        n++;
        snprintf(row->name, sizeof(row->name), "%s", name);
        row->kind = kind;
        log_info("bench: scale: preparing %s", name);
        if (!bench_scene_prepare(name, &cfg, w, h, &s->vol, &s->sc))
            goto done;
        if (kind == BENCH_SCALE_EMPTY) {
            /* The empty box keeps the storm's effects: its light map and all they compile. */
            const struct bench_scene *storm = &st[0].sc;
            s->sc.settings = storm->settings;
            s->sc.light = storm->light;
            s->sc.shadows = storm->shadows;
            s->sc.mode = storm->mode;
        }
        s->r = renderer_create();
        s->lg = light_gpu_create();
        if (!s->r || !s->lg)
            goto done;
        bool half = cfg.render.precision == PRECISION_HALF;
        renderer_set_half(s->r, half);
        light_gpu_set_half(s->lg, half);
        if (!renderer_set_optics(s->r, &cfg.optics.params) || !renderer_set_volume(s->r, &s->vol))
            goto done;
        const struct render_stats *rs = renderer_stats(s->r);
        row->upload_ms = rs->upload_ms;
        row->upload_bytes = (double)rs->upload_bytes;
        memcpy(row->n, s->vol.grid.n, sizeof(row->n));
        memcpy(row->light_n, s->sc.light.resolution, sizeof(row->light_n));
        row->shadows = s->sc.shadows;
        row->multiple = s->sc.light.multiple;
        row->lateral = s->sc.light.multiple && s->sc.light.lateral;
        row->cells_clear = clear_share(renderer_cells(s->r));
        /* The CPU volume is no longer needed: the renderer holds it. */
        ext_volume_finish(&s->vol);
        s->sc.vol = NULL;
    }
    /* Warm up (compile every variant, allocate), and count what one view's rays do. */
    for (int i = 0; i < n; i++) {
        struct scene_state *s = &st[i];
        double ms;
        struct gpu_texture t = {0};
        struct render_settings noskip = s->sc.settings;
        noskip.no_skip = true;
        struct render_view large = s->sc.view;
        large.width = lw;
        large.height = lh;
        bool good =
            bench_timed_build(s->r, s->lg, &s->sc, s->sc.shadows, &s->sc.light, s->sc.mode, &ms) &&
            bench_timed_draw(s->r, &s->sc.settings, &s->sc.view, &t, &ms) &&
            bench_timed_draw(s->r, &noskip, &s->sc.view, &t, &ms) &&
            bench_timed_draw(s->r, &s->sc.settings, &large, &t, &ms) &&
            (rows[i].kind != BENCH_SCALE_STORM || output_times(s, &t, 0)) &&
            counted_draw(s, true, &rows[i].counts) &&
            counted_draw(s, false, &rows[i].counts_noskip);
        gpu_texture_finish(&t);
        if (!good)
            goto done;
        size_t dense, compressed;
        light_gpu_bytes(s->lg, &dense, &compressed);
        rows[i].light_bytes = (double)(compressed ? compressed : dense);
    }
    /* The compressed and half-float storms against the storm's picture, the storms with a
     * level of detail against the same storm's without it. */
    for (int i = 1; i < n; i++) {
        enum bench_scale_kind kind = rows[i].kind, of = BENCH_SCALE_STORM;
        if (kind == BENCH_SCALE_LARGE_LOD)
            of = BENCH_SCALE_LARGE;
        else if (kind != BENCH_SCALE_COMPRESSED && kind != BENCH_SCALE_HALF &&
                 kind != BENCH_SCALE_LOD)
            continue;
        int j = 0;
        while (j < n && rows[j].kind != of)
            j++;
        struct image ref = {0}, img = {0};
        bool good = j < n && picture(&st[j], &ref) && picture(&st[i], &img);
        if (good)
            rows[i].image_error = rms_error(&img, &ref, &rows[i].image_max);
        image_finish(&img);
        image_finish(&ref);
        if (!good)
            goto done;
    }
    for (int k = 0; k < rounds; k++) {
        for (int i = 0; i < n; i++) {
            struct scene_state *s = &st[i];
            struct gpu_texture t = {0};
            struct render_settings noskip = s->sc.settings;
            noskip.no_skip = true;
            struct render_view large = s->sc.view;
            large.width = lw;
            large.height = lh;
            bool good = bench_timed_build(s->r, s->lg, &s->sc, s->sc.shadows, &s->sc.light,
                                          s->sc.mode, &s->build[k]) &&
                        bench_timed_draw(s->r, &s->sc.settings, &s->sc.view, &t, &s->view[k]) &&
                        bench_timed_draw(s->r, &noskip, &s->sc.view, &t, &s->noskip[k]) &&
                        bench_timed_draw(s->r, &s->sc.settings, &large, &t, &s->large[k]);
            if (good && rows[i].kind == BENCH_SCALE_STORM && !output_times(s, &t, k))
                good = false;
            gpu_texture_finish(&t);
            if (!good)
                goto done;
            log_info("bench: scale: %s round %d: view %.0f ms (%.0f without skipping), "
                     "%dx%d %.0f ms, build %.0f ms",
                     rows[i].name, k + 1, s->view[k], s->noskip[k], lw, lh, s->large[k],
                     s->build[k]);
        }
    }
    for (int i = 0; i < n; i++) {
        rows[i].view_ms = median_of(st[i].view, rounds);
        rows[i].view_noskip_ms = median_of(st[i].noskip, rounds);
        rows[i].large_ms = median_of(st[i].large, rounds);
        rows[i].build_ms = median_of(st[i].build, rounds);
        if (rows[i].kind == BENCH_SCALE_STORM) {
            rows[i].output_cpu_ms = median_of(st[i].out_cpu, rounds);
            rows[i].output_gpu_ms = median_of(st[i].out_gpu, rounds);
        }
    }
    ok = true;
done:
    for (int i = 0; i < BENCH_SCALE_SCENES; i++) {
        light_gpu_destroy(st[i].lg);
        renderer_destroy(st[i].r);
        ext_volume_finish(&st[i].vol);
    }
    *n_rows = n;
    return ok;
}

static double per_pixel(uint64_t v, const struct render_counts *c)
{
    return c->rays ? (double)v / (double)c->rays : 0.0;
}

void bench_write_scale_table(FILE *f, const struct bench_scale_desc *d,
                             const struct bench_scale_row *rows, int n, const char *device)
{
    int w = d->width ? d->width : d->quick ? 160 : 640;
    int h = d->height ? d->height : d->quick ? 120 : 480;
    int rounds = d->rounds ? d->rounds : d->quick ? 1 : 5;
    int lw = d->quick ? 320 : 1280, lh = d->quick ? 256 : 1024;
    fprintf(f,
            "| scene | clear cells | view %dx%d, ms | without skipping, ms | skipping buys | "
            "rays marched | β samples / pixel | without | light reads / pixel | cells read "
            "/ pixel | steps leapt / pixel | view %dx%d, ms | light build, ms | build ÷ "
            "%dx%d view | light map, KiB | picture off the reference's | upload, ms | upload, "
            "MiB |\n"
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
            "---:|---:|\n",
            w, h, lw, lh, lw, lh);
    for (int i = 0; i < n; i++) {
        const struct bench_scale_row *r = &rows[i];
        char err[48] = "";
        if (r->kind == BENCH_SCALE_COMPRESSED || r->kind == BENCH_SCALE_HALF ||
            r->kind == BENCH_SCALE_LOD || r->kind == BENCH_SCALE_LARGE_LOD)
            snprintf(err, sizeof(err), "%.2f %% (at most %.1f %%)", 100.0 * r->image_error,
                     100.0 * r->image_max);
        fprintf(f, "| %s | %.0f %% | %.0f | %.0f | %.1fx | %.0f %% | %.1f | %.1f | %.1f | %.2f | "
                   "%.1f | %.0f | %.0f | %.2f | %.0f | %s | %.0f | %.1f |\n",
                r->name, 100.0 * r->cells_clear, r->view_ms, r->view_noskip_ms,
                r->view_ms > 0 ? r->view_noskip_ms / r->view_ms : 0.0,
                100.0 * per_pixel(r->counts.rays_marched, &r->counts),
                per_pixel(r->counts.beta_samples, &r->counts),
                per_pixel(r->counts_noskip.beta_samples, &r->counts_noskip),
                per_pixel(r->counts.light_reads, &r->counts),
                per_pixel(r->counts.cells_read, &r->counts),
                per_pixel(r->counts.steps_leapt, &r->counts), r->large_ms, r->build_ms,
                r->large_ms > 0 ? r->build_ms / r->large_ms : 0.0, r->light_bytes / 1024.0, err,
                r->upload_ms, r->upload_bytes / (1024.0 * 1024.0));
    }
    fprintf(f, "\n");
    const struct bench_scale_row *storm = &rows[0];
    for (int i = 1; i < n; i++) {
        const struct bench_scale_row *r = &rows[i];
        if (r->kind == BENCH_SCALE_EMPTY)
            fprintf(f, "- The empty box's view ÷ the storm's: **%.3f** (%.3f without "
                       "skipping).\n",
                    r->view_ms / storm->view_ms, r->view_noskip_ms / storm->view_noskip_ms);
        else if (r->kind == BENCH_SCALE_LARGE)
            fprintf(f, "- The %dx%dx%d storm's view ÷ the %dx%dx%d storm's at %dx%d: **%.2f** "
                       "(%.2f without skipping).\n",
                    r->n[0], r->n[1], r->n[2], storm->n[0], storm->n[1], storm->n[2], w, h,
                    r->view_ms / storm->view_ms, r->view_noskip_ms / storm->view_noskip_ms);
    }
    /* With a level of detail: the large storm against the small one, both with it and the
     * small one without. */
    const struct bench_scale_row *lod = NULL, *large_lod = NULL;
    for (int i = 0; i < n; i++) {
        if (rows[i].kind == BENCH_SCALE_LOD)
            lod = &rows[i];
        else if (rows[i].kind == BENCH_SCALE_LARGE_LOD)
            large_lod = &rows[i];
    }
    if (lod && large_lod && lod->view_ms > 0.0)
        fprintf(f,
                "- With render.lod = %s: the %dx%dx%d storm's view ÷ the %dx%dx%d storm's "
                "at %dx%d: **%.2f** with it on both, %.2f against the small storm without "
                "it; the pictures %.2f %% and %.2f %% (RMS) off the same storms' without it.\n",
                BENCH_SCALE_LOD_PIXELS, large_lod->n[0], large_lod->n[1], large_lod->n[2],
                lod->n[0], lod->n[1], lod->n[2], w, h, large_lod->view_ms / lod->view_ms,
                large_lod->view_ms / storm->view_ms, 100.0 * large_lod->image_error,
                100.0 * lod->image_error);
    for (int i = 0; i < n; i++) {
        const struct bench_scale_row *r = &rows[i];
        if (r->kind == BENCH_SCALE_STORM || r->kind == BENCH_SCALE_LARGE)
            fprintf(f, "- The light build ÷ one %dx%d view, %dx%dx%d storm: **%.2f**.\n", lw, lh,
                    r->n[0], r->n[1], r->n[2], r->large_ms > 0 ? r->build_ms / r->large_ms : 0.0);
    }
    fprintf(f, "- A %dx%d view into 8-bit pixels for a PNG: read back in floats and tone-mapped "
               "on the CPU %.0f ms, tone-mapped on the GPU and read back in bytes %.0f ms "
               "(**%.2f**).\n",
            lw, lh, storm->output_cpu_ms, storm->output_gpu_ms,
            storm->output_cpu_ms > 0 ? storm->output_gpu_ms / storm->output_cpu_ms : 0.0);
    fprintf(f, "\nLight maps: ");
    for (int i = 0; i < n; i++) {
        const struct bench_scale_row *r = &rows[i];
        fprintf(f, "%s%s %dx%dx%d%s%s", i ? "; " : "", r->name, r->light_n[0], r->light_n[1],
                r->light_n[2], r->multiple ? ", diffuse light" : "",
                r->lateral ? " with lateral escape" : "");
    }
    fprintf(f, ".  Views from the configs' cameras (the default storm's camera for the storm "
               "boxes), medians of %d interleaved round%s, every time waited for (glFinish).  "
               "Device: %s.\n",
            rounds, rounds > 1 ? "s" : "", device);
}
