/* anvil bench: the views benchmark and the quality sweep (bench/bench.h), written as CSV,
 * markdown and PNG. */
#include <errno.h>
#include <getopt.h>
#include <libgen.h>
#include <limits.h>
#include <math.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "app/app.h"
#include "session/scene.h"
#include "session/stats.h"
#include "app/cmd_bench.h"
#include "session/effects.h"
#include "bench/bench.h"
#include "common/log.h"
#include "data/extfile.h"
#include "gpu/gpu.h"
#include "light/light_gpu.h"
#include "render/camera.h"

extern char **environ;

#define MAX_VARIANTS 32
#define MAX_SCENES 3

struct bench_options {
    bool quick, views, quality, paraview;
    const char *out;
    char cache[PATH_MAX];
    int spp;
    const char *scenes[MAX_SCENES];
    int n_scenes;
};

static int usage(FILE *out)
{
    fprintf(out,
            "usage: anvil bench [--quick] [--views-only | --quality-only] [-o DIR] [--cache DIR]\n"
            "                   [--spp N] [--scene sphere|storm|katrina]... [--paraview] [--quiet]\n"
            "What accuracy costs in time (docs/accuracy.md):\n"
            "  views    frame cost of 1, 2, 8 and 12 views sharing one light map against the\n"
            "           same views each rebuilding it\n"
            "  quality  each quality knob swept around the defaults on named scenes: GPU ms per\n"
            "           light build and per view, error against the Monte Carlo reference;\n"
            "           then a uniform cloud layer seen from 16 directions and a uniform\n"
            "           wall under 4 suns against Monte Carlo\n"
            "  -o DIR       where views.md, accuracy.csv, accuracy-table.md, accuracy.png and\n"
            "               angles-table.md go (default docs/bench)\n"
            "  --cache DIR  Monte Carlo references are kept here (default: bench-cache beside\n"
            "               the anvil binary)\n"
            "  --spp N      reference samples per pixel (default 256, --quick 32; the sphere\n"
            "               gets 64 times as many)\n"
            "  --quick      small scenes and images, one repeat: a CI-sized run\n"
            "  --paraview   also time ParaView's shadowed volume rendering of the same volume and\n"
            "               views (src/bench/paraview_views.py through pvbatch, under xvfb-run\n"
            "               without a display) into views-paraview.md; skipped with \"ParaView\n"
            "               not available\" when pvbatch is not on PATH\n");
    return EXIT_USAGE;
}

static int parse(int argc, char **argv, struct bench_options *o)
{
    static const struct option longopts[] = {
        {"quick", no_argument, NULL, 'Q'},          {"views-only", no_argument, NULL, 'V'},
        {"quality-only", no_argument, NULL, 'A'},   {"output", required_argument, NULL, 'o'},
        {"cache", required_argument, NULL, 'c'},    {"spp", required_argument, NULL, 'n'},
        {"scene", required_argument, NULL, 's'},    {"quiet", no_argument, NULL, 'q'},
        {"paraview", no_argument, NULL, 'P'},       {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0},
    };
    memset(o, 0, sizeof(*o));
    o->views = o->quality = true;
    o->out = "docs/bench";
    optind = 1;
    int c;
    char *end;
    while ((c = getopt_long(argc, argv, "o:qh", longopts, NULL)) != -1) {
        switch (c) {
        case 'Q':
            o->quick = true;
            break;
        case 'V':
            o->quality = false;
            break;
        case 'A':
            o->views = false;
            break;
        case 'o':
            o->out = optarg;
            break;
        case 'c':
            snprintf(o->cache, sizeof(o->cache), "%s", optarg);
            break;
        case 'n':
            errno = 0;
            o->spp = (int)strtol(optarg, &end, 10);
            if (errno || *end || o->spp < 2 || o->spp > 1 << 20) {
                log_error("bench: --spp: expected an integer in [2, 1048576], got \"%s\"",
                          optarg);
                return EXIT_BAD_INPUT;
            }
            break;
        case 's':
            if (strcmp(optarg, "sphere") && strcmp(optarg, "storm") && strcmp(optarg, "katrina")) {
                log_error("bench: --scene: expected sphere, storm or katrina, got \"%s\"", optarg);
                return EXIT_BAD_INPUT;
            }
            if (o->n_scenes < MAX_SCENES)
                o->scenes[o->n_scenes++] = optarg;
            break;
        case 'q':
            log_set_level(LOG_ERROR);
            break;
        case 'P':
            o->paraview = true;
            break;
        case 'h':
            return -1;
        default:
            return EXIT_USAGE;
        }
    }
    if (optind < argc) {
        log_error("bench: unexpected argument \"%s\"", argv[optind]);
        return EXIT_USAGE;
    }
    if (!o->views && !o->quality) {
        log_error("bench: --views-only and --quality-only exclude each other");
        return EXIT_USAGE;
    }
    if (o->paraview && !o->views) {
        log_error("bench: --paraview compares the views benchmark; it excludes --quality-only");
        return EXIT_USAGE;
    }
    if (!o->spp)
        o->spp = o->quick ? 32 : 256;
    if (!o->cache[0]) {
        char exe[PATH_MAX];
        ssize_t len = readlink("/proc/self/exe", exe, sizeof(exe) - 1);
        if (len > 0) {
            exe[len] = '\0';
            snprintf(o->cache, sizeof(o->cache), "%s/bench-cache", dirname(exe));
        } else {
            snprintf(o->cache, sizeof(o->cache), "bench-cache");
        }
    }
    if (o->n_scenes == 0) {
        o->scenes[0] = "sphere";
        o->scenes[1] = "storm";
        o->scenes[2] = "katrina";
        o->n_scenes = 3;
    }
    return EXIT_OK;
}

/* A named scene's config: its file, then SETS. */
static bool scene_config(const char *name, bool quick, const char **extra, int n_extra,
                         struct config *cfg)
{
    char path[PATH_MAX];
    const char *file = NULL;
    if (strcmp(name, "sphere") == 0)
        file = "sphere.cfg";
    else if (strcmp(name, "katrina") == 0)
        file = "katrina.cfg";
    if (file)
        snprintf(path, sizeof(path), "%s/configs/%s", ANVIL_SOURCE_DIR, file);
    char *sets[16];
    int n = 0;
    static char quick_size[] = "scene.size=[48,48,24]";
    static char quick_light[] = "lightmap.resolution=[64,64,64]";
    if (quick && strcmp(name, "storm") == 0) {
        sets[n++] = quick_size;
        sets[n++] = quick_light;
    }
    for (int i = 0; i < n_extra && n < 16; i++)
        sets[n++] = (char *)extra[i];
    return config_load_overrides(file ? path : NULL, sets, n, cfg);
}

/* The scene as anvil render draws it (effects decided from the scene), at W x H. */
static bool scene_prepare(const char *name, const struct config *cfg, int w, int h,
                          struct ext_volume *vol, struct bench_scene *sc)
{
    memset(sc, 0, sizeof(*sc));
    snprintf(sc->name, sizeof(sc->name), "%s", name);
    if (!scene_build_volume(cfg, vol))
        return false;
    camera_direction(cfg->light.azimuth_deg, cfg->light.elevation_deg, sc->sun);
    scene_camera_view(cfg, w, h, &sc->view);
    struct effects_facts facts;
    effects_facts_init(&facts);
    if (!effects_measure_volume(vol, sc->sun, &cfg->optics.params, &facts))
        return false;
    facts.time_steps = 1;
    facts.views_known = true;
    facts.ground_visible = cfg->render.ground_on && effects_view_sees_ground(&sc->view);
    struct effects e;
    effects_decide(cfg, &facts, &e);
    scene_render_settings(cfg, &sc->settings);
    effects_apply_render(&e, &sc->settings);
    effects_light_settings(cfg, &e, &sc->light);
    sc->shadows = e.on[EFFECT_SHADOWS];
    sc->mode = cfg->lightmap.mode == LIGHTMAP_COMPRESSED ? LIGHT_GPU_COMPRESSED : LIGHT_GPU_DENSE;
    sc->optics = cfg->optics.params;
    sc->vol = vol;
    return true;
}

/* A markdown table written in memory, headed by the command that makes it (RUN: "views" or
 * "quality"); write_text() puts it under docs/. */
static FILE *open_table(const struct bench_options *o, const char *run, char **buf, size_t *len)
{
    FILE *f = open_memstream(buf, len);
    fprintf(f, "<!-- generated by `anvil bench%s --%s-only`; do not edit by hand -->\n",
            o->quick ? " --quick" : "", run);
    return f;
}

static bool write_text(const char *dir, const char *name, char *buf, size_t len)
{
    char path[PATH_MAX];
    snprintf(path, sizeof(path), "%s/%s", dir, name);
    bool ok = file_write_atomic(path, buf, len);
    if (ok)
        printf("wrote %s\n", path);
    return ok;
}

static bool make_dir(const char *dir)
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

/* ---- views ----------------------------------------------------------------------------- */

/* Whether NAME is an executable on PATH. */
static bool on_path(const char *name)
{
    const char *path = getenv("PATH");
    while (path && *path) {
        size_t len = strcspn(path, ":");
        char file[PATH_MAX];
        snprintf(file, sizeof(file), "%.*s/%s", len ? (int)len : 1, len ? path : ".", name);
        if (access(file, X_OK) == 0)
            return true;
        path += len + (path[len] == ':');
    }
    return false;
}

/* The ParaView side of the views benchmark: VOL goes to an extinction file in the cache, and
 * src/bench/paraview_views.py (pvbatch) renders the same views of it with VTK's volumetric
 * shadows, and writes views-paraview.md beside anvil's numbers ROWS.  Missing ParaView is not
 * an error. */
static bool run_paraview(const struct bench_options *o, const struct config *cfg,
                         const struct ext_volume *vol, const struct bench_views_row *rows, int n,
                         int w, int h, int repeats)
{
    if (!on_path("pvbatch")) {
        printf("ParaView not available (no pvbatch on PATH): the comparison with ParaView is "
               "skipped\n");
        return true;
    }
    char volume[PATH_MAX + 32], script[PATH_MAX], sun[64], size[32], reps[16], anvil[1024];
    if (!make_dir(o->cache))
        return false;
    snprintf(volume, sizeof(volume), "%s/paraview-storm.nc", o->cache);
    struct extfile_writer *ew = extfile_writer_create(volume, &vol->grid, "anvil bench",
                                                      "anvil bench --paraview", NULL);
    if (!ew || !extfile_writer_add(ew, vol, "") || !extfile_writer_finish(ew)) {
        extfile_writer_destroy(ew);
        return false;
    }
    snprintf(script, sizeof(script), "%s/src/bench/paraview_views.py", ANVIL_SOURCE_DIR);
    snprintf(sun, sizeof(sun), "%g,%g", cfg->light.azimuth_deg, cfg->light.elevation_deg);
    snprintf(size, sizeof(size), "%dx%d", w, h);
    snprintf(reps, sizeof(reps), "%d", repeats);
    size_t len = 0;
    for (int i = 0; i < n && len < sizeof(anvil); i++)
        len += (size_t)snprintf(anvil + len, sizeof(anvil) - len, "%s%d:%.3f:%.3f:%.3f:%.3f",
                                i ? "," : "", rows[i].views, rows[i].shared_ms,
                                rows[i].static_ms, rows[i].rebuild_ms, rows[i].view_ms);
    /* pvbatch in Debian needs an X display (GLX); xvfb-run gives it one. */
    bool xvfb = !getenv("DISPLAY") && on_path("xvfb-run");
    char *argv[] = {"xvfb-run", "-a", "pvbatch", script, "--volume", volume, "--sun", sun,
                    "--size", size, "--repeats", reps, "--anvil", anvil, "--out",
                    (char *)o->out, NULL};
    char **args = xvfb ? argv : argv + 2;
    printf("running %s%s (ParaView)\n", xvfb ? "xvfb-run -a " : "", "pvbatch");
    fflush(stdout);
    pid_t pid;
    int err = posix_spawnp(&pid, args[0], NULL, NULL, args, environ);
    if (err) {
        log_error("bench: cannot run %s: %s", args[0], strerror(err));
        return false;
    }
    int status;
    if (waitpid(pid, &status, 0) < 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        log_error("bench: %s failed (ParaView side of the views benchmark)", script);
        return false;
    }
    return true;
}

static bool run_views(const struct bench_options *o, const char *device, struct renderer *r,
                      struct light_gpu *lg)
{
    struct config cfg;
    const char *extra[] = {"render.ground_on=false"};
    if (!scene_config("storm", o->quick, extra, 1, &cfg))
        return false;
    int w = o->quick ? 64 : 160, h = o->quick ? 48 : 120, repeats = o->quick ? 1 : 3;
    struct ext_volume vol = {0};
    struct bench_scene sc;
    bool ok = scene_prepare("storm", &cfg, w, h, &vol, &sc) &&
              renderer_set_optics(r, &cfg.optics.params) && renderer_set_volume(r, &vol);
    static const int counts[] = {1, 2, 8, 12};
    struct bench_views_row rows[4];
    ok = ok && bench_views(r, lg, &sc, counts, 4, w, h, repeats, rows);
    if (!ok) {
        ext_volume_finish(&vol);
        return false;
    }
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_table(o, "views", &buf, &len);
    fprintf(f, "| views | shared light map: frame after a change, ms | shared: frame without a "
               "change, ms | a build per view, ms | per-view build ÷ shared | one build, ms | "
               "one view, ms |\n|---:|---:|---:|---:|---:|---:|---:|\n");
    for (int i = 0; i < 4; i++)
        fprintf(f, "| %d | %.0f | %.0f | %.0f | %.2f | %.0f | %.1f |\n", rows[i].views,
                rows[i].shared_ms, rows[i].static_ms, rows[i].rebuild_ms,
                rows[i].rebuild_ms / rows[i].shared_ms, rows[i].build_ms, rows[i].view_ms);
    fprintf(f, "\nScene: the procedural storm %dx%dx%d, light map %dx%dx%d (%s), views %dx%d "
               "orbiting the storm, medians of %d frame%s.  Device: %s.\n",
            vol.grid.n[0], vol.grid.n[1], vol.grid.n[2], sc.light.resolution[0],
            sc.light.resolution[1], sc.light.resolution[2],
            sc.mode == LIGHT_GPU_DENSE ? "dense" : "compressed", w, h, repeats,
            repeats > 1 ? "s" : "", device);
    fclose(f);
    ok = write_text(o->out, "views-table.md", buf, len);
    free(buf);
    printf("views (%s):\n", device);
    for (int i = 0; i < 4; i++)
        printf("  %2d views: shared %.0f ms (%.0f without a change), a build per view %.0f ms: "
               "%.2fx\n", rows[i].views, rows[i].shared_ms, rows[i].static_ms,
               rows[i].rebuild_ms, rows[i].rebuild_ms / rows[i].shared_ms);
    if (ok && o->paraview)
        ok = run_paraview(o, &cfg, &vol, rows, 4, w, h, repeats);
    ext_volume_finish(&vol);
    return ok;
}

/* ---- quality --------------------------------------------------------------------------- */

struct scene_results {
    char name[32];
    struct bench_result res[MAX_VARIANTS];
    int n;
    double sigma; /* the reference's RMS standard error */
    int spp;      /* its samples per pixel */
};

static bool run_scene(const struct bench_options *o, const char *name, struct renderer *r,
                      struct light_gpu *lg, struct scene_results *out)
{
    struct config cfg;
    /* The renderer lights the cloud with the sun only, so the comparison does too: no sky
     * (the reference would add sky light scattered by the cloud) and no ground. */
    const char *extra[] = {"render.sky=[0,0,0]", "render.ground_on=false"};
    if (!scene_config(name, o->quick, extra, 2, &cfg))
        return false;
    int w = o->quick ? 48 : 96, h = o->quick ? 36 : 72;
    struct ext_volume vol = {0};
    struct bench_scene sc;
    struct image ref = {0}, err = {0}, self = {0};
    bool ok = false;
    if (!scene_prepare(name, &cfg, w, h, &vol, &sc))
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
    if (!renderer_set_optics(r, &cfg.optics.params) || !renderer_set_volume(r, &vol))
        goto done;
    struct bench_variant variants[MAX_VARIANTS];
    int n = bench_variants(&sc, o->quick, variants, MAX_VARIANTS);
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
    for (int i = 0; i < n; i++) {
        if (!bench_measure(r, lg, &sc, &variants[i], &ref, &err, &self, &out->res[i]))
            goto done;
    }
    out->n = n;
    /* Timings round-robin over the variants: 5 builds and 5 views each (1 and 1 quick). */
    int rounds = o->quick ? 1 : 5, build_rounds = rounds;
    for (int k = 0; k < rounds; k++) {
        for (int i = 0; i < n; i++) {
            if (!bench_time_once(r, lg, &sc, k < build_rounds, &out->res[i]))
                goto done;
        }
    }
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

/* The plane-parallel layer seen from every side: a water cloud layer of optical depth 20
 * (480 x 480 x 2 km, the slab test scene) lit like the Katrina sample (azimuth 120 degrees,
 * elevation 40), looked at through an 8 degree field from each elevation and each azimuth
 * relative to the sun below, at the default settings.  A uniform layer has one exact answer
 * per direction, so the ratio of the picture's mean to Monte Carlo's says how well the model
 * gets the angular distribution of the light a cloud top reflects (docs/accuracy.md). */
static const double angle_elevations[] = {12.0, 30.0, 60.0, 85.0};
static const double angle_azimuths[] = {0.0, 75.0, 120.0, 180.0};
#define N_ELEV (int)(sizeof(angle_elevations) / sizeof(angle_elevations[0]))
#define N_AZIM (int)(sizeof(angle_azimuths) / sizeof(angle_azimuths[0]))

struct angle_result {
    double model, traced, sigma; /* means over pixels and channels; sigma: of the traced mean */
    double scattering_deg;       /* between the sunlight and the light heading to the camera */
};

/* The means of scene NAME (the config overrides SETS) at the default settings and of its
 * Monte Carlo reference, W x H pixels, into OUT (its scattering_deg is left alone). */
static bool scene_means(const struct bench_options *o, struct renderer *r, struct light_gpu *lg,
                        const char *name, char **sets, int n_sets, int w, int h,
                        struct angle_result *out)
{
    struct config cfg;
    if (!config_load_overrides(NULL, sets, n_sets, &cfg))
        return false;
    struct ext_volume vol = {0};
    struct bench_scene sc;
    struct image ref = {0}, err = {0}, img = {0};
    bool ok = false;
    if (!scene_prepare(name, &cfg, w, h, &vol, &sc))
        goto done;
    if (!bench_reference(&sc, o->spp, o->cache, &ref, &err, NULL))
        goto done;
    struct bench_variant def;
    if (bench_variants(&sc, true, &def, 1) != 1 || !renderer_set_optics(r, &cfg.optics.params) ||
        !renderer_set_volume(r, &vol) || !bench_render(r, lg, &sc, &def, &img))
        goto done;
    double a = 0.0, b = 0.0, var = 0.0;
    for (int i = 0; i < w * h; i++) {
        for (int c = 0; c < 3; c++) {
            a += img.rgba[4 * i + c];
            b += ref.rgba[4 * i + c];
            var += (double)err.rgba[4 * i + c] * err.rgba[4 * i + c];
        }
    }
    int n = 3 * w * h;
    out->model = a / n;
    out->traced = b / n;
    out->sigma = sqrt(var) / n;
    ok = true;
done:
    image_finish(&ref);
    image_finish(&err);
    image_finish(&img);
    ext_volume_finish(&vol);
    return ok;
}

static bool run_angle(const struct bench_options *o, struct renderer *r, struct light_gpu *lg,
                      double elevation, double rel_azimuth, struct angle_result *out)
{
    const double sun_az = 120.0, sun_el = 40.0, dist_km = 300.0;
    const double target[3] = {240.0, 240.0, 1.0};
    double d[3], sun[3];
    camera_direction(sun_az + rel_azimuth, elevation, d);
    camera_direction(sun_az, sun_el, sun);
    char sun_set[2][48], cam_set[80];
    snprintf(sun_set[0], sizeof(sun_set[0]), "light.azimuth=%g", sun_az);
    snprintf(sun_set[1], sizeof(sun_set[1]), "light.elevation=%g", sun_el);
    snprintf(cam_set, sizeof(cam_set), "camera.position=[%.4f,%.4f,%.4f]",
             target[0] + dist_km * d[0], target[1] + dist_km * d[1], target[2] + dist_km * d[2]);
    char *sets[] = {"scene.kind=slab", "scene.size=[64,64,16]", "scene.extent=[480,480,2]",
                    "scene.tau=20", "scene.phase=water", sun_set[0], sun_set[1], cam_set,
                    "camera.target=[240,240,1]", "camera.fov=8", "camera.far=5000",
                    "render.sky=[0,0,0]", "render.ground_on=false"};
    int w = o->quick ? 16 : 32, h = o->quick ? 12 : 24;
    if (!scene_means(o, r, lg, "layer", sets, (int)(sizeof(sets) / sizeof(sets[0])), w, h, out))
        return false;
    /* Sunlight travels along -sun; the light reaching the camera travels along +d. */
    double c = -(sun[0] * d[0] + sun[1] * d[1] + sun[2] * d[2]);
    out->scattering_deg = acos(fmax(-1.0, fmin(1.0, c))) * (180.0 / 3.14159265358979323846);
    log_info("bench: layer seen from elevation %g, azimuth %g from the sun: %.4g against "
             "%.4g +- %.2g", elevation, rel_azimuth, out->model, out->traced, out->sigma);
    return true;
}

/* A uniform wall: a box 2 km thick, 60 km long and 10 km high of water cloud (optical depth
 * 20 across), its long face toward the sun's azimuth, seen square-on from 50 km at 10 degrees
 * of elevation with the sun behind the camera, at each sun elevation.  Every light column is
 * solved as a layer lit at the sun's elevation (docs/lightmap.md), which is a deck's slant and
 * not a wall's: the table shows what that costs a tower's sunlit side (docs/accuracy.md). */
static const double wall_elevations[] = {10.0, 20.0, 45.0, 70.0};
#define N_WALL (int)(sizeof(wall_elevations) / sizeof(wall_elevations[0]))

static bool run_wall(const struct bench_options *o, struct renderer *r, struct light_gpu *lg,
                     double sun_el, struct angle_result *out)
{
    char sun_set[48];
    snprintf(sun_set, sizeof(sun_set), "light.elevation=%g", sun_el);
    char *sets[] = {"scene.kind=slab", o->quick ? "scene.size=[8,32,32]" : "scene.size=[16,64,64]",
                    "scene.extent=[2,60,10]", "scene.tau=100", "scene.phase=water",
                    "light.azimuth=270", sun_set, "camera.position=[-50,30,13.8164]",
                    "camera.target=[0,30,5]", "camera.fov=8", "camera.far=5000",
                    "render.sky=[0,0,0]", "render.ground_on=false"};
    int w = o->quick ? 16 : 32, h = o->quick ? 12 : 24;
    if (!scene_means(o, r, lg, "wall", sets, (int)(sizeof(sets) / sizeof(sets[0])), w, h, out))
        return false;
    out->scattering_deg = 0.0;
    log_info("bench: wall under a sun at elevation %g: %.4g against %.4g +- %.2g", sun_el,
             out->model, out->traced, out->sigma);
    return true;
}

/* The head of a table with one column per relative azimuth. */
static void angles_header(FILE *f)
{
    fprintf(f, "| elevation |");
    for (int j = 0; j < N_AZIM; j++)
        fprintf(f, " azimuth %g |", angle_azimuths[j]);
    fprintf(f, "\n|---:|");
    for (int j = 0; j < N_AZIM; j++)
        fprintf(f, "---:|");
    fprintf(f, "\n");
}

static bool run_angles(const struct bench_options *o, const char *device, struct renderer *r,
                       struct light_gpu *lg)
{
    struct angle_result res[N_ELEV][N_AZIM];
    for (int i = 0; i < N_ELEV; i++) {
        for (int j = 0; j < N_AZIM; j++) {
            if (!run_angle(o, r, lg, angle_elevations[i], angle_azimuths[j], &res[i][j]))
                return false;
        }
    }
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_table(o, "quality", &buf, &len);
    fprintf(f, "Device: %s.  A uniform water cloud layer, optical depth 20, 2 km thick, lit "
               "from azimuth 120 and elevation 40 degrees (the Katrina sample's sun), seen at "
               "the default settings through an 8 degree field from each elevation (rows) and "
               "each azimuth relative to the sun's (columns: 0 = the sun behind the camera, "
               "180 = the camera facing the sun).  Each cell: the picture's mean over the "
               "Monte Carlo reference's (%d samples per pixel), and the scattering angle "
               "between the sunlight and the light reaching the camera.\n\n",
            device, o->spp);
    angles_header(f);
    for (int i = 0; i < N_ELEV; i++) {
        fprintf(f, "| %g |", angle_elevations[i]);
        for (int j = 0; j < N_AZIM; j++) {
            const struct angle_result *a = &res[i][j];
            double ratio = a->traced > 0.0 ? a->model / a->traced : 0.0;
            double rel = a->traced > 0.0 ? a->sigma / a->traced : 0.0;
            fprintf(f, " %.2f ± %.2f (%.0f°) |", ratio, ratio * rel, a->scattering_deg);
        }
        fprintf(f, "\n");
    }
    fprintf(f, "\nMonte Carlo means (linear radiance):\n\n");
    angles_header(f);
    for (int i = 0; i < N_ELEV; i++) {
        fprintf(f, "| %g |", angle_elevations[i]);
        for (int j = 0; j < N_AZIM; j++)
            fprintf(f, " %.3g ± %.2g |", res[i][j].traced, res[i][j].sigma);
        fprintf(f, "\n");
    }
    struct angle_result wall[N_WALL];
    for (int i = 0; i < N_WALL; i++) {
        if (!run_wall(o, r, lg, wall_elevations[i], &wall[i])) {
            fclose(f);
            free(buf);
            return false;
        }
    }
    fprintf(f, "\nA uniform wall of the same cloud: a box 2 km thick, 60 km long and 10 km high "
               "(optical depth 20 across), its long face toward the sun's azimuth, seen "
               "square-on from 50 km at 10 degrees of elevation with the sun behind the camera, "
               "under each sun elevation (rows).  Every light column is a layer lit at the "
               "sun's elevation, a deck's slant and not this face's.\n\n");
    fprintf(f, "| sun elevation | picture over Monte Carlo | Monte Carlo mean |\n"
               "|---:|---:|---:|\n");
    for (int i = 0; i < N_WALL; i++) {
        const struct angle_result *a = &wall[i];
        double ratio = a->traced > 0.0 ? a->model / a->traced : 0.0;
        double rel = a->traced > 0.0 ? a->sigma / a->traced : 0.0;
        fprintf(f, "| %g | %.2f ± %.2f | %.3g ± %.2g |\n", wall_elevations[i], ratio,
                ratio * rel, a->traced, a->sigma);
    }
    fclose(f);
    bool ok = write_text(o->out, "angles-table.md", buf, len);
    printf("%.*s", (int)len, buf);
    free(buf);
    return ok;
}

static void verdict(FILE *f, const struct scene_results *s, bool self)
{
    const struct bench_result *def = NULL;
    for (int i = 0; i < s->n; i++) {
        if (s->res[i].v.is_default)
            def = &s->res[i];
    }
    if (!def)
        return;
    const char *against = self ? "against the converged renderer" : "against Monte Carlo";
    if (self ? def->pareto_self : def->pareto) {
        fprintf(f, "- **%s**, %s: the default is on the Pareto front.\n", s->name, against);
        return;
    }
    fprintf(f, "- **%s**, %s: the default is *not* on the Pareto front; beaten by", s->name,
            against);
    double td = def->build_ms + def->view_ms, ed = bench_error(def, self);
    for (int i = 0; i < s->n; i++) {
        const struct bench_result *r = &s->res[i];
        double t = r->build_ms + r->view_ms, e = bench_error(r, self);
        if (r != def && bench_beats(r, def, self))
            fprintf(f, " %s %s (%.2f× the time, error %.4g vs %.4g);", r->v.knob, r->v.value,
                    t / td, e, ed);
    }
    fprintf(f, "\n");
}

/* The result of scene S with knob and value as R's, or NULL. */
static const struct bench_result *same_setting(const struct scene_results *s,
                                               const struct bench_result *r)
{
    for (int i = 0; i < s->n; i++) {
        if (strcmp(s->res[i].v.knob, r->v.knob) == 0 && strcmp(s->res[i].v.value, r->v.value) == 0)
            return &s->res[i];
    }
    return NULL;
}

static const struct bench_result *default_of(const struct scene_results *s)
{
    for (int i = 0; i < s->n; i++) {
        if (s->res[i].v.is_default)
            return &s->res[i];
    }
    return NULL;
}

/* The defaults are one setting for every scene: a setting beats them across the scenes when,
 * the same on each, it is no slower and no worse on every scene and faster or better on one
 * (each beyond the noise).  Settings missing from a scene (a knob that scene's defaults make
 * moot) are left out. */
static void verdict_across(FILE *f, const struct scene_results *s, int n, bool self)
{
    if (n < 2)
        return;
    const char *against = self ? "against the converged renderer" : "against Monte Carlo";
    int beaten = 0;
    for (int i = 0; i < s[0].n; i++) {
        const struct bench_result *cand = &s[0].res[i];
        if (cand->v.is_default)
            continue;
        bool all = true, one = false;
        for (int k = 0; k < n && all; k++) {
            const struct bench_result *d = default_of(&s[k]), *v = same_setting(&s[k], cand);
            if (!d || !v || v->v.is_default) {
                all = false;
                break;
            }
            all = bench_no_worse(v, d, self);
            one = one || bench_beats(v, d, self);
        }
        if (!(all && one))
            continue;
        if (!beaten)
            fprintf(f, "- **Every scene**, %s: the defaults are *not* on the Pareto front; "
                       "beaten on every scene by", against);
        fprintf(f, " %s %s;", cand->v.knob, cand->v.value);
        beaten++;
    }
    if (beaten)
        fprintf(f, "\n");
    else
        fprintf(f, "- **Every scene**, %s: the defaults are on the Pareto front: no setting is "
                   "as fast and as accurate on every scene and better on one.\n", against);
}

static bool run_quality(const struct bench_options *o, const char *device, struct renderer *r,
                        struct light_gpu *lg)
{
    static struct scene_results scenes[MAX_SCENES];
    int n = 0;
    for (int i = 0; i < o->n_scenes; i++) {
        if (strcmp(o->scenes[i], "katrina") == 0) {
            char data[PATH_MAX];
            snprintf(data, sizeof(data), "%s/../shared/data/wrf/katrina_2005_mercator_wsm3.nc",
                     ANVIL_SOURCE_DIR);
            if (access(data, R_OK) != 0) {
                log_warn("bench: %s not found: the katrina scene is left out", data);
                continue;
            }
        }
        if (!run_scene(o, o->scenes[i], r, lg, &scenes[n]))
            return false;
        n++;
    }
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    for (int i = 0; i < n; i++)
        bench_write_csv(f, scenes[i].name, scenes[i].res, scenes[i].n, i == 0);
    fclose(f);
    bool ok = write_text(o->out, "accuracy.csv", buf, len);
    free(buf);

    f = open_table(o, "quality", &buf, &len);
    fprintf(f, "Device: %s.%s  Reference: %d samples per pixel (64 times that for the sphere), "
               "no sky, no ground.  ms are medians (± 1.48 × the median absolute deviation), "
               "repeats taken round-robin over the rows; rows that do the same work (the "
               "same shaders, grids and ray step: the forward angle is a constant of one "
               "shader) share their repeats.  σ is the reference's own RMS "
               "standard error per pixel and channel; the model RMSE is sqrt(RMSE² − σ²), the "
               "part of the RMSE the reference's noise does not explain.\n\n", device,
            strstr(device, "llvmpipe") ? "  **A CPU rasteriser: read the milliseconds as "
                                        "ratios between rows, not as GPU times.**"
                                      : "",
            o->spp);
    for (int i = 0; i < n; i++) {
        fprintf(f, "σ(%s) = %.3g (%d samples per pixel)\n\n", scenes[i].name,
                scenes[i].sigma, scenes[i].spp);
        bench_write_markdown(f, scenes[i].name, scenes[i].res, scenes[i].n);
        fprintf(f, "\n");
    }
    fprintf(f, "Pareto verdict (time = one light build + one view; error = the model RMSE "
               "against Monte Carlo, the RMSE against the converged renderer):\n\n");
    for (int self = 0; self < 2; self++) {
        for (int i = 0; i < n; i++)
            verdict(f, &scenes[i], self);
        verdict_across(f, scenes, n, self);
    }
    fclose(f);
    ok = write_text(o->out, "accuracy-table.md", buf, len) && ok;
    printf("%.*s", (int)len, buf);
    free(buf);

    const char *names[MAX_SCENES];
    const struct bench_result *res[MAX_SCENES];
    int counts[MAX_SCENES];
    for (int i = 0; i < n; i++) {
        names[i] = scenes[i].name;
        res[i] = scenes[i].res;
        counts[i] = scenes[i].n;
    }
    for (int self = 0; self < 2; self++) {
        char path[PATH_MAX], title[256];
        snprintf(path, sizeof(path), "%s/accuracy%s.png", o->out, self ? "-self" : "");
        snprintf(title, sizeof(title), "%s vs time (red: Pareto front, blue ring: default)",
                 self ? "error against the converged renderer" : "error against Monte Carlo");
        if (bench_plot_png(path, title, n, names, res, counts, self))
            printf("wrote %s\n", path);
        else
            ok = false;
    }
    return ok;
}

int cmd_bench(int argc, char **argv)
{
    struct bench_options o;
    int rc = parse(argc, argv, &o);
    if (rc < 0) {
        usage(stdout);
        return EXIT_OK;
    }
    if (rc == EXIT_USAGE)
        return usage(stderr);
    if (rc != EXIT_OK)
        return rc;
    if (!make_dir(o.out))
        return EXIT_FAILED;
    struct gpu_context *ctx = gpu_context_create(&(struct gpu_context_desc){.backend = "egl"});
    if (!ctx)
        return EXIT_NO_GPU;
    const char *device = gpu_renderer_name();
    struct renderer *r = renderer_create();
    struct light_gpu *lg = light_gpu_create();
    rc = EXIT_FAILED;
    if (!r || !lg)
        goto done;
    if (strstr(device, "llvmpipe"))
        printf("note: %s is a CPU rasteriser; the milliseconds below are only meaningful as "
               "ratios\n", device);
    if (o.views && !run_views(&o, device, r, lg))
        goto done;
    if (o.quality && !(run_quality(&o, device, r, lg) && run_angles(&o, device, r, lg)))
        goto done;
    rc = EXIT_OK;
done:
    light_gpu_destroy(lg);
    renderer_destroy(r);
    gpu_context_destroy(ctx);
    return rc;
}
