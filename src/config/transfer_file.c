#include "config/transfer_file.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <libconfig.h>

#include "common/log.h"
#include "config/transfer_group.h"

static void fail(const struct transfer_where *w, const config_setting_t *s, const char *setting,
                 const char *fmt, ...) __attribute__((format(printf, 4, 5)));

/* One message "FILE:LINE: PREFIX.SETTING: ...", the line mapped through W's locate. */
static void fail(const struct transfer_where *w, const config_setting_t *s, const char *setting,
                 const char *fmt, ...)
{
    char msg[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof(msg), fmt, ap);
    va_end(ap);
    int line = s ? config_setting_source_line(s) : 0;
    const char *file = w->file;
    if (w->locate && line > 0)
        w->locate(w->user, line, &file, &line);
    if (line > 0)
        log_error("%s:%d: %s%s: %s", file, line, w->prefix, setting, msg);
    else
        log_error("%s: %s%s: %s", file, w->prefix, setting, msg);
}

static bool number(const config_setting_t *s, double *out)
{
    int t = config_setting_type(s);
    if (t == CONFIG_TYPE_FLOAT)
        *out = config_setting_get_float(s);
    else if (t == CONFIG_TYPE_INT)
        *out = config_setting_get_int(s);
    else if (t == CONFIG_TYPE_INT64)
        *out = (double)config_setting_get_int64(s);
    else
        return false;
    return true;
}

static bool read_channel(const struct transfer_where *w, const config_setting_t *group,
                         int c, struct transfer_function *tf)
{
    const char *name = transfer_channel_name((enum transfer_channel)c);
    char where[64];
    snprintf(where, sizeof(where), ".%s", name);
    const config_setting_t *list = config_setting_get_member(group, name);
    if (!list) {
        fail(w, group, where, "missing (a list of [x, value] points)");
        return false;
    }
    int n = config_setting_length(list);
    if (!(config_setting_is_list(list) || config_setting_is_array(list)) || n < 1 ||
        n > TRANSFER_MAX_POINTS) {
        fail(w, list, where, "expected a list of 1 to %d [x, value] points",
             TRANSFER_MAX_POINTS);
        return false;
    }
    for (int i = 0; i < n; i++) {
        const config_setting_t *p = config_setting_get_elem(list, (unsigned)i);
        char at[80];
        snprintf(at, sizeof(at), "%s[%d]", where, i);
        double xv[2];
        if (!config_setting_is_array(p) || config_setting_length(p) != 2 ||
            !number(config_setting_get_elem(p, 0), &xv[0]) ||
            !number(config_setting_get_elem(p, 1), &xv[1])) {
            fail(w, p, at, "expected [x, value], two numbers");
            return false;
        }
        if (!(xv[0] >= 0.0 && xv[0] <= 1.0 && xv[1] >= 0.0 && xv[1] <= 1.0)) {
            fail(w, p, at, "expected x and value in [0, 1], got [%g, %g]", xv[0], xv[1]);
            return false;
        }
        if (i > 0 && (float)xv[0] < tf->points[c][i - 1].x) {
            fail(w, p, at, "expected x >= %g (points in ascending x), got %g",
                 tf->points[c][i - 1].x, xv[0]);
            return false;
        }
        tf->points[c][i] = (struct transfer_point){(float)xv[0], (float)xv[1]};
    }
    tf->count[c] = n;
    return true;
}

static bool read_group(const struct transfer_where *w, const config_setting_t *g,
                       struct transfer_function *tf)
{
    const config_setting_t *s = config_setting_get_member(g, "name");
    if (s) {
        const char *name = config_setting_get_string(s);
        if (!name || strlen(name) >= TRANSFER_NAME_MAX) {
            fail(w, s, ".name", "expected a string of at most %d characters",
                 TRANSFER_NAME_MAX - 1);
            return false;
        }
        snprintf(tf->name, sizeof(tf->name), "%s", name);
    }
    s = config_setting_get_member(g, "field");
    const char *field = s ? config_setting_get_string(s) : NULL;
    if (!field || !transfer_field_from_name(field, &tf->field)) {
        fail(w, s ? s : g, ".field",
             "expected \"qvapor\", \"condensate\", \"temperature\" or \"wind\"");
        return false;
    }
    s = config_setting_get_member(g, "range");
    double r[2];
    if (!s || !config_setting_is_array(s) || config_setting_length(s) != 2 ||
        !number(config_setting_get_elem(s, 0), &r[0]) ||
        !number(config_setting_get_elem(s, 1), &r[1]) || !(r[0] < r[1])) {
        fail(w, s ? s : g, ".range", "expected [lo, hi], two numbers with lo < hi");
        return false;
    }
    tf->lo = r[0];
    tf->hi = r[1];
    s = config_setting_get_member(g, "density");
    if (!s || !number(s, &tf->density) || !(tf->density >= 0.0)) {
        fail(w, s ? s : g, ".density", "expected a number >= 0 (1/m)");
        return false;
    }
    for (int c = 0; c < TRANSFER_CHANNELS; c++) {
        if (!read_channel(w, g, c, tf))
            return false;
    }
    return true;
}

bool transfer_group_read(const config_setting_t *g, const struct transfer_where *w,
                         struct transfer_function *out)
{
    struct transfer_function *tf = calloc(1, sizeof(*tf));
    if (!tf) {
        log_error("%s: out of memory", w->file);
        return false;
    }
    transfer_defaults(tf, TRANSFER_FIELD_QVAPOR);
    bool ok = read_group(w, g, tf);
    char why[160];
    if (ok && !transfer_valid(tf, why, sizeof(why))) {
        fail(w, g, "", "%s", why);
        ok = false;
    }
    if (ok)
        *out = *tf;
    free(tf);
    return ok;
}

bool transfer_file_load(const char *path, struct transfer_function *out)
{
    size_t len = 0;
    char *text = file_read_all(path, &len);
    if (!text)
        return false;
    config_t cf;
    config_init(&cf);
    bool ok = false;
    struct transfer_function *tf = calloc(1, sizeof(*tf));
    if (!tf) {
        log_error("%s: out of memory", path);
        goto done;
    }
    if (strlen(text) != len) {
        log_error("%s: not a text file (a NUL byte at offset %zu)", path, strlen(text));
        goto done;
    }
    if (config_read_string(&cf, text) != CONFIG_TRUE) {
        log_error("%s:%d: %s", path, config_error_line(&cf), config_error_text(&cf));
        goto done;
    }
    const config_setting_t *g = config_lookup(&cf, "transfer");
    if (!g || !config_setting_is_group(g)) {
        log_error("%s: expected a group \"transfer = { ... };\"", path);
        goto done;
    }
    transfer_defaults(tf, TRANSFER_FIELD_QVAPOR);
    struct transfer_where where = {.file = path, .prefix = "transfer"};
    if (!read_group(&where, g, tf))
        goto done;
    char why[160];
    if (!transfer_valid(tf, why, sizeof(why))) {
        log_error("%s: %s", path, why);
        goto done;
    }
    *out = *tf;
    ok = true;
done:
    free(tf);
    config_destroy(&cf);
    free(text);
    return ok;
}

void transfer_file_write_group(FILE *f, const char *name, const struct transfer_function *tf,
                               const char *indent)
{
    fprintf(f, "%s%s = {\n", indent, name);
    fprintf(f, "%s    name = \"", indent);
    for (const char *p = tf->name; *p; p++) {
        if (*p == '"' || *p == '\\')
            fputc('\\', f);
        fputc(*p, f);
    }
    fprintf(f, "\";\n%s    field = \"%s\";\n", indent, transfer_field_name(tf->field));
    fprintf(f, "%s    range = [%.17e, %.17e];\n", indent, tf->lo, tf->hi);
    fprintf(f, "%s    density = %.17e;\n", indent, tf->density);
    for (int c = 0; c < TRANSFER_CHANNELS; c++) {
        fprintf(f, "%s    %s = (", indent, transfer_channel_name((enum transfer_channel)c));
        for (int i = 0; i < tf->count[c]; i++)
            fprintf(f, "%s[%.9e, %.9e]", i ? ", " : "", (double)tf->points[c][i].x,
                    (double)tf->points[c][i].v);
        fprintf(f, ");\n");
    }
    fprintf(f, "%s};\n", indent);
}

bool transfer_file_save(const char *path, const struct transfer_function *tf)
{
    char why[160];
    if (!transfer_valid(tf, why, sizeof(why))) {
        log_error("%s: not saved: %s", path, why);
        return false;
    }
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    if (!f) {
        log_error("%s: out of memory", path);
        return false;
    }
    fprintf(f, "# anvil transfer function (docs/menu.md)\n");
    transfer_file_write_group(f, "transfer", tf, "");
    if (fclose(f) != 0) {
        free(buf);
        log_error("%s: out of memory", path);
        return false;
    }
    bool ok = file_write_atomic(path, buf, len);
    free(buf);
    return ok;
}
