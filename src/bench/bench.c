/* The views and quality benchmarks (bench.h): sweeps, timing, errors, the reference cache. */
#include "bench/bench.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "common/log.h"
#include "reference/reference.h"
#include "render/camera.h"

/* Bump when the reference's estimator or the cache layout changes: old files are ignored. */
#define REFERENCE_CACHE_VERSION 1
#define REPEATS_MAX 32

static uint64_t generation_counter = 1000; /* forces light map rebuilds */

static float min_spacing(const struct ext_volume *vol)
{
    double m = vol->grid.spacing[0];
    for (int a = 1; a < 3; a++)
        m = fmin(m, vol->grid.spacing[a]);
    return (float)m;
}

static struct bench_variant base_variant(const struct bench_scene *sc)
{
    struct bench_variant v;
    memset(&v, 0, sizeof(v));
    v.shadows = sc->shadows;
    v.light = sc->light;
    v.mode = sc->mode;
    v.step_m = sc->settings.step_m;
    return v;
}

int bench_variants(const struct bench_scene *sc, bool quick, struct bench_variant *out, int max)
{
    int n = 0;
    float voxel = min_spacing(sc->vol);
#define ADD(...)                                                                              \
    do {                                                                                      \
        if (n < max) {                                                                        \
            out[n] = base_variant(sc);                                                        \
            struct bench_variant *v = &out[n++];                                              \
            __VA_ARGS__;                                                                      \
        }                                                                                     \
    } while (0)

    ADD(snprintf(v->knob, sizeof(v->knob), "default"); v->is_default = true;
        char step[32];
        /* Step 0 is not a length: half of what each ray takes to cross a voxel (a thick step
         * in parts of one light map node), longer than half the smallest spacing for oblique
         * rays. */
        if (sc->settings.step_m > 0)
            snprintf(step, sizeof(step), "step %.2g voxel", sc->settings.step_m / voxel);
        else
            snprintf(step, sizeof(step), "step 1/2 crossing");
        snprintf(v->value, sizeof(v->value), "%d^3 %s, %s, theta %.0f",
                 sc->light.resolution[0], sc->mode == LIGHT_GPU_DENSE ? "dense" : "compressed",
                 step, sc->light.forward_angle_deg));
    static const float steps[] = {0.25f, 1.0f, 2.0f};
    for (int i = 0; i < 3; i++)
        ADD(snprintf(v->knob, sizeof(v->knob), "ray step");
            snprintf(v->value, sizeof(v->value), "%.2g voxel", steps[i]);
            v->step_m = steps[i] * voxel);
    static const int res[] = {32, 64, 256};
    for (int i = 0; i < (quick ? 2 : 3); i++)
        ADD(snprintf(v->knob, sizeof(v->knob), "resolution");
            snprintf(v->value, sizeof(v->value), "%d^3", res[i]);
            v->light.resolution[0] = v->light.resolution[1] = v->light.resolution[2] = res[i]);
    static const double eps[] = {0.002, 0.01, 0.05};
    for (int i = 0; i < 3; i++)
        ADD(snprintf(v->knob, sizeof(v->knob), "compressed");
            snprintf(v->value, sizeof(v->value), "epsilon %g", eps[i]);
            v->mode = LIGHT_GPU_COMPRESSED; v->light.epsilon = eps[i]);
    static const double angles[] = {10.0, 30.0, 40.0};
    for (int i = 0; i < 3; i++)
        ADD(snprintf(v->knob, sizeof(v->knob), "forward angle");
            snprintf(v->value, sizeof(v->value), "theta %.0f", angles[i]);
            /* CP scales with the cone: recompute it for the new angle. */
            light_settings_set_optics(&v->light, &sc->optics, angles[i]);
            if (sc->settings.single_phase)
                light_settings_one_phase(&v->light, sc->settings.single_phase_ice));
    ADD(snprintf(v->knob, sizeof(v->knob), "peripheral"); snprintf(v->value, sizeof(v->value),
        "off"); v->light.peripheral = false);
    ADD(snprintf(v->knob, sizeof(v->knob), "forward"); snprintf(v->value, sizeof(v->value),
        "off (shadow only)"); v->light.forward = false; v->light.peripheral = false);
    ADD(snprintf(v->knob, sizeof(v->knob), "multiple"); snprintf(v->value, sizeof(v->value),
        "%s", sc->light.multiple ? "off" : "on (two-stream)");
        v->light.multiple = !sc->light.multiple);
    if (sc->light.multiple && !sc->light.volume)
        ADD(snprintf(v->knob, sizeof(v->knob), "multiple");
            snprintf(v->value, sizeof(v->value), "volume (3-D diffusion)");
            v->light.volume = true);
    struct light_grid grid;
    if (sc->light.grid == LIGHT_GRID_AUTO &&
        light_grid_init(&grid, sc->sun, &sc->vol->grid, sc->light.resolution, LIGHT_GRID_AUTO) &&
        grid.sheared)
        ADD(snprintf(v->knob, sizeof(v->knob), "light grid");
            snprintf(v->value, sizeof(v->value), "upright (not sheared)");
            v->light.grid = LIGHT_GRID_UPRIGHT);
    if (sc->light.multiple)
        ADD(snprintf(v->knob, sizeof(v->knob), "lateral escape");
            snprintf(v->value, sizeof(v->value), "%s", sc->light.lateral ? "off" : "on");
            v->light.lateral = !sc->light.lateral);
    ADD(snprintf(v->knob, sizeof(v->knob), "shadows"); snprintf(v->value, sizeof(v->value),
        "off (no light map)"); v->shadows = false);
    ADD(snprintf(v->knob, sizeof(v->knob), "combination");
        snprintf(v->value, sizeof(v->value), "64^3, step 1 voxel"); v->step_m = voxel;
        v->light.resolution[0] = v->light.resolution[1] = v->light.resolution[2] = 64);
    ADD(snprintf(v->knob, sizeof(v->knob), "combination");
        snprintf(v->value, sizeof(v->value), "64^3, step 0.5 voxel"); v->step_m = 0.5f * voxel;
        v->light.resolution[0] = v->light.resolution[1] = v->light.resolution[2] = 64);
    if (!quick)
        ADD(snprintf(v->knob, sizeof(v->knob), "combination");
            snprintf(v->value, sizeof(v->value), "256^3, step 0.25 voxel");
            v->step_m = 0.25f * voxel;
            v->light.resolution[0] = v->light.resolution[1] = v->light.resolution[2] = 256);
#undef ADD
    return n;
}

/* ---- the reference cache ------------------------------------------------------------ */

static uint64_t fnv(uint64_t h, const void *data, size_t len)
{
    const unsigned char *p = data;
    for (size_t i = 0; i < len; i++) {
        h ^= p[i];
        h *= 1099511628211ull;
    }
    return h;
}

static uint64_t reference_key(const struct bench_scene *sc, int spp)
{
    uint64_t h = 14695981039346656037ull;
    int version = REFERENCE_CACHE_VERSION;
    h = fnv(h, &version, sizeof(version));
    h = fnv(h, &spp, sizeof(spp));
    const struct grid3 *g = &sc->vol->grid;
    h = fnv(h, g->n, sizeof(g->n));
    h = fnv(h, g->origin, sizeof(g->origin));
    h = fnv(h, g->spacing, sizeof(g->spacing));
    h = fnv(h, sc->vol->beta, (size_t)g->n[0] * g->n[1] * g->n[2] * 2 * sizeof(float));
    const struct render_settings *s = &sc->settings;
    h = fnv(h, s->sun_dir, sizeof(s->sun_dir));
    h = fnv(h, s->sun_radiance, sizeof(s->sun_radiance));
    h = fnv(h, s->sky, sizeof(s->sky));
    h = fnv(h, s->ground, sizeof(s->ground));
    h = fnv(h, &s->ground_on, sizeof(s->ground_on));
    h = fnv(h, sc->view.view, sizeof(sc->view.view));
    h = fnv(h, sc->view.proj, sizeof(sc->view.proj));
    h = fnv(h, &sc->view.width, sizeof(int));
    h = fnv(h, &sc->view.height, sizeof(int));
    h = fnv(h, &sc->optics.g_ice, sizeof(double));
    h = fnv(h, &sc->optics.g_water, sizeof(double));
    return h;
}

bool bench_reference(const struct bench_scene *sc, int spp, const char *cache_dir,
                     struct image *mean, struct image *err, bool *cached)
{
    memset(mean, 0, sizeof(*mean));
    memset(err, 0, sizeof(*err));
    if (cached)
        *cached = false;
    char path[1024], err_path[1024];
    unsigned long long key = (unsigned long long)reference_key(sc, spp);
    snprintf(path, sizeof(path), "%s/ref-%s-%d-%016llx.pfm", cache_dir, sc->name, spp, key);
    snprintf(err_path, sizeof(err_path), "%s/ref-%s-%d-%016llx.stderr.pfm", cache_dir, sc->name,
             spp, key);
    struct stat st;
    if (stat(path, &st) == 0 && stat(err_path, &st) == 0) {
        if (image_read_pfm(path, mean) && image_read_pfm(err_path, err) &&
            mean->width == sc->view.width && mean->height == sc->view.height &&
            err->width == mean->width && err->height == mean->height) {
            if (cached)
                *cached = true;
            return true;
        }
        image_finish(mean);
        image_finish(err);
        log_warn("%s: unreadable or of the wrong size; rendering the reference again", path);
    }
    mkdir(cache_dir, 0777);
    struct reference_desc d;
    reference_desc_from_render(&sc->settings, &sc->optics, &d);
    struct reference *ref = reference_create(sc->vol, &d);
    if (!ref)
        return false;
    log_info("bench: reference of %s, %dx%d at %d spp (cached in %s)", sc->name, sc->view.width,
             sc->view.height, spp, cache_dir);
    double t = time_now_ms();
    struct reference_image_desc id = {.spp = spp, .threads = 0, .seed = 1};
    bool ok = reference_render(ref, &sc->view, &id, mean, err);
    reference_destroy(ref);
    if (!ok)
        return false;
    log_info("bench: reference of %s took %.1f s", sc->name, (time_now_ms() - t) / 1000.0);
    if (!image_write_pfm(mean, path) || !image_write_pfm(err, err_path))
        log_warn("bench: could not cache the reference in %s", cache_dir);
    return true;
}

/* ---- measuring ------------------------------------------------------------------------ */

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double middle(double *v, int n)
{
    qsort(v, (size_t)n, sizeof(double), compare_doubles);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* The median of V (reordered) and, in *SPREAD, 1.4826 times the median absolute deviation:
 * a standard deviation that one stalled repeat on a shared machine does not inflate. */
static double median(double *v, int n, double *spread)
{
    if (n <= 0) {
        *spread = 0.0;
        return 0.0;
    }
    double m = middle(v, n);
    double dev[n];
    for (int i = 0; i < n; i++)
        dev[i] = fabs(v[i] - m);
    *spread = 1.4826 * middle(dev, n);
    return m;
}

/* Builds the light map of V (forced: a new generation) and points R at it; *MS its time.  A
 * benchmark waits for every time it measures, build and view alike: the next measurement
 * must not overlap it. */
static bool build(struct renderer *r, struct light_gpu *lg, const struct bench_scene *sc,
                  const struct bench_variant *v, double *ms)
{
    *ms = 0.0;
    if (!v->shadows) {
        renderer_set_light(r, NULL);
        return true;
    }
    struct light_gpu_source src = {
        .beta = renderer_volume_texture(r),
        .grid = renderer_grid(r),
        .volume_id = 1,
        .generation = generation_counter++,
        .cells = renderer_cells(r),
    };
    struct gpu_timings t = {0};
    light_gpu_set_timing(lg, &t);
    bool ok = light_gpu_update(lg, &src, sc->sun, &v->light, v->mode, NULL);
    light_gpu_collect_timings(lg, true);
    light_gpu_set_timing(lg, NULL);
    if (!ok)
        return false;
    *ms = t.total_ms;
    renderer_set_light(r, light_gpu_render_light(lg));
    return true;
}

static bool draw(struct renderer *r, const struct render_settings *s,
                 const struct render_view *view, struct gpu_texture *out, double *ms);

bool bench_timed_build(struct renderer *r, struct light_gpu *lg, const struct bench_scene *sc,
                       bool shadows, const struct light_settings *settings,
                       enum light_gpu_mode mode, double *ms)
{
    struct bench_variant v = {.shadows = shadows, .light = *settings, .mode = mode};
    return build(r, lg, sc, &v, ms);
}

bool bench_timed_draw(struct renderer *r, const struct render_settings *s,
                      const struct render_view *view, struct gpu_texture *out, double *ms)
{
    return draw(r, s, view, out, ms);
}

static bool draw(struct renderer *r, const struct render_settings *s,
                 const struct render_view *view, struct gpu_texture *out, double *ms)
{
    struct gpu_timings t = {0};
    renderer_set_timing(r, &t);
    bool ok = renderer_draw(r, s, view, out);
    renderer_collect_timings(r, true);
    renderer_set_timing(r, NULL);
    *ms = t.total_ms;
    return ok;
}

static void compare(const struct image *img, const struct image *ref, const struct image *err,
                    struct bench_result *out)
{
    double sum = 0.0, worst = 0.0, noise = 0.0;
    size_t count = (size_t)img->width * img->height;
    for (size_t i = 0; i < count; i++) {
        for (int c = 0; c < 3; c++) {
            double d = (double)img->rgba[4 * i + c] - ref->rgba[4 * i + c];
            if (!isfinite(d))
                d = INFINITY;
            sum += d * d;
            worst = fmax(worst, fabs(d));
            noise += (double)err->rgba[4 * i + c] * err->rgba[4 * i + c];
        }
    }
    out->rmse = sqrt(sum / (3.0 * count));
    out->rmse_model = sqrt(fmax(sum - noise, 0.0) / (3.0 * count));
    out->max_err = worst;
    double sigma = sqrt(noise / (3.0 * count));
    out->rmse_rel = sigma > 0 ? out->rmse / sigma : INFINITY;
    out->max_rel = sigma > 0 ? out->max_err / sigma : INFINITY;
}

bool bench_measure(struct renderer *r, struct light_gpu *lg, const struct bench_scene *sc,
                   const struct bench_variant *v, const struct image *ref,
                   const struct image *ref_err, const struct image *self_ref,
                   struct bench_result *out)
{
    memset(out, 0, sizeof(*out));
    out->v = *v;
    struct render_settings s = sc->settings;
    s.step_m = v->step_m;
    double ms;
    struct gpu_texture target = {0};
    struct image img = {0};
    bool ok = build(r, lg, sc, v, &ms) && draw(r, &s, &sc->view, &target, &ms) &&
              renderer_read(&target, &img);
    if (ok && ref && ref_err)
        compare(&img, ref, ref_err, out);
    if (ok && self_ref) {
        struct bench_result self;
        compare(&img, self_ref, self_ref, &self);
        out->self_rmse = self.rmse;
    }
    image_finish(&img);
    gpu_texture_finish(&target);
    return ok;
}

bool bench_time_once(struct renderer *r, struct light_gpu *lg, const struct bench_scene *sc,
                     bool with_build, struct bench_result *out)
{
    struct render_settings s = sc->settings;
    s.step_m = out->v.step_m;
    double ms;
    struct gpu_texture target = {0};
    /* The view needs this variant's map bound: build it.  Round-robin, the previous variant
     * may have left maps of another size: an untimed build first reallocates them, so the
     * timed one is a rebuild in place, as in a session. */
    bool ok = build(r, lg, sc, &out->v, &ms);
    if (ok && with_build) {
        ok = build(r, lg, sc, &out->v, &ms);
        if (ok && out->n_build_samples < REPEATS_MAX)
            out->build_samples[out->n_build_samples++] = ms;
    }
    ok = ok && draw(r, &s, &sc->view, &target, &ms);
    if (ok && out->n_view_samples < REPEATS_MAX)
        out->view_samples[out->n_view_samples++] = ms;
    gpu_texture_finish(&target);
    return ok;
}

void bench_timings_finish(struct bench_result *out)
{
    double v[REPEATS_MAX];
    if (out->n_build_samples > 0) {
        memcpy(v, out->build_samples, sizeof(double) * out->n_build_samples);
        out->build_ms = median(v, out->n_build_samples, &out->build_spread);
    }
    if (out->n_view_samples > 0) {
        memcpy(v, out->view_samples, sizeof(double) * out->n_view_samples);
        out->view_ms = median(v, out->n_view_samples, &out->view_spread);
    }
}

bool bench_render(struct renderer *r, struct light_gpu *lg, const struct bench_scene *sc,
                  const struct bench_variant *v, struct image *out)
{
    struct render_settings s = sc->settings;
    s.step_m = v->step_m;
    struct gpu_texture target = {0};
    double ms;
    bool ok = build(r, lg, sc, v, &ms) && draw(r, &s, &sc->view, &target, &ms) &&
              renderer_read(&target, out);
    gpu_texture_finish(&target);
    return ok;
}

/* Whether A's and B's light builds do the same work: the same shader variant over the same
 * grid and storage.  The forward angle and the CP it gives are uniforms of one variant
 * (whether the two phases' terms are equal is not: it compiles the mix out), so maps that
 * differ only in them take the same time, and what their timings differ by is the machine's
 * load. */
static bool same_build_work(const struct bench_variant *a, const struct bench_variant *b)
{
    if (a->shadows != b->shadows)
        return false;
    if (!a->shadows)
        return true;
    const struct light_settings *x = &a->light, *y = &b->light;
    bool per_x = x->peripheral && x->forward, per_y = y->peripheral && y->forward;
    return a->mode == b->mode &&
           memcmp(x->resolution, y->resolution, sizeof(x->resolution)) == 0 &&
           x->forward == y->forward && per_x == per_y && x->multiple == y->multiple &&
           (!x->multiple || (x->lateral == y->lateral && x->volume == y->volume)) &&
           x->grid == y->grid &&
           x->substeps == y->substeps &&
           light_settings_phases_equal(x) == light_settings_phases_equal(y) &&
           (a->mode == LIGHT_GPU_DENSE || x->epsilon == y->epsilon);
}

bool bench_is_volume_tier(const struct bench_variant *v)
{
    return v->shadows && v->light.multiple && v->light.volume;
}

bool bench_same_work(const struct bench_variant *a, const struct bench_variant *b)
{
    return same_build_work(a, b) && a->step_m == b->step_m;
}

/* Each of RES's build (VIEW false) or view medians over the samples of every result that does
 * the same work as it (SAME).  Only the samples are read, so each result is set in turn. */
static void pool(struct bench_result *res, int n, bool view,
                 bool (*same)(const struct bench_variant *, const struct bench_variant *))
{
    for (int i = 0; i < n; i++) {
        double samples[32 * REPEATS_MAX];
        int count = 0;
        for (int j = 0; j < n; j++) {
            if (!same(&res[i].v, &res[j].v))
                continue;
            int m = view ? res[j].n_view_samples : res[j].n_build_samples;
            const double *from = view ? res[j].view_samples : res[j].build_samples;
            for (int k = 0; k < m && count < 32 * REPEATS_MAX; k++)
                samples[count++] = from[k];
        }
        if (count == 0)
            continue;
        if (view)
            res[i].view_ms = median(samples, count, &res[i].view_spread);
        else
            res[i].build_ms = median(samples, count, &res[i].build_spread);
    }
}

void bench_pool_timings(struct bench_result *res, int n)
{
    pool(res, n, false, same_build_work);
    pool(res, n, true, bench_same_work);
}

/* The relative timing noise of R against another result: the robust spread of its repeats
 * over its time, leaving out a build (BUILD_SHARED) or a view (VIEW_SHARED) whose pooled
 * median the two share, which cannot make one look faster than the other. */
static double time_noise(const struct bench_result *r, bool build_shared, bool view_shared)
{
    double t = r->build_ms + r->view_ms;
    double s = (build_shared ? 0.0 : r->build_spread) + (view_shared ? 0.0 : r->view_spread);
    return t > 0.0 ? s / t : 0.0;
}

double bench_error(const struct bench_result *r, bool self)
{
    return self ? r->self_rmse : r->rmse_model;
}

/* Time noise of a comparison: the larger of the floor and what either's repeats scattered in
 * the parts the two do not share (bench_pool_timings gives rows that do the same work one
 * median). */
static double pair_time_noise(const struct bench_result *a, const struct bench_result *b)
{
    bool build = same_build_work(&a->v, &b->v), view = bench_same_work(&a->v, &b->v);
    return fmax(BENCH_TIME_NOISE,
                fmax(time_noise(a, build, view), time_noise(b, build, view)));
}

bool bench_no_worse(const struct bench_result *b, const struct bench_result *a, bool self)
{
    double ta = a->build_ms + a->view_ms, tb = b->build_ms + b->view_ms;
    double ea = bench_error(a, self), eb = bench_error(b, self);
    return tb <= ta * (1.0 + pair_time_noise(a, b)) && eb <= ea * (1.0 + BENCH_ERROR_NOISE);
}

bool bench_beats(const struct bench_result *b, const struct bench_result *a, bool self)
{
    double ta = a->build_ms + a->view_ms, tb = b->build_ms + b->view_ms;
    double ea = bench_error(a, self), eb = bench_error(b, self);
    bool faster = tb * (1.0 + pair_time_noise(a, b)) < ta;
    bool better = eb * (1.0 + BENCH_ERROR_NOISE) < ea;
    return bench_no_worse(b, a, self) && (faster || better);
}

void bench_pareto(struct bench_result *res, int n)
{
    for (int i = 0; i < n; i++) {
        res[i].pareto = res[i].pareto_self = true;
        for (int j = 0; j < n; j++) {
            if (j != i && bench_beats(&res[j], &res[i], false))
                res[i].pareto = false;
            if (j != i && bench_beats(&res[j], &res[i], true))
                res[i].pareto_self = false;
        }
    }
}

/* ---- views -------------------------------------------------------------------------- */

bool bench_views(struct renderer *r, struct light_gpu *lg, const struct bench_scene *sc,
                 const int *counts, int n_counts, int w, int h, int repeats,
                 struct bench_views_row *out)
{
    repeats = repeats < 1 ? 1 : repeats > REPEATS_MAX ? REPEATS_MAX : repeats;
    const struct grid3 *g = &sc->vol->grid;
    double centre[3], diag = 0.0;
    for (int a = 0; a < 3; a++) {
        double size = g->n[a] * g->spacing[a];
        centre[a] = g->origin[a] + 0.5 * size;
        diag += size * size;
    }
    diag = sqrt(diag);
    struct bench_variant v = base_variant(sc);
    v.shadows = true;
    struct render_settings s = sc->settings;
    struct gpu_texture target = {0};
    bool ok = false;
    double ms;
    /* Warm up: compile, allocate. */
    if (!build(r, lg, sc, &v, &ms) || !draw(r, &s, &sc->view, &target, &ms))
        goto done;
    for (int c = 0; c < n_counts; c++) {
        int n = counts[c];
        struct render_view views[64];
        if (n > 64)
            n = 64;
        for (int i = 0; i < n; i++) {
            struct camera_orbit o = {{centre[0], centre[1], centre[2]}, 360.0 * i / n + 20.0,
                                     15.0 + 10.0 * (i % 3), 1.2 * diag};
            double eye[3], up[3] = {0, 0, 1};
            camera_orbit_eye(&o, eye);
            camera_look_at(eye, o.target, up, 50.0, 10.0, 10.0 * diag, w, h, &views[i]);
        }
        double shared[REPEATS_MAX], still[REPEATS_MAX], rebuild[REPEATS_MAX];
        double builds[REPEATS_MAX * 64], draws[REPEATS_MAX * 64];
        int nb = 0, nd = 0;
        for (int k = 0; k < repeats; k++) {
            double b, total = 0.0;
            if (!build(r, lg, sc, &v, &b))
                goto done;
            builds[nb++] = b;
            double views_ms = 0.0;
            for (int i = 0; i < n; i++) {
                if (!draw(r, &s, &views[i], &target, &ms))
                    goto done;
                views_ms += ms;
                draws[nd++] = ms;
            }
            shared[k] = b + views_ms;
            still[k] = 0.0;
            for (int i = 0; i < n; i++) {
                if (!draw(r, &s, &views[i], &target, &ms))
                    goto done;
                still[k] += ms;
            }
            for (int i = 0; i < n; i++) {
                if (!build(r, lg, sc, &v, &b) || !draw(r, &s, &views[i], &target, &ms))
                    goto done;
                total += b + ms;
            }
            rebuild[k] = total;
        }
        double spread;
        out[c].views = n;
        out[c].shared_ms = median(shared, repeats, &spread);
        out[c].static_ms = median(still, repeats, &spread);
        out[c].rebuild_ms = median(rebuild, repeats, &spread);
        out[c].build_ms = median(builds, nb, &spread);
        out[c].view_ms = median(draws, nd, &spread);
        log_info("bench: %2d views: shared %.0f ms, static %.0f ms, rebuilding %.0f ms", n,
                 out[c].shared_ms, out[c].static_ms, out[c].rebuild_ms);
    }
    ok = true;
done:
    gpu_texture_finish(&target);
    return ok;
}

/* ---- files ---------------------------------------------------------------------------- */

bool bench_make_dir(const char *dir)
{
    char tmp[PATH_MAX];
    snprintf(tmp, sizeof(tmp), "%s", dir);
    for (char *p = tmp + 1; *p; p++) {
        if (*p == '/') {
            *p = '\0';
            mkdir(tmp, 0777);
            *p = '/';
        }
    }
    if (mkdir(tmp, 0777) != 0 && errno != EEXIST) {
        log_error("%s: cannot create the folder: %s", dir, strerror(errno));
        return false;
    }
    return true;
}
