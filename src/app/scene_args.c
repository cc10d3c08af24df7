/* The scene a command line names (app.h): an optional config, then data files, folders and
 * glob patterns, each known by its content (data/detect.h). */
#include <glob.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "app/app.h"
#include "common/log.h"
#include "config/config.h"
#include "data/detect.h"
#include "session/scene.h"

static bool is_pattern(const char *s)
{
    return strpbrk(s, "*?[") != NULL;
}

static bool exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

/* The data format of a kind. */
static enum data_format format_of(enum data_kind k)
{
    return k == DATA_KIND_EXTINCTION ? DATA_EXTINCTION
           : k == DATA_KIND_ISABEL   ? DATA_ISABEL
           : k == DATA_KIND_CM1      ? DATA_CM1
           : k == DATA_KIND_CF       ? DATA_CF
                                     : DATA_WRF;
}

/* Adds ENTRY (a path or a pattern as given) to OUT. */
static bool add_entry(const char *command, const char *entry, struct app_inputs *out)
{
    if (out->count == CONFIG_MAX_FILES) {
        log_error("%s: more than %d data files: name a series by a quoted pattern "
                  "('wrfout_d01_*'), which anvil expands itself",
                  command, CONFIG_MAX_FILES);
        return false;
    }
    if (strlen(entry) >= CONFIG_PATH_MAX) {
        log_error("%s: path too long (at most %d bytes)", entry, CONFIG_PATH_MAX - 1);
        return false;
    }
    out->files[out->count++] = entry;
    return true;
}

/* The kind of PATH, checked against what came before (OUT->kind); false (logged) when it is not
 * data or does not go with the others. */
static bool take_kind(const char *command, const char *path, bool first, struct app_inputs *out)
{
    char why[2048];
    enum data_kind k = data_detect(path, why, sizeof(why));
    if (k == DATA_KIND_CONFIG) {
        if (first && !out->config && out->count == 0) {
            out->config = path;
            return true;
        }
        log_error("%s: %s is a text file (a scene config) among data files: the config comes "
                  "first, the data after it (anvil %s look.cfg wrfout_d01_* ...)",
                  command, path, command);
        return false;
    }
    if (!data_kind_is_data(k)) {
        log_error("%s", why);
        return false;
    }
    if (out->kind != DATA_KIND_UNREADABLE && out->kind != k) {
        log_error("%s: %s is %s, the files before it %s: one scene reads one format", command,
                  path, data_kind_name(k), data_kind_name(out->kind));
        return false;
    }
    if (out->kind == k && !data_kind_is_series(k)) {
        log_error("%s: %s: %s holds a whole series: name one (%s came first)", command, path,
                  data_kind_name(k), out->files[0]);
        return false;
    }
    out->kind = k;
    return true;
}

/* Keeps TEXT (copied) for as long as OUT: NULL (logged) when there is no room. */
static const char *own(const char *command, const char *text, struct app_inputs *out)
{
    char *one = out->n_owned < APP_INPUTS_MAX_OWNED ? strdup(text) : NULL;
    if (!one) {
        log_error("%s: out of memory", command);
        return NULL;
    }
    out->owned[out->n_owned++] = one;
    return one;
}

/* A pattern anvil expands (sorted, as the WRF reader does); every match must be data of one
 * kind.  A WRF, CM1 or CF series keeps the pattern itself (any number of files); PATTERN must
 * then outlive OUT. */
static bool add_pattern(const char *command, const char *pattern, struct app_inputs *out)
{
    glob_t g;
    int rc = glob(pattern, 0, NULL, &g);
    if (rc == GLOB_NOMATCH || (rc == 0 && g.gl_pathc == 0)) {
        log_error("%s: no file matches the pattern %s", command, pattern);
        globfree(&g);
        return false;
    }
    if (rc != 0) {
        log_error("%s: the pattern %s cannot be expanded (out of memory or a folder that "
                  "cannot be read)",
                  command, pattern);
        globfree(&g);
        return false;
    }
    bool ok = true;
    for (size_t m = 0; ok && m < g.gl_pathc; m++)
        ok = take_kind(command, g.gl_pathv[m], false, out);
    if (ok && !data_kind_is_series(out->kind)) {
        /* Extinction files and Isabel folders: one, named by its path. */
        const char *one = own(command, g.gl_pathv[0], out);
        ok = one && add_entry(command, one, out);
    } else if (ok) {
        ok = add_entry(command, pattern, out);
    }
    globfree(&g);
    return ok;
}

/* A folder that is not an Isabel folder: its WRF output or its NetCDF files, as a pattern
 * (data_folder_pattern).  False with the detector's message WHY when it holds neither. */
static bool add_folder(const char *command, const char *dir, const char *why,
                       struct app_inputs *out)
{
    char pattern[CONFIG_PATH_MAX];
    size_t count;
    const char *what;
    if (!data_folder_pattern(dir, pattern, sizeof(pattern), &count, &what)) {
        log_error("%s", why);
        return false;
    }
    log_info("%s: %zu %s (%s)", dir, count, what, pattern);
    const char *kept = own(command, pattern, out);
    return kept && add_pattern(command, kept, out);
}

static bool is_folder(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

bool app_inputs_collect(const char *command, char **args, int n, struct app_inputs *out)
{
    memset(out, 0, sizeof(*out));
    out->kind = DATA_KIND_UNREADABLE; /* none yet */
    for (int i = 0; i < n; i++) {
        const char *a = args[i];
        if (is_folder(a)) {
            char why[2048];
            enum data_kind k = data_detect(a, why, sizeof(why));
            if (k == DATA_KIND_UNKNOWN) { /* not Isabel's: the model output in it */
                if (!add_folder(command, a, why, out))
                    goto error;
                continue;
            }
        }
        if (!is_pattern(a) || exists(a)) {
            bool was_config = out->config != NULL;
            if (!take_kind(command, a, i == 0, out))
                goto error;
            if (out->config != NULL && !was_config)
                continue; /* the config */
            if (!add_entry(command, a, out))
                goto error;
            continue;
        }
        if (!add_pattern(command, a, out))
            goto error;
    }
    return true;
error:
    app_inputs_finish(out);
    return false;
}

void app_inputs_finish(struct app_inputs *in)
{
    for (int i = 0; i < in->n_owned; i++)
        free(in->owned[i]);
    in->n_owned = 0;
}

int app_load_scene(const char *command, char **args, int n, char **sets, int n_sets,
                   struct config *cfg, const char **config_path)
{
    struct app_inputs in;
    if (config_path)
        *config_path = NULL;
    if (!app_inputs_collect(command, args, n, &in))
        return EXIT_BAD_INPUT;
    int rc = EXIT_BAD_INPUT;
    if (in.config) {
        if (!config_load(in.config, cfg))
            goto done;
        if (config_path)
            *config_path = in.config;
    } else {
        config_defaults(cfg);
    }
    if (in.count > 0) {
        /* The files replace the config's data.files; its other data.* settings stay. */
        cfg->scene.kind = SCENE_DATA;
        cfg->data.format = format_of(in.kind);
        for (int i = 0; i < in.count; i++)
            snprintf(cfg->data.files[i], CONFIG_PATH_MAX, "%s", in.files[i]);
        cfg->data.file_count = in.count;
    }
    for (int i = 0; i < n_sets; i++) {
        if (!config_set(cfg, sets[i]))
            goto done;
    }
    if (!config_validate(cfg))
        goto done;
    if (!app_frame_camera(cfg))
        goto done;
    rc = EXIT_OK;
done:
    app_inputs_finish(&in);
    return rc;
}

bool app_frame_camera(struct config *cfg)
{
    if (cfg->camera.given || cfg->scene.kind != SCENE_DATA)
        return true;
    double lo[3], hi[3];
    if (!scene_domain_box(cfg, lo, hi))
        return false;
    struct display_camera c;
    scene_frame_camera(lo, hi, cfg->camera.fov_deg,
                       (double)cfg->render.width / cfg->render.height, cfg->camera.near_m, &c);
    scene_camera_to_config(&c, &cfg->camera);
    log_info("camera framing the data (%.0f x %.0f x %.1f km): position [%.3f, %.3f, %.3f] km, "
             "target [%.3f, %.3f, %.3f] km, fov %g",
             (hi[0] - lo[0]) / 1e3, (hi[1] - lo[1]) / 1e3, (hi[2] - lo[2]) / 1e3,
             cfg->camera.position_km[0], cfg->camera.position_km[1], cfg->camera.position_km[2],
             cfg->camera.target_km[0], cfg->camera.target_km[1], cfg->camera.target_km[2],
             cfg->camera.fov_deg);
    return true;
}

bool app_frame_navigation(const struct config *cfg, struct display_config *dcfg,
                          struct display_navigation *fitted)
{
    if (fitted)
        *fitted = dcfg->navigation;
    if (!(dcfg->type == DISPLAY_TYPE_CAVE || dcfg->type == DISPLAY_TYPE_HMD ||
          dcfg->type == DISPLAY_TYPE_OPENXR) ||
        (dcfg->navigation.given && !fitted))
        return true;
    double lo[3], hi[3];
    if (!scene_domain_box(cfg, lo, hi))
        return false;
    struct display_navigation fit;
    scene_frame_navigation(lo, hi, dcfg, &fit);
    if (fitted)
        *fitted = fit;
    if (dcfg->navigation.given)
        return true;
    dcfg->navigation = fit;
    const struct display_navigation *nv = &dcfg->navigation;
    log_info("navigation fitting the domain to the room: scale %.3g (%.2f x %.2f x %.2f m), "
             "origin [%.3f, %.3f, %.3f] km at [%.2f, %.2f, %.2f] m",
             nv->scale, (hi[0] - lo[0]) * nv->scale, (hi[1] - lo[1]) * nv->scale,
             (hi[2] - lo[2]) * nv->scale, nv->origin_km[0], nv->origin_km[1], nv->origin_km[2],
             nv->position[0], nv->position[1], nv->position[2]);
    /* A domain hundreds of kilometres wide and a few tall lies on the floor as a map a few
     * centimetres thick: say how to lift it (a round factor that makes it about 0.25 m). */
    double tall = (hi[2] - lo[2]) * nv->scale;
    if (tall > 0.0 && tall < 0.1 && cfg->scene.height_exaggeration <= 1.0) {
        double want = 0.25 / tall * fmax(cfg->scene.height_exaggeration, 1e-9), k = 1.0;
        while (k * 10.0 <= want)
            k *= 10.0;
        k = want >= 5.0 * k ? 5.0 * k : want >= 2.0 * k ? 2.0 * k : k;
        log_info("the domain stands %.0f mm tall in the room: --set scene.height_exaggeration=%g "
                 "lifts it to %.0f mm (docs/displays.md, \"Fitted to the room\")",
                 tall * 1e3, k, tall * 1e3 * k / fmax(cfg->scene.height_exaggeration, 1e-9));
    }
    return true;
}
