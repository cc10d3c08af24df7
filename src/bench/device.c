/* anvil bench --gpu (device.h). */
#include "bench/device.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bench/bench.h"
#include "bench/scenes.h"
#include "common/log.h"
#include "config/display_config.h"
#include "display/display.h"
#include "gpu/gpu.h"
#include "light/light_gpu.h"
#include "render/render.h"

#define FRAMES_MAX 16

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median_of(double *v, int n, double *spread)
{
    qsort(v, (size_t)n, sizeof(double), compare_doubles);
    *spread = 0.5 * (v[n - 1] - v[0]);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* The HMD frame: two eyes 64 mm apart at the head of hmd.cfg's room (1.6 m up), 100 degrees
 * across and 110 degrees up and down each, the storm placed as hmd.cfg places it. */
static int hmd_views(int w, int h, struct render_view *out)
{
    struct display_navigation nav = {
        .scale = 1e-4, .origin_km = {30.0, 30.0, 0.0}, .position = {0.0, 0.0, -3.5}};
    float n[16];
    display_navigation_matrix(&nav, n);
    const double pos[3] = {0.0, 1.6, 0.0}, hpr[3] = {0.0, -15.0, 0.0};
    struct display_pose head;
    display_pose_from_euler(pos, hpr, &head);
    float eyes[2][3];
    display_pose_eyes(&head, 0.064, eyes[0], eyes[1]);
    for (int e = 0; e < 2; e++) {
        struct display_pose eye = head;
        memcpy(eye.position, eyes[e], sizeof(eye.position));
        display_pose_view(&eye, n, out[e].view);
        const float half_w = (float)(50.0 * M_PI / 180.0), half_h = (float)(55.0 * M_PI / 180.0);
        display_fov_projection(-half_w, half_w, half_h, -half_h, 0.01f, 1000.0f, out[e].proj);
        out[e].width = w;
        out[e].height = h;
    }
    return 2;
}

/* The CAVE frame: cave4.cfg's walls and eyes for its fixed head, each view W x H. */
static int cave_views(const char *dir, int w, int h, struct render_view *out)
{
    char path[PATH_MAX];
    snprintf(path, sizeof(path), "%s/cave4.cfg", dir);
    struct display_config cfg;
    if (!display_config_load(path, &cfg))
        return -1;
    struct display_pose head;
    display_pose_from_euler(cfg.head.position, cfg.head.orientation_deg, &head);
    int sizes[DISPLAY_MAX_WALLS][2];
    for (int i = 0; i < cfg.wall_count; i++)
        sizes[i][0] = w, sizes[i][1] = h;
    static struct view_set set;
    memset(&set, 0, sizeof(set));
    view_set_layout(&set, &cfg, &cfg.navigation, &head, (const int(*)[2])sizes);
    int n = 0;
    for (int i = 0; i < set.count; i++) {
        if (set.views[i].visible)
            out[n++] = set.views[i].rv;
    }
    return n;
}

bool bench_device(const struct bench_device_desc *d, struct bench_device_result *out)
{
    double start = time_now_ms();
    memset(out, 0, sizeof(*out));
    snprintf(out->device, sizeof(out->device), "%s", gpu_renderer_name());
    int frames = d->frames ? d->frames : d->quick ? 1 : 5;
    frames = frames > FRAMES_MAX ? FRAMES_MAX : frames;
    static char big[] = "scene.size=[500,500,100]";
    static char small[] = "scene.size=[64,64,32]";
    char *sets[] = {d->quick ? small : big};
    struct config cfg;
    if (!bench_scene_config("storm", NULL, false, sets, 1, &cfg))
        return false;
    int hw = d->quick ? 144 : 1440, hh = d->quick ? 160 : 1600;
    int cw = d->quick ? 128 : 1280, ch = d->quick ? 102 : 1024;
    struct ext_volume vol = {0};
    struct bench_scene sc;
    struct renderer *r = NULL;
    struct light_gpu *lg = NULL;
    struct gpu_texture target = {0};
    bool ok = false;
    log_info("bench: gpu: preparing the %dx%dx%d storm", cfg.scene.size[0], cfg.scene.size[1],
             cfg.scene.size[2]);
    if (!bench_scene_prepare("storm", &cfg, cw, ch, &vol, &sc))
        goto done;
    memcpy(out->n, vol.grid.n, sizeof(out->n));
    memcpy(out->light_n, sc.light.resolution, sizeof(out->light_n));
    r = renderer_create();
    lg = light_gpu_create();
    if (!r || !lg || !renderer_set_optics(r, &cfg.optics.params) || !renderer_set_volume(r, &vol))
        goto done;
    ext_volume_finish(&vol);
    sc.vol = NULL;
    struct render_view views[2][DISPLAY_MAX_VIEWS];
    int counts[2] = {hmd_views(hw, hh, views[0]), cave_views(d->displays, cw, ch, views[1])};
    if (counts[1] < 0)
        goto done;
    for (int f = 0; f < BENCH_DEVICE_FRAMES; f++) {
        const char *what = f % 2 ? "cave4" : "HMD";
        if (f < 2)
            snprintf(out->frames[f].name, sizeof(out->frames[f].name), "%s", what);
        else
            snprintf(out->frames[f].name, sizeof(out->frames[f].name), "%s, render.lod = %g", what,
                     (double)BENCH_DEVICE_LOD);
    }
    double ms, builds[FRAMES_MAX];
    for (int k = -1; k < frames; k++) { /* k = -1 compiles and allocates */
        if (!bench_timed_build(r, lg, &sc, sc.shadows, &sc.light, sc.mode, &ms))
            goto done;
        if (k >= 0)
            builds[k] = ms;
    }
    for (int f = 0; f < BENCH_DEVICE_FRAMES; f++) {
        struct bench_device_frame *fr = &out->frames[f];
        const struct render_view *vs = views[f % 2];
        int count = counts[f % 2];
        struct render_settings settings = sc.settings;
        if (f >= 2)
            settings.lod_pixels = BENCH_DEVICE_LOD;
        fr->views = count;
        fr->width = vs[0].width;
        fr->height = vs[0].height;
        double times[FRAMES_MAX];
        for (int k = -1; k < frames; k++) {
            double total = 0.0;
            for (int v = 0; v < count; v++) {
                if (!bench_timed_draw(r, &settings, &vs[v], &target, &ms))
                    goto done;
                total += ms;
            }
            if (k >= 0)
                times[k] = total;
            log_info("bench: gpu: %s frame: %.1f ms", fr->name, total);
        }
        fr->frame_ms = median_of(times, frames, &fr->frame_spread);
        /* What one frame's rays fetched. */
        struct render_counts c, sum = {0};
        for (int v = 0; v < count; v++) {
            if (!renderer_set_counting(r, true) ||
                !bench_timed_draw(r, &settings, &vs[v], &target, &ms) || !renderer_counts(r, &c))
                goto done;
            sum.beta_samples += c.beta_samples;
            sum.light_reads += c.light_reads;
            sum.rays_marched += c.rays_marched;
            sum.rays += c.rays;
        }
        renderer_set_counting(r, false);
        fr->fetches = (double)(sum.beta_samples + sum.light_reads);
        fr->rays_marched = sum.rays ? (double)sum.rays_marched / (double)sum.rays : 0.0;
    }
    double spread;
    out->build_ms = median_of(builds, frames, &spread);
    if (!render_fetch_peak(&out->peak_fetches))
        goto done;
    out->total_s = (time_now_ms() - start) / 1000.0;
    ok = true;
done:
    gpu_texture_finish(&target);
    light_gpu_destroy(lg);
    renderer_destroy(r);
    ext_volume_finish(&vol);
    return ok;
}

void bench_write_device_table(FILE *f, const struct bench_device_desc *d,
                              const struct bench_device_result *r)
{
    int frames = d->frames ? d->frames : d->quick ? 1 : 5;
    fprintf(f, "| frame | views | each, pixels | GPU ms per frame | frames per second | light "
               "map rebuild, ms | rays marched | fetches per frame | fetches per second | of "
               "the device's peak |\n|---|---:|---|---:|---:|---:|---:|---:|---:|---:|\n");
    for (int i = 0; i < BENCH_DEVICE_FRAMES; i++) {
        const struct bench_device_frame *fr = &r->frames[i];
        double per_s = fr->frame_ms > 0 ? fr->fetches / (fr->frame_ms * 1e-3) : 0.0;
        fprintf(f,
                "| %s | %d | %dx%d | %.2f ± %.2f | %.1f | %.2f | %.0f %% | %.3g | %.3g | "
                "%.0f %% |\n",
                fr->name, fr->views, fr->width, fr->height, fr->frame_ms, fr->frame_spread,
                fr->frame_ms > 0 ? 1000.0 / fr->frame_ms : 0.0, r->build_ms,
                100.0 * fr->rays_marched, fr->fetches, per_s,
                r->peak_fetches > 0 ? 100.0 * per_s / r->peak_fetches : 0.0);
    }
    fprintf(f,
            "\nThe storm on %dx%dx%d voxels (60 x 60 x 16 km), light map %dx%dx%d shared by "
            "the views of a frame, built once per frame for the rebuild column; the "
            "render.lod rows' ray steps at least %g pixels wide where a voxel looks smaller "
            "(docs/architecture.md, \"Level of detail\"); views timed with GPU timer queries (wall "
            "time around glFinish on a CPU rasteriser), "
            "medians of %d frame%s (± half their range).  "
            "Fetches: extinction samples and light map reads the rays took (counted on a "
            "frame of its own); the peak: %.3g filtered fetches per second, a fetch-only "
            "pass over a volume that stays in the texture cache.  Whole run %.0f s.  "
            "Device: %s.\n",
            r->n[0], r->n[1], r->n[2], r->light_n[0], r->light_n[1], r->light_n[2],
            (double)BENCH_DEVICE_LOD, frames, frames > 1 ? "s" : "", r->peak_fetches, r->total_s,
            r->device);
}
