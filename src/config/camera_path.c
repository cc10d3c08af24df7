/* Camera path files: every key checked, the caller's struct filled only when all are valid. */
#include "config/camera_path.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <libconfig.h>

#include "common/log.h"

static void fail(const char *path, const config_setting_t *s, const char *setting,
                 const char *fmt, ...) __attribute__((format(printf, 4, 5)));

static void fail(const char *path, const config_setting_t *s, const char *setting,
                 const char *fmt, ...)
{
    char msg[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof(msg), fmt, ap);
    va_end(ap);
    int line = s ? config_setting_source_line(s) : 0;
    if (line > 0)
        log_error("%s:%d: %s: %s", path, line, setting, msg);
    else
        log_error("%s: %s: %s", path, setting, msg);
}

static bool number(const config_setting_t *s, double *out)
{
    int t = s ? config_setting_type(s) : CONFIG_TYPE_NONE;
    if (t == CONFIG_TYPE_FLOAT)
        *out = config_setting_get_float(s);
    else if (t == CONFIG_TYPE_INT)
        *out = config_setting_get_int(s);
    else if (t == CONFIG_TYPE_INT64)
        *out = (double)config_setting_get_int64(s);
    else
        return false;
    return isfinite(*out);
}

static bool vector3(const char *path, const config_setting_t *key, const char *name,
                    const char *where, bool required, const double def[3], double out[3])
{
    const config_setting_t *s = config_setting_get_member(key, name);
    char at[96];
    snprintf(at, sizeof(at), "%s.%s", where, name);
    if (!s) {
        if (required) {
            fail(path, key, at, "missing ([x, y, z])");
            return false;
        }
        memcpy(out, def, 3 * sizeof(double));
        return true;
    }
    if (!(config_setting_is_array(s) || config_setting_is_list(s)) ||
        config_setting_length(s) != 3 || !number(config_setting_get_elem(s, 0), &out[0]) ||
        !number(config_setting_get_elem(s, 1), &out[1]) ||
        !number(config_setting_get_elem(s, 2), &out[2])) {
        fail(path, s, at, "expected [x, y, z], three finite numbers");
        return false;
    }
    return true;
}

static bool scalar(const char *path, const config_setting_t *key, const char *name,
                   const char *where, double lo, double hi, double *out, bool *given)
{
    const config_setting_t *s = config_setting_get_member(key, name);
    *given = s != NULL;
    if (!s)
        return true;
    char at[96];
    snprintf(at, sizeof(at), "%s.%s", where, name);
    if (!number(s, out) || !(*out >= lo && *out <= hi)) {
        fail(path, s, at, "expected a number in [%g, %g]", lo, hi);
        return false;
    }
    return true;
}

static bool read_key(const char *path, const config_setting_t *key, int i,
                     struct camera_key *k, bool *has_step)
{
    char where[64];
    snprintf(where, sizeof(where), "camera_path.keys.[%d]", i);
    if (!config_setting_is_group(key)) {
        fail(path, key, where, "expected a key { time = ...; position = [...]; ... }");
        return false;
    }
    static const char *const known[] = {"time", "position", "target", "up", "fov", "step"};
    for (int m = 0; m < config_setting_length(key); m++) {
        const config_setting_t *s = config_setting_get_elem(key, (unsigned)m);
        bool ok = false;
        for (size_t j = 0; j < sizeof(known) / sizeof(known[0]); j++)
            ok = ok || strcmp(config_setting_name(s), known[j]) == 0;
        if (!ok) {
            char at[128];
            snprintf(at, sizeof(at), "%s.%s", where, config_setting_name(s));
            fail(path, s, at, "unknown setting (a key has time, position, target, up, fov, "
                              "step)");
            return false;
        }
    }
    bool given;
    const double up[3] = {0.0, 0.0, 1.0};
    k->fov_deg = 50.0;
    if (!scalar(path, key, "time", where, 0.0, 1e7, &k->time_s, &given))
        return false;
    if (!given) {
        fail(path, key, where, "missing time (seconds into the path)");
        return false;
    }
    if (!vector3(path, key, "position", where, true, NULL, k->position_km) ||
        !vector3(path, key, "target", where, true, NULL, k->target_km) ||
        !vector3(path, key, "up", where, false, up, k->up) ||
        !scalar(path, key, "fov", where, 1.0, 179.0, &k->fov_deg, &given) ||
        !scalar(path, key, "step", where, 0.0, 1e6, &k->step, has_step))
        return false;
    double d = 0.0, u = 0.0, c = 0.0;
    double f[3], x[3];
    for (int a = 0; a < 3; a++) {
        f[a] = k->target_km[a] - k->position_km[a];
        d += f[a] * f[a];
        u += k->up[a] * k->up[a];
    }
    x[0] = f[1] * k->up[2] - f[2] * k->up[1];
    x[1] = f[2] * k->up[0] - f[0] * k->up[2];
    x[2] = f[0] * k->up[1] - f[1] * k->up[0];
    c = x[0] * x[0] + x[1] * x[1] + x[2] * x[2];
    if (!(d > 1e-18) || !(u > 1e-24) || !(c > 1e-12 * d * u)) {
        fail(path, key, where, "expected a target away from the position and an up that is "
                               "not along the view");
        return false;
    }
    return true;
}

bool camera_path_load(const char *path, struct camera_path *out)
{
    char *text = file_read_all(path, NULL);
    if (!text)
        return false;
    struct camera_path *p = calloc(1, sizeof(*p));
    config_t lc;
    config_init(&lc);
    bool ok = false;
    if (!p) {
        log_error("%s: out of memory", path);
        goto done;
    }
    if (!config_read_string(&lc, text)) {
        log_error("%s:%d: %s", path, config_error_line(&lc), config_error_text(&lc));
        goto done;
    }
    const config_setting_t *group = config_lookup(&lc, "camera_path");
    const config_setting_t *keys = group ? config_setting_get_member(group, "keys") : NULL;
    int n = keys ? config_setting_length(keys) : 0;
    if (!keys || !config_setting_is_list(keys) || n < 1 || n > CAMERA_PATH_MAX) {
        fail(path, keys ? keys : group, "camera_path.keys", "expected a list ( {...}, ... ) of "
                                                            "1 to %d key views",
             CAMERA_PATH_MAX);
        goto done;
    }
    for (int i = 0; i < n; i++) {
        const config_setting_t *key = config_setting_get_elem(keys, (unsigned)i);
        bool has_step = false;
        if (!read_key(path, key, i, &p->keys[i], &has_step))
            goto done;
        if (i == 0)
            p->has_steps = has_step;
        if (has_step != p->has_steps) {
            fail(path, key, "camera_path.keys", "expected a step on every key or on none (key "
                                                "%d differs from key 0)",
                 i);
            goto done;
        }
        if (i > 0 && !(p->keys[i].time_s > p->keys[i - 1].time_s)) {
            char at[64];
            snprintf(at, sizeof(at), "camera_path.keys.[%d].time", i);
            fail(path, config_setting_get_member(key, "time"), at,
                 "expected a time after %g s (times must increase)", p->keys[i - 1].time_s);
            goto done;
        }
    }
    p->count = n;
    *out = *p;
    ok = true;
done:
    config_destroy(&lc);
    free(p);
    free(text);
    return ok;
}

bool camera_path_save(const char *path, const struct camera_path *p)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    if (!f) {
        log_error("%s: out of memory", path);
        return false;
    }
    fprintf(f, "# anvil camera path: key views, flown through in time (docs/user-guide.md)\n"
               "camera_path = {\n    keys = (\n");
    for (int i = 0; i < p->count; i++) {
        const struct camera_key *k = &p->keys[i];
        fprintf(f, "        { time = %.6f; position = [%.6f, %.6f, %.6f];\n", k->time_s,
                k->position_km[0], k->position_km[1], k->position_km[2]);
        fprintf(f, "          target = [%.6f, %.6f, %.6f]; up = [%.6f, %.6f, %.6f];\n",
                k->target_km[0], k->target_km[1], k->target_km[2], k->up[0], k->up[1],
                k->up[2]);
        fprintf(f, "          fov = %.6f;", k->fov_deg);
        if (p->has_steps)
            fprintf(f, " step = %.6f;", k->step);
        fprintf(f, " }%s\n", i + 1 < p->count ? "," : "");
    }
    fprintf(f, "    );\n};\n");
    fclose(f);
    bool ok = file_write_atomic(path, buf, len);
    free(buf);
    return ok;
}
