/*
 * The settings engine (config_table.h).  A file is read in three steps: @include lines are
 * expanded (Debian's libconfig 1.5 has no include hook) into texts that keep a map from their
 * lines back to (file, line), libconfig parses each text, and the walker checks every setting
 * it finds against the table, so each message names the real file and line.  --set goes
 * through the same checks from command-line text.
 */
#include "config/config_table.h"

#include <assert.h>
#include <ctype.h>
#include <errno.h>
#include <glob.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include <libconfig.h>

#include "common/log.h"
#include "config/config.h"
#include "config/transfer_file.h"
#include "config/transfer_group.h"
#include "optics/optics.h"

#define INCLUDE_DEPTH_MAX 16
#define NAME_MAX_LEN 256

/* ------------------------------------------------------------------------------------------ */
/* Finding settings                                                                            */

static int instances(const struct config_field *s)
{
    return (s->flags & F_SPECIES) ? SPECIES_COUNT : 1;
}

/* The path of one instance of S: '*' replaced by the species name. */
static void instance_path(const struct config_field *s, int sp, char *buf, size_t size)
{
    const char *star = strchr(s->path, '*');
    if (!star) {
        snprintf(buf, size, "%s", s->path);
        return;
    }
    snprintf(buf, size, "%.*s%s%s", (int)(star - s->path), s->path, species_name(sp), star + 1);
}

static bool find_setting(const struct config_table *t, const char *path,
                         const struct config_field **out, int *sp_out)
{
    char buf[NAME_MAX_LEN];
    for (int i = 0; i < t->count; i++) {
        for (int sp = 0; sp < instances(&t->fields[i]); sp++) {
            instance_path(&t->fields[i], sp, buf, sizeof(buf));
            if (strcmp(buf, path) == 0) {
                *out = &t->fields[i];
                *sp_out = sp;
                return true;
            }
        }
    }
    return false;
}

/* True when PATH names a group of settings, e.g. "light" or "species.rain"; then EXAMPLE (may
 * be NULL) receives the first setting in it. */
static bool is_group_path(const struct config_table *t, const char *path, char *example,
                          size_t size)
{
    char buf[NAME_MAX_LEN];
    size_t len = strlen(path);
    for (int i = 0; i < t->count; i++) {
        for (int sp = 0; sp < instances(&t->fields[i]); sp++) {
            instance_path(&t->fields[i], sp, buf, sizeof(buf));
            if (strncmp(buf, path, len) == 0 && buf[len] == '.') {
                if (example)
                    snprintf(example, size, "%s", buf);
                return true;
            }
        }
    }
    return false;
}

/* "PREFIX.NAME", or NAME alone when PREFIX is empty, cut to SIZE - 1 characters. */
static void join_name(const char *prefix, const char *name, char *buf, size_t size)
{
    size_t n = 0;
    for (const char *p = prefix; *p && n + 1 < size; p++)
        buf[n++] = *p;
    if (prefix[0] && name[0] && n + 1 < size)
        buf[n++] = '.';
    for (const char *p = name; *p && n + 1 < size; p++)
        buf[n++] = *p;
    buf[n] = '\0';
}

/* "walls.[2]": element INDEX of the list PATH. */
static void element_path(const char *path, int index, char *buf, size_t size)
{
    snprintf(buf, size, "%.200s.[%d]", path, index);
}

/* ------------------------------------------------------------------------------------------ */
/* Storing and fetching                                                                        */

static size_t element_size(const struct config_field *s)
{
    switch (s->type) {
    case T_BOOL:
        return sizeof(bool);
    case T_INT:
    case T_ENUM:
        return sizeof(int);
    case T_UINT:
        return sizeof(unsigned);
    case T_DOUBLE:
        return sizeof(double);
    case T_STRING:
    case T_PATH:
    case T_FILES:
    case T_GROUPS:
    case T_TRANSFER:
        break;
    }
    return 0;
}

static void *field(const struct config_field *s, int sp, int k, void *base)
{
    return (char *)base + s->offset + (size_t)sp * s->stride + (size_t)k * element_size(s);
}

static void *member(void *base, size_t offset)
{
    return (char *)base + offset;
}

static double scale_of(const struct config_field *s)
{
    return s->scale != 0 ? s->scale : 1.0;
}

/* Stores number K of setting S as written in a file (before scaling). */
static void store(const struct config_field *s, int sp, int k, double v, void *base)
{
    void *p = field(s, sp, k, base);
    switch (s->type) {
    case T_BOOL:
        *(bool *)p = v != 0;
        break;
    case T_INT:
    case T_ENUM:
        *(int *)p = (int)v;
        break;
    case T_UINT:
        *(unsigned *)p = (unsigned)v;
        break;
    case T_DOUBLE:
        *(double *)p = v * scale_of(s);
        break;
    case T_STRING:
    case T_PATH:
    case T_FILES:
    case T_GROUPS:
    case T_TRANSFER:
        assert(!"not a number");
    }
}

/* Number K of setting S in the units of a file. */
static double fetch(const struct config_field *s, int sp, int k, const void *base)
{
    const void *p = field(s, sp, k, (void *)base);
    switch (s->type) {
    case T_BOOL:
        return *(const bool *)p;
    case T_INT:
    case T_ENUM:
        return *(const int *)p;
    case T_UINT:
        return *(const unsigned *)p;
    case T_DOUBLE:
        return *(const double *)p / scale_of(s);
    case T_STRING:
    case T_PATH:
    case T_FILES:
    case T_GROUPS:
    case T_TRANSFER:
        break;
    }
    return 0;
}

static void mark_given(const struct config_field *s, void *base)
{
    if (s->flags & F_GIVEN)
        *(bool *)member(base, s->given) = true;
}

void config_table_defaults(const struct config_table *t, void *base)
{
    memset(base, 0, t->size);
    for (int i = 0; i < t->count; i++) {
        const struct config_field *s = &t->fields[i];
        if (s->flags & F_OPTICS_DEFAULT)
            continue;
        switch (s->type) {
        case T_FILES:
            break; /* none */
        case T_STRING:
        case T_PATH:
            snprintf(member(base, s->offset), s->size, "%s", s->def_text ? s->def_text : "");
            break;
        case T_TRANSFER:
            transfer_defaults(member(base, s->offset), TRANSFER_FIELD_QVAPOR);
            break;
        case T_GROUPS:
            assert(s->def_count >= s->min && s->def_count <= s->max);
            if (s->def_count > 0)
                memcpy(member(base, s->offset), s->def_elems,
                       (size_t)s->def_count * s->elems->size);
            *(int *)member(base, s->count_offset) = s->def_count;
            break;
        default:
            for (int sp = 0; sp < instances(s); sp++)
                for (int k = 0; k < s->n; k++)
                    store(s, sp, k, s->def[k], base);
        }
    }
}

/* ------------------------------------------------------------------------------------------ */
/* Formatting                                                                                  */

/* A double the way a libconfig file would spell it: always with a point or an exponent. */
static void format_double(double v, char *buf, size_t size)
{
    snprintf(buf, size, "%.10g", v);
    if (!strpbrk(buf, ".eni"))
        strncat(buf, ".0", size - strlen(buf) - 1);
}

static void format_range(const struct config_field *s, char *buf, size_t size)
{
    snprintf(buf, size, "%c%.15g, %.15g%c", (s->flags & F_MIN_OPEN) ? '(' : '[', s->min, s->max,
             (s->flags & F_MAX_OPEN) ? ')' : ']');
}

static void format_names(const struct config_field *s, char *buf, size_t size)
{
    buf[0] = '\0';
    for (int i = 0; s->names[i]; i++) {
        size_t len = strlen(buf);
        snprintf(buf + len, size - len, "%s\"%s\"", i ? ", " : "", s->names[i]);
    }
}

/* What one value of S must be: "a number in [-90, 90]", "true or false", ... */
static void expectation(const struct config_field *s, bool plural, char *buf, size_t size)
{
    char range[96];
    switch (s->type) {
    case T_BOOL:
        snprintf(buf, size, "true or false");
        break;
    case T_INT:
    case T_UINT:
    case T_DOUBLE:
        format_range(s, range, sizeof(range));
        if (plural)
            snprintf(buf, size, "%s in %s", s->type == T_DOUBLE ? "numbers" : "integers", range);
        else
            snprintf(buf, size, "%s in %s", s->type == T_DOUBLE ? "a number" : "an integer", range);
        break;
    case T_ENUM:
        snprintf(buf, size, "one of ");
        format_names(s, buf + strlen(buf), size - strlen(buf));
        break;
    case T_STRING:
        snprintf(buf, size, "a string of 1 to %zu characters", s->size - 1);
        break;
    case T_PATH:
    case T_FILES:
        snprintf(buf, size, "a file name (a string)");
        break;
    case T_GROUPS:
        snprintf(buf, size, "a list ( { ... }, { ... } ) of %ss", s->elems->elem_name);
        break;
    case T_TRANSFER:
        snprintf(buf, size, "a transfer function: a file name, or its group { field = ...; "
                            "range = [...]; ... } written in place");
        break;
    }
}

/* ------------------------------------------------------------------------------------------ */
/* Values as written, from a file or from --set, before they are checked                      */

enum raw_kind { RAW_INT, RAW_FLOAT, RAW_BOOL, RAW_STRING, RAW_OTHER };

struct where {
    const char *file; /* NULL: the --set option */
    int line;         /* 0: unknown */
};

struct raw {
    enum raw_kind kind;
    long long i;
    double d;
    bool b;
    const char *s; /* RAW_STRING: the text; RAW_OTHER: what it is ("a group") */
    struct where where;
};

#define ELEMS_MAX (CONFIG_MAX_FILES + 1)

struct value {
    struct raw one; /* the setting itself; RAW_OTHER for arrays and lists */
    bool is_list;   /* written as an array or a list */
    int count;      /* is_list: its length (only ELEMS_MAX are kept) */
    struct raw elems[ELEMS_MAX];
};

static void describe(const struct raw *r, char *buf, size_t size)
{
    switch (r->kind) {
    case RAW_INT:
        snprintf(buf, size, "%lld", r->i);
        break;
    case RAW_FLOAT:
        format_double(r->d, buf, size);
        break;
    case RAW_BOOL:
        snprintf(buf, size, "%s", r->b ? "true" : "false");
        break;
    case RAW_STRING:
        snprintf(buf, size, "\"%s\"", r->s);
        break;
    case RAW_OTHER:
        snprintf(buf, size, "%s", r->s);
        break;
    }
}

/* The whole value: "[1, 2.5]" for an array, else as describe(). */
static void describe_value(const struct value *val, char *buf, size_t size)
{
    if (!val->is_list) {
        describe(&val->one, buf, size);
        return;
    }
    snprintf(buf, size, "[");
    for (int k = 0; k < val->count && k < ELEMS_MAX; k++) {
        char one[NAME_MAX_LEN + 8];
        describe(&val->elems[k], one, sizeof(one));
        size_t len = strlen(buf);
        snprintf(buf + len, size - len, "%s%s", k ? ", " : "", one);
    }
    strncat(buf, "]", size - strlen(buf) - 1);
}

static void report(const struct where *w, const char *path, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static void report(const struct where *w, const char *path, const char *fmt, ...)
{
    char msg[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof(msg), fmt, ap);
    va_end(ap);
    if (!w->file)
        log_error("--set %s: %s", path, msg);
    else if (w->line > 0)
        log_error("%s:%d: %s: %s", w->file, w->line, path, msg);
    else
        log_error("%s: %s: %s", w->file, path, msg);
}

/* Checks one written value against S; on success *OUT is the number to store. */
static bool check_number(const struct config_field *s, const struct raw *r, double *out)
{
    bool ok = false;
    double v = 0;
    switch (s->type) {
    case T_BOOL:
        ok = r->kind == RAW_BOOL;
        v = r->b;
        break;
    case T_INT:
    case T_UINT:
    case T_DOUBLE:
        if (r->kind == RAW_INT)
            v = (double)r->i;
        else if (r->kind == RAW_FLOAT && s->type == T_DOUBLE)
            v = r->d;
        else
            break;
        ok = isfinite(v) && ((s->flags & F_MIN_OPEN) ? v > s->min : v >= s->min) &&
             ((s->flags & F_MAX_OPEN) ? v < s->max : v <= s->max);
        break;
    case T_ENUM:
        if (r->kind != RAW_STRING)
            break;
        for (int i = 0; s->names[i]; i++) {
            if (strcmp(s->names[i], r->s) == 0) {
                ok = true;
                v = i;
            }
        }
        break;
    case T_STRING:
    case T_PATH:
    case T_FILES:
    case T_GROUPS:
    case T_TRANSFER:
        assert(!"not a number");
    }
    *out = v;
    return ok;
}

/* As check_number, and says what was expected when R does not fit. */
static bool convert(const struct config_field *s, const struct raw *r, const char *path,
                    double *out)
{
    if (check_number(s, r, out))
        return true;
    char expect[256], got[NAME_MAX_LEN + 8];
    expectation(s, false, expect, sizeof(expect));
    describe(r, got, sizeof(got));
    report(&r->where, path, "expected %s, got %s", expect, got);
    return false;
}

static void dir_of(const char *file, char *buf, size_t size)
{
    const char *slash = strrchr(file, '/');
    if (!slash)
        snprintf(buf, size, "%s", "");
    else if (slash == file)
        snprintf(buf, size, "/");
    else
        snprintf(buf, size, "%.*s", (int)(slash - file), file);
}

/* DIR/NAME, or NAME alone when it is absolute or DIR is empty.  False when too long. */
static bool join_path(const char *dir, const char *name, char *buf, size_t size)
{
    int n;
    if (name[0] == '/' || !dir[0])
        n = snprintf(buf, size, "%s", name);
    else if (dir[strlen(dir) - 1] == '/')
        n = snprintf(buf, size, "%s%s", dir, name);
    else
        n = snprintf(buf, size, "%s/%s", dir, name);
    return n >= 0 && (size_t)n < size;
}

typedef char file_list[CONFIG_MAX_FILES][CONFIG_PATH_MAX];

/* Resolves one entry of data.files against BASE_DIR and appends what it names to LIST. */
static bool add_files(const struct raw *r, const char *path, const char *base_dir, file_list list,
                      int *count)
{
    char full[CONFIG_PATH_MAX] = ""; /* all of it zero: it is copied whole */
    if (!r->s[0]) {
        report(&r->where, path, "expected a file name, got an empty string");
        return false;
    }
    if (!join_path(base_dir, r->s, full, sizeof(full))) {
        report(&r->where, path, "path longer than %d characters", CONFIG_PATH_MAX - 1);
        return false;
    }
    if (!strpbrk(r->s, "*?[")) {
        if (*count >= CONFIG_MAX_FILES)
            goto error_too_many;
        memcpy(list[(*count)++], full, sizeof(full));
        return true;
    }
    glob_t g;
    int rc = glob(full, 0, NULL, &g);
    if (rc == GLOB_NOMATCH) {
        report(&r->where, path, "no file matches \"%s\"", full);
        return false;
    }
    if (rc != 0) {
        report(&r->where, path, "cannot expand \"%s\"", full);
        globfree(&g);
        return false;
    }
    /* The pattern stays one entry: the data reader expands it (and orders the files by
     * their time steps), so a glob may match any number of files. */
    if (*count >= CONFIG_MAX_FILES) {
        globfree(&g);
        goto error_too_many;
    }
    memcpy(list[(*count)++], full, sizeof(full));
    globfree(&g);
    return true;

error_too_many:
    report(&r->where, path, "expected at most %d files", CONFIG_MAX_FILES);
    return false;
}

static bool apply_files(const struct config_field *s, const struct value *val, const char *path,
                        void *base)
{
    assert(s->max == CONFIG_MAX_FILES);
    const struct raw *elems = val->elems;
    int n = val->count;
    if (!val->is_list) {
        if (val->one.kind != RAW_STRING) {
            char got[NAME_MAX_LEN + 8];
            describe(&val->one, got, sizeof(got));
            report(&val->one.where, path, "expected a list of file names, got %s", got);
            return false;
        }
        elems = &val->one;
        n = 1;
    }
    if (n > CONFIG_MAX_FILES) {
        report(&val->one.where, path, "expected at most %d files, got %d", CONFIG_MAX_FILES, n);
        return false;
    }
    file_list *list = calloc(1, sizeof(file_list)); /* zeroed: configs compare bytewise */
    if (!list) {
        report(&val->one.where, path, "out of memory");
        return false;
    }
    int count = 0;
    for (int i = 0; i < n; i++) {
        char elem_path[NAME_MAX_LEN + 16];
        snprintf(elem_path, sizeof(elem_path), "%s[%d]", path, i);
        if (elems[i].kind != RAW_STRING) {
            char got[NAME_MAX_LEN + 8];
            describe(&elems[i], got, sizeof(got));
            report(&elems[i].where, elem_path, "expected a file name (a string), got %s", got);
            goto error_list;
        }
        char dir[CONFIG_PATH_MAX] = "";
        if (elems[i].where.file)
            dir_of(elems[i].where.file, dir, sizeof(dir));
        if (!add_files(&elems[i], elem_path, dir, *list, &count))
            goto error_list;
    }
    memcpy(member(base, s->offset), *list, (size_t)count * CONFIG_PATH_MAX);
    *(int *)member(base, s->count_offset) = count;
    free(list);
    return true;

error_list:
    free(list);
    return false;
}

/* A short string or a path; a relative path from a file is resolved against its folder. */
static bool apply_string(const struct config_field *s, const struct value *val, const char *path,
                         void *base)
{
    char got[NAME_MAX_LEN + 8], expect[128];
    const struct raw *r = &val->one;
    expectation(s, false, expect, sizeof(expect));
    if (val->is_list || r->kind != RAW_STRING) {
        describe_value(val, got, sizeof(got));
        report(&r->where, path, "expected %s, got %s", expect, got);
        return false;
    }
    char *dst = member(base, s->offset);
    if (s->type == T_STRING) {
        size_t len = strlen(r->s);
        if (len < 1 || len >= s->size) {
            describe(r, got, sizeof(got));
            report(&r->where, path, "expected %s, got %s", expect, got);
            return false;
        }
        memcpy(dst, r->s, len + 1);
        return true;
    }
    char dir[CONFIG_PATH_MAX] = "", full[CONFIG_PATH_MAX];
    if (r->where.file && r->s[0])
        dir_of(r->where.file, dir, sizeof(dir));
    if (!join_path(dir, r->s, full, sizeof(full)) || strlen(full) >= s->size) {
        report(&r->where, path, "path longer than %zu characters", s->size - 1);
        return false;
    }
    snprintf(dst, s->size, "%s", full);
    return true;
}

/* A transfer function named by its file: resolved as a path, then read whole (its own
 * messages name that file and line). */
static bool apply_transfer_file(const struct config_field *s, const struct value *val,
                                const char *path, void *base)
{
    const struct raw *r = &val->one;
    char got[NAME_MAX_LEN + 8], expect[160];
    if (val->is_list || r->kind != RAW_STRING || !r->s[0]) {
        expectation(s, false, expect, sizeof(expect));
        describe_value(val, got, sizeof(got));
        report(&r->where, path, "expected %s, got %s", expect, got);
        return false;
    }
    char dir[CONFIG_PATH_MAX] = "", full[CONFIG_PATH_MAX];
    if (r->where.file)
        dir_of(r->where.file, dir, sizeof(dir));
    if (!join_path(dir, r->s, full, sizeof(full))) {
        report(&r->where, path, "path longer than %d characters", CONFIG_PATH_MAX - 1);
        return false;
    }
    FILE *f = fopen(full, "r");
    if (!f) {
        report(&r->where, path, "cannot read the transfer function \"%s\": %s", full,
               strerror(errno));
        return false;
    }
    fclose(f);
    struct transfer_function tf;
    if (!transfer_file_load(full, &tf))
        return false; /* said once, at the transfer function file's line */
    memcpy(member(base, s->offset), &tf, sizeof(tf));
    return true;
}

/* whole_vectors wording: what is wrong with the vector VAL, said of the vector at W. */
static void report_vector(const struct config_field *s, const struct value *val,
                          const struct where *w, const char *path)
{
    char expect[256], got[768];
    expectation(s, false, expect, sizeof(expect));
    describe_value(val, got, sizeof(got));
    report(w, path, "expected [%d numbers] each %s, got %s", s->n, expect, got);
}

/* Checks VAL against S and stores it; nothing is stored unless all of it is valid. */
static bool apply(const struct config_table *t, const struct config_field *s, int sp,
                  const char *path, const struct value *val, void *base)
{
    bool ok;
    switch (s->type) {
    case T_FILES:
        ok = apply_files(s, val, path, base);
        break;
    case T_STRING:
    case T_PATH:
        ok = apply_string(s, val, path, base);
        break;
    case T_TRANSFER:
        if (!val->is_list && val->one.kind == RAW_STRING && strcmp(val->one.s, "none") == 0) {
            /* "none": no transfer function (the default). */
            transfer_defaults(member(base, s->offset), TRANSFER_FIELD_QVAPOR);
            if (s->flags & F_GIVEN)
                *(bool *)member(base, s->given) = false;
            return true;
        }
        ok = apply_transfer_file(s, val, path, base);
        break;
    case T_GROUPS:
        assert(!"lists of groups are read by walk_list and set by element");
        return false;
    default:
        ok = false;
        double v[6];
        if (s->n == 1) {
            ok = convert(s, &val->one, path, &v[0]);
            if (ok)
                store(s, sp, 0, v[0], base);
            break;
        }
        char expect[256], got[NAME_MAX_LEN + 8];
        expectation(s, true, expect, sizeof(expect));
        bool up_to = (s->flags & F_UP_TO) != 0;
        int count = val->is_list ? val->count : 0;
        if (up_to && (!val->is_list || count > s->n)) {
            describe_value(val, got, sizeof(got));
            report(&val->one.where, path, "expected an array of 0 to %d %s, got %s", s->n,
                   expect, got);
            break;
        }
        if (!up_to && (!val->is_list || val->count != s->n)) {
            if (t->whole_vectors) {
                report_vector(s, val, &val->one.where, path);
            } else if (!val->is_list) {
                describe(&val->one, got, sizeof(got));
                report(&val->one.where, path, "expected an array of %d %s, got %s", s->n, expect,
                       got);
            } else {
                report(&val->one.where, path, "expected an array of %d %s, got %d element%s", s->n,
                       expect, val->count, val->count == 1 ? "" : "s");
            }
            break;
        }
        int want = up_to ? count : s->n;
        int k = 0;
        for (; k < want; k++) {
            char elem_path[NAME_MAX_LEN + 16];
            snprintf(elem_path, sizeof(elem_path), "%s[%d]", path, k);
            if (t->whole_vectors ? !check_number(s, &val->elems[k], &v[k])
                                 : !convert(s, &val->elems[k], elem_path, &v[k]))
                break;
        }
        if (k < want) {
            if (t->whole_vectors)
                report_vector(s, val, &val->elems[k].where, path);
            break;
        }
        for (k = 0; k < s->n; k++)
            store(s, sp, k, k < want ? v[k] : 0.0, base);
        if (up_to)
            *(int *)member(base, s->count_offset) = want;
        ok = true;
    }
    if (ok)
        mark_given(s, base);
    return ok;
}

/* ------------------------------------------------------------------------------------------ */
/* Unknown names                                                                               */

static size_t edit_distance(const char *a, const char *b)
{
    size_t la = strlen(a), lb = strlen(b);
    if (la >= NAME_MAX_LEN || lb >= NAME_MAX_LEN)
        return SIZE_MAX;
    size_t row[NAME_MAX_LEN + 1];
    for (size_t j = 0; j <= lb; j++)
        row[j] = j;
    for (size_t i = 1; i <= la; i++) {
        size_t diag = row[0];
        row[0] = i;
        for (size_t j = 1; j <= lb; j++) {
            size_t up = row[j];
            size_t best = diag + (a[i - 1] != b[j - 1]);
            if (up + 1 < best)
                best = up + 1;
            if (row[j - 1] + 1 < best)
                best = row[j - 1] + 1;
            row[j] = best;
            diag = up;
        }
    }
    return row[lb];
}

/* The known name of T closest to PATH (a setting or a group), or "" when none is close. */
static void suggest(const struct config_table *t, const char *path, char *best, size_t size)
{
    char buf[NAME_MAX_LEN];
    size_t best_d = SIZE_MAX, len = strlen(path);
    best[0] = '\0';
    for (int i = 0; i < t->count; i++) {
        for (int sp = 0; sp < instances(&t->fields[i]); sp++) {
            instance_path(&t->fields[i], sp, buf, sizeof(buf));
            /* "elevation" at the top level: the setting of that name in its group. */
            size_t bl = strlen(buf);
            if (bl > len && buf[bl - len - 1] == '.' && strcmp(buf + bl - len, path) == 0) {
                snprintf(best, size, "%s", buf);
                return;
            }
            /* The setting itself and each group above it. */
            for (char *end = buf + bl; end; end = strrchr(buf, '.')) {
                *end = '\0';
                size_t d = edit_distance(path, buf);
                if (d < best_d) {
                    best_d = d;
                    snprintf(best, size, "%s", buf);
                }
            }
        }
    }
    if (best_d > 2 && best_d > len / 4)
        best[0] = '\0';
}

/* The name S has one level below PARENT ("" = the top): "position" for head.position under
 * "head".  False when S is not under PARENT.  *SETTING says whether that name is a setting
 * (else a group, or a list of groups). */
static bool level_name(const struct config_field *s, const char *parent, char *out, size_t size,
                       bool *setting)
{
    char name[NAME_MAX_LEN];
    instance_path(s, 0, name, sizeof(name));
    size_t plen = strlen(parent);
    if (plen && !(strncmp(name, parent, plen) == 0 && name[plen] == '.'))
        return false;
    const char *part = name + (plen ? plen + 1 : 0);
    size_t len = strcspn(part, ".");
    *setting = part[len] == '\0' && s->type != T_GROUPS;
    snprintf(out, size, "%.*s", (int)len, part);
    return true;
}

/* list_known wording: the names known beside PATH's last part ("source, position, ..." for
 * "head.postion"; the top-level names when PATH's group is unknown too).  *GROUPS says
 * whether they are all groups (or lists of groups) rather than settings. */
static void known_beside(const struct config_table *t, const char *path, char *buf, size_t size,
                         bool *groups)
{
    char parent[NAME_MAX_LEN];
    snprintf(parent, sizeof(parent), "%s", path);
    char *dot = strrchr(parent, '.');
    if (dot)
        *dot = '\0';
    else
        parent[0] = '\0';
    if (parent[0] && !is_group_path(t, parent, NULL, 0))
        parent[0] = '\0';
    buf[0] = '\0';
    *groups = true;
    for (int i = 0; i < t->count; i++) {
        char name[NAME_MAX_LEN], earlier[NAME_MAX_LEN];
        bool setting, other;
        if (!level_name(&t->fields[i], parent, name, sizeof(name), &setting))
            continue;
        int j = 0;
        while (j < i && !(level_name(&t->fields[j], parent, earlier, sizeof(earlier), &other) &&
                          strcmp(earlier, name) == 0))
            j++;
        if (j < i)
            continue; /* named already */
        *groups = *groups && !setting;
        size_t len = strlen(buf);
        snprintf(buf + len, size - len, "%s%s", len ? ", " : "", name);
    }
}

/* PATH (in T, below the list element PREFIX when that is not "") is not a setting of T. */
static void report_unknown(const struct config_table *t, const struct where *w, const char *prefix,
                           const char *path)
{
    char full[NAME_MAX_LEN], near[NAME_MAX_LEN], near_full[NAME_MAX_LEN + 32];
    join_name(prefix, path, full, sizeof(full));
    suggest(t, path, near, sizeof(near));
    join_name(prefix, near, near_full, sizeof(near_full));
    if (!t->list_known) {
        if (near[0])
            report(w, full, "unknown setting (did you mean %s?)", near_full);
        else
            report(w, full, "unknown setting");
        return;
    }
    char known[512];
    bool groups;
    known_beside(t, path, known, sizeof(known), &groups);
    if (near[0])
        report(w, full, "expected a known %s (did you mean %s?)", groups ? "group" : "setting",
               near_full);
    else if (groups)
        report(w, full, "expected a known group (%s)", known);
    else
        report(w, full, "expected a known setting (one of %s)", known);
}

bool config_table_owns(const struct config_table *t, const char *path)
{
    path += strspn(path, " \t");
    size_t len = strcspn(path, ".[= \t");
    for (int i = 0; i < t->count; i++) {
        const char *p = t->fields[i].path;
        if (strncmp(p, path, len) == 0 && (p[len] == '.' || p[len] == '\0'))
            return len > 0;
    }
    return false;
}

/* ------------------------------------------------------------------------------------------ */
/* --set                                                                                       */

static char *trim(char *s)
{
    while (isspace((unsigned char)*s))
        s++;
    char *end = s + strlen(s);
    while (end > s && isspace((unsigned char)end[-1]))
        *--end = '\0';
    return s;
}

static char *strip_quotes(char *s)
{
    size_t len = strlen(s);
    if (len >= 2 && s[0] == '"' && s[len - 1] == '"') {
        s[len - 1] = '\0';
        return s + 1;
    }
    return s;
}

/* One value from command-line text, read the way setting S expects. */
static void raw_from_text(const struct config_field *s, char *text, struct raw *r)
{
    memset(r, 0, sizeof(*r));
    text = trim(text);
    if (s->type == T_ENUM || s->type == T_FILES || s->type == T_STRING || s->type == T_PATH ||
        s->type == T_TRANSFER) {
        r->kind = RAW_STRING;
        r->s = strip_quotes(text);
        return;
    }
    if (!text[0]) {
        r->kind = RAW_OTHER;
        r->s = "nothing";
        return;
    }
    static const char *const truths[] = {"true", "yes", "on"};
    static const char *const falsehoods[] = {"false", "no", "off"};
    for (int i = 0; i < 3; i++) {
        if (strcasecmp(text, truths[i]) == 0 || strcasecmp(text, falsehoods[i]) == 0) {
            r->kind = RAW_BOOL;
            r->b = strcasecmp(text, truths[i]) == 0;
            return;
        }
    }
    char *end;
    errno = 0;
    long long i = strtoll(text, &end, 10);
    if (!*end && errno == 0) {
        r->kind = RAW_INT;
        r->i = i;
        return;
    }
    errno = 0;
    double d = strtod(text, &end);
    if (!*end && isfinite(d)) {
        r->kind = RAW_FLOAT;
        r->d = d;
        return;
    }
    r->kind = RAW_STRING;
    r->s = text;
}

/* A --set PATH inside a list element, "walls.[2].mode": *T, *BASE and *REST become the
 * element's table, the element and "mode".  False (reported) when PATH names a list but no
 * element's setting; true with nothing changed when PATH is not in a list. */
static bool find_element(const struct config_table **t, void **base, const char *path,
                         const char **rest)
{
    *rest = path;
    for (int i = 0; i < (*t)->count; i++) {
        const struct config_field *s = &(*t)->fields[i];
        size_t len = strlen(s->path);
        if (s->type != T_GROUPS || strncmp(path, s->path, len) != 0 || path[len] != '.')
            continue;
        struct where w = {NULL, 0};
        int count = *(int *)member(*base, s->count_offset);
        const char *p = path + len + 1, *name = s->elems->elem_name;
        char *end = NULL;
        long index = -1;
        if (*p == '[' && isdigit((unsigned char)p[1]))
            index = strtol(p + 1, &end, 10);
        if (!end || *end != ']' || (end[1] != '.' && end[1] != '\0')) {
            report(&w, path, "expected %s.[INDEX].SETTING, INDEX in [0, %d] (one of the %d %ss)",
                   s->path, count - 1, count, name);
            return false;
        }
        if (index >= count) {
            report(&w, path, "expected a %s index in [0, %d] (there %s %d %s%s), got %ld", name,
                   count - 1, count == 1 ? "is" : "are", count, name, count == 1 ? "" : "s", index);
            return false;
        }
        if (end[1] == '\0') {
            report(&w, path, "expected a setting, not a group (e.g. %s.%s)", path,
                   s->elems->fields[0].path);
            return false;
        }
        *base = (char *)member(*base, s->offset) + (size_t)index * s->elems->size;
        *t = s->elems;
        *rest = end + 2;
        return true;
    }
    return true;
}

bool config_table_set(const struct config_table *t, void *base, const char *assignment)
{
    char *copy = strdup(assignment);
    if (!copy) {
        log_error("--set %s: out of memory", assignment);
        return false;
    }
    bool ok = false;
    char *eq = strchr(copy, '=');
    if (!eq) {
        log_error("--set %s: expected SETTING=VALUE, e.g. %s", assignment, t->example);
        goto done;
    }
    *eq = '\0';
    char *path = trim(copy), *text = trim(eq + 1);
    if (!*path) {
        log_error("--set %s: no setting before the '=': expected SETTING=VALUE, e.g. %s",
                  assignment, t->example);
        goto done;
    }
    const char *rel;
    if (!find_element(&t, &base, path, &rel))
        goto done;
    char prefix[NAME_MAX_LEN];
    snprintf(prefix, sizeof(prefix), "%.*s", rel > path ? (int)(rel - path - 1) : 0, path);
    const struct config_field *s;
    int sp;
    struct where w = {NULL, 0};
    if (!find_setting(t, rel, &s, &sp)) {
        char example[NAME_MAX_LEN], full[NAME_MAX_LEN + 32];
        if (is_group_path(t, rel, example, sizeof(example))) {
            join_name(prefix, example, full, sizeof(full));
            report(&w, path, "expected a setting, not a group (e.g. %s)", full);
        } else {
            report_unknown(t, &w, prefix, rel);
        }
        goto done;
    }
    if (s->type == T_GROUPS) {
        report(&w, path, "expected a setting, not a list of %ss (e.g. %s.[0].%s)",
               s->elems->elem_name, path, s->elems->fields[0].path);
        goto done;
    }

    struct value val;
    memset(&val, 0, sizeof(val));
    if (s->n > 1 || s->type == T_FILES) {
        size_t len = strlen(text);
        if (len >= 2 && ((text[0] == '[' && text[len - 1] == ']') ||
                         (text[0] == '(' && text[len - 1] == ')'))) {
            text[len - 1] = '\0';
            text = trim(text + 1);
        }
        val.is_list = true;
        val.one.kind = RAW_OTHER;
        val.one.s = "an array";
        if (text[0]) {
            for (char *item = text;;) {
                char *comma = strchr(item, ',');
                if (comma)
                    *comma = '\0';
                if (val.count < ELEMS_MAX)
                    raw_from_text(s, item, &val.elems[val.count]);
                val.count++;
                if (!comma)
                    break;
                item = comma + 1;
            }
        }
    } else {
        raw_from_text(s, text, &val.one);
    }
    ok = apply(t, s, sp, path, &val, base);

done:
    free(copy);
    return ok;
}

/* ------------------------------------------------------------------------------------------ */
/* Files: @include expansion with a line map                                                   */

/* An @include at the top level (outside any group) starts a new chunk, and the rest of the
 * including file another one.  Chunks are parsed one after the other, so a group written in a
 * later chunk adds to and overrides the same group of an earlier one instead of being a
 * duplicate; an @include inside a group is plain text substitution. */

struct origin {
    int file; /* index into source.files */
    int line;
};

struct chunk {
    char *text;
    size_t len, cap;
    struct origin *lines; /* lines[i]: where line i + 1 of TEXT came from */
    int line_count, line_cap;
};

struct source {
    struct chunk *chunks;
    int chunk_count;
    int depth; /* of brackets open at the end of the text so far */
    char **files;
    int file_count;
    struct stat chain[INCLUDE_DEPTH_MAX + 1]; /* the files being expanded, outermost first */
};

static bool new_chunk(struct source *src)
{
    struct chunk *grown = realloc(src->chunks, (size_t)(src->chunk_count + 1) * sizeof(*grown));
    if (!grown)
        return false;
    src->chunks = grown;
    memset(&src->chunks[src->chunk_count++], 0, sizeof(struct chunk));
    return true;
}

static bool append_text(struct chunk *ch, const char *s, size_t n)
{
    if (ch->len + n + 1 > ch->cap) {
        size_t cap = ch->cap ? ch->cap : 4096;
        while (ch->len + n + 1 > cap)
            cap *= 2;
        char *grown = realloc(ch->text, cap);
        if (!grown)
            return false;
        ch->text = grown;
        ch->cap = cap;
    }
    memcpy(ch->text + ch->len, s, n);
    ch->len += n;
    ch->text[ch->len] = '\0';
    return true;
}

static bool append_line(struct source *src, const char *s, size_t n, int file, int line)
{
    struct chunk *ch = &src->chunks[src->chunk_count - 1];
    if (ch->line_count == ch->line_cap) {
        int cap = ch->line_cap ? ch->line_cap * 2 : 256;
        struct origin *grown = realloc(ch->lines, (size_t)cap * sizeof(*grown));
        if (!grown)
            return false;
        ch->lines = grown;
        ch->line_cap = cap;
    }
    ch->lines[ch->line_count++] = (struct origin){file, line};
    return append_text(ch, s, n) && append_text(ch, "\n", 1);
}

static int add_file_name(struct source *src, const char *path)
{
    char **grown = realloc(src->files, (size_t)(src->file_count + 1) * sizeof(*grown));
    if (!grown)
        return -1;
    src->files = grown;
    src->files[src->file_count] = strdup(path);
    if (!src->files[src->file_count])
        return -1;
    return src->file_count++;
}

static void source_finish(struct source *src)
{
    for (int i = 0; i < src->file_count; i++)
        free(src->files[i]);
    free(src->files);
    for (int i = 0; i < src->chunk_count; i++) {
        free(src->chunks[i].lines);
        free(src->chunks[i].text);
    }
    free(src->chunks);
}

/* File and line of line LINE (from 1) of chunk CH. */
static struct where locate(const struct source *src, const struct chunk *ch, int line)
{
    if (ch->line_count == 0)
        return (struct where){src->files[0], 0};
    if (line < 1)
        line = 1;
    if (line > ch->line_count)
        line = ch->line_count;
    const struct origin *o = &ch->lines[line - 1];
    return (struct where){src->files[o->file], o->line};
}

/* Follows block comments and open brackets through line L..END. */
static void scan_line(const char *l, const char *end, bool *in_comment, int *depth)
{
    bool in_string = false;
    for (const char *p = l; p < end; p++) {
        if (*in_comment) {
            if (p[0] == '*' && p + 1 < end && p[1] == '/') {
                *in_comment = false;
                p++;
            }
        } else if (in_string) {
            if (*p == '\\' && p + 1 < end)
                p++;
            else if (*p == '"')
                in_string = false;
        } else if (*p == '"') {
            in_string = true;
        } else if (*p == '#' || (p[0] == '/' && p + 1 < end && p[1] == '/')) {
            break;
        } else if (p[0] == '/' && p + 1 < end && p[1] == '*') {
            *in_comment = true;
            p++;
        } else if (*p == '{' || *p == '(' || *p == '[') {
            (*depth)++;
        } else if (*p == '}' || *p == ')' || *p == ']') {
            (*depth)--;
        }
    }
}

static bool expand_file(struct source *src, const char *path, int depth, const struct where *from);

/* An @include line: expands the named file relative to the one that names it. */
static bool expand_include(struct source *src, const char *line, const char *end, int depth,
                           const struct where *here)
{
    const char *p = line + strlen("@include");
    while (p < end && (*p == ' ' || *p == '\t'))
        p++;
    const char *name = p + 1, *close = NULL;
    if (p < end && *p == '"')
        close = memchr(name, '"', (size_t)(end - name));
    if (!close) {
        log_error("%s:%d: syntax error: expected @include \"FILE\"", here->file, here->line);
        return false;
    }
    for (p = close + 1; p < end && (*p == ' ' || *p == '\t' || *p == '\r'); p++)
        ;
    if (p < end && *p != '#' && !(p[0] == '/' && p + 1 < end && p[1] == '/')) {
        log_error("%s:%d: syntax error: unexpected text after @include \"FILE\"", here->file,
                  here->line);
        return false;
    }
    char rel[CONFIG_PATH_MAX], dir[CONFIG_PATH_MAX], full[CONFIG_PATH_MAX];
    if ((size_t)(close - name) >= sizeof(rel)) {
        /* Cut short, the name could be another file's. */
        log_error("%s:%d: @include: a name of %zu characters (at most %zu)", here->file, here->line,
                  (size_t)(close - name), sizeof(rel) - 1);
        return false;
    }
    snprintf(rel, sizeof(rel), "%.*s", (int)(close - name), name);
    dir_of(here->file, dir, sizeof(dir));
    if (!join_path(dir, rel, full, sizeof(full))) {
        log_error("%s:%d: @include \"%s\": path too long", here->file, here->line, rel);
        return false;
    }
    return expand_file(src, full, depth + 1, here);
}

/* Appends PATH, with its @include lines expanded, to SRC.  FROM is the @include that names it
 * (NULL for the top file). */
static bool expand_file(struct source *src, const char *path, int depth, const struct where *from)
{
    if (depth > INCLUDE_DEPTH_MAX) {
        log_error("%s:%d: @include: nested more than %d deep (an include cycle?)", from->file,
                  from->line, INCLUDE_DEPTH_MAX);
        return false;
    }
    char why[160];
    size_t len = 0;
    char *text = file_read_text(path, FILE_TEXT_MAX, &len, why, sizeof(why));
    if (!text) {
        if (from)
            log_error("%s:%d: @include: %s: %s", from->file, from->line, path, why);
        else
            log_error("%s: %s", path, why);
        return false;
    }
    if (strlen(text) != len) {
        log_error("%s: not a text file (a NUL byte at offset %zu)", path, strlen(text));
        free(text);
        return false;
    }
    struct stat st;
    if (stat(path, &st) == 0) {
        for (int i = 0; i < depth; i++) {
            if (src->chain[i].st_dev == st.st_dev && src->chain[i].st_ino == st.st_ino) {
                log_error("%s:%d: @include: include cycle through %s", from->file, from->line,
                          path);
                free(text);
                return false;
            }
        }
        src->chain[depth] = st;
    }
    int file = add_file_name(src, path);
    if (file < 0) {
        log_error("%s: out of memory", path);
        free(text);
        return false;
    }

    bool ok = true, in_comment = false;
    int number = 0;
    for (const char *l = text; ok && *l;) {
        const char *end = strchr(l, '\n');
        const char *next = end ? end + 1 : l + strlen(l);
        if (!end)
            end = next;
        number++;
        const char *p = l;
        while (p < end && (*p == ' ' || *p == '\t'))
            p++;
        if (!in_comment && (size_t)(end - p) >= 8 && strncmp(p, "@include", 8) == 0) {
            struct where here = {src->files[file], number};
            bool top = src->depth <= 0;
            if (top && !new_chunk(src))
                goto error_memory;
            ok = expand_include(src, p, end, depth, &here);
            if (ok && top && !new_chunk(src))
                goto error_memory;
        } else {
            scan_line(l, end, &in_comment, &src->depth);
            if (!append_line(src, l, (size_t)(end - l), file, number))
                goto error_memory;
        }
        l = next;
    }
    free(text);
    return ok;

error_memory:
    log_error("%s: out of memory", path);
    free(text);
    return false;
}

/* ------------------------------------------------------------------------------------------ */
/* Where each setting was read                                                                 */

static bool trace_add(struct config_trace *tr, const char *path, const struct where *w)
{
    if (!tr)
        return true;
    if (tr->count == tr->cap) {
        int cap = tr->cap ? 2 * tr->cap : 64;
        struct config_trace_entry *grown = realloc(tr->entries, (size_t)cap * sizeof(*grown));
        if (!grown)
            goto error_memory;
        tr->entries = grown;
        tr->cap = cap;
    }
    struct config_trace_entry *e = &tr->entries[tr->count];
    e->path = strdup(path);
    e->file = strdup(w->file ? w->file : "");
    e->line = w->line;
    if (!e->path || !e->file) {
        free(e->path);
        free(e->file);
        goto error_memory;
    }
    tr->count++;
    return true;

error_memory:
    log_error("%s: out of memory", w->file ? w->file : path);
    return false;
}

bool config_trace_find(const struct config_trace *trace, const char *path, const char **file,
                       int *line)
{
    for (int i = trace ? trace->count - 1 : -1; i >= 0; i--) {
        if (strcmp(trace->entries[i].path, path) == 0) {
            *file = trace->entries[i].file;
            *line = trace->entries[i].line;
            return true;
        }
    }
    return false;
}

void config_trace_finish(struct config_trace *trace)
{
    for (int i = 0; i < trace->count; i++) {
        free(trace->entries[i].path);
        free(trace->entries[i].file);
    }
    free(trace->entries);
    memset(trace, 0, sizeof(*trace));
}

/* ------------------------------------------------------------------------------------------ */
/* Files: the walker                                                                           */

struct reader {
    const struct source *src;
    const struct chunk *ch;
    struct config_trace *trace; /* may be NULL */
};

static void raw_from_setting(const struct reader *rd, const config_setting_t *st, struct raw *r)
{
    memset(r, 0, sizeof(*r));
    switch (config_setting_type(st)) {
    case CONFIG_TYPE_INT:
    case CONFIG_TYPE_INT64:
        r->kind = RAW_INT;
        r->i = config_setting_get_int64(st);
        break;
    case CONFIG_TYPE_FLOAT:
        r->kind = RAW_FLOAT;
        r->d = config_setting_get_float(st);
        break;
    case CONFIG_TYPE_BOOL:
        r->kind = RAW_BOOL;
        r->b = config_setting_get_bool(st);
        break;
    case CONFIG_TYPE_STRING:
        r->kind = RAW_STRING;
        r->s = config_setting_get_string(st);
        break;
    case CONFIG_TYPE_GROUP:
        r->kind = RAW_OTHER;
        r->s = "a group";
        break;
    case CONFIG_TYPE_ARRAY:
        r->kind = RAW_OTHER;
        r->s = "an array";
        break;
    default:
        r->kind = RAW_OTHER;
        r->s = "a list";
        break;
    }
    r->where = locate(rd->src, rd->ch, config_setting_source_line(st));
}

static bool walk_group(const struct reader *rd, const config_setting_t *group,
                       const struct config_table *t, void *base, const char *prefix,
                       const char *rel);

/* The list of groups LIST for setting S (at PATH): every element is filled from S's element
 * defaults and the element table; the list replaces what was there. */
static bool walk_list(const struct reader *rd, const config_setting_t *list,
                      const struct config_field *s, void *base, const char *path)
{
    const struct config_table *et = s->elems;
    struct raw r;
    raw_from_setting(rd, list, &r);
    char got[NAME_MAX_LEN + 8];
    if (!config_setting_is_list(list)) {
        describe(&r, got, sizeof(got));
        report(&r.where, path, "expected a list ( { ... }, { ... } ) of %ss, got %s", et->elem_name,
               got);
        return false;
    }
    int n = config_setting_length(list);
    if (n < s->min || n > s->max) {
        report(&r.where, path, "expected %g to %g %ss, got %d", s->min, s->max, et->elem_name, n);
        return false;
    }
    for (int i = 0; i < n; i++) {
        const config_setting_t *g = config_setting_get_elem(list, (unsigned)i);
        char elem_path[NAME_MAX_LEN];
        element_path(path, i, elem_path, sizeof(elem_path));
        struct raw er;
        raw_from_setting(rd, g, &er);
        if (!config_setting_is_group(g)) {
            describe(&er, got, sizeof(got));
            report(&er.where, elem_path, "expected a group { ... }, got %s", got);
            return false;
        }
        if (!trace_add(rd->trace, elem_path, &er.where))
            return false;
        void *elem = (char *)member(base, s->offset) + (size_t)i * et->size;
        config_table_defaults(et, elem);
        if (!walk_group(rd, g, et, elem, elem_path, ""))
            return false;
        for (int k = 0; k < et->count; k++) {
            const char *name = et->fields[k].path;
            if ((et->fields[k].flags & F_REQUIRED) && !config_setting_get_member(g, name)) {
                char missing[NAME_MAX_LEN + 32];
                join_name(elem_path, name, missing, sizeof(missing));
                report(&er.where, missing, "expected a setting \"%s\" in every %s", name,
                       et->elem_name);
                return false;
            }
        }
    }
    *(int *)member(base, s->count_offset) = n;
    mark_given(s, base);
    return true;
}

static void locate_line(void *user, int line, const char **file, int *file_line)
{
    const struct reader *rd = user;
    struct where w = locate(rd->src, rd->ch, line);
    *file = w.file;
    *file_line = w.line;
}

/* A transfer function written in place (look.transfer = { ... };), read as its file would
 * be, its messages at the scene file's lines. */
static bool walk_transfer(const struct reader *rd, const config_setting_t *g,
                          const struct config_field *s, void *base, const char *path)
{
    struct raw r;
    raw_from_setting(rd, g, &r);
    struct transfer_where w = {
        .file = r.where.file, .prefix = path, .locate = locate_line, .user = (void *)rd};
    struct transfer_function tf;
    if (!transfer_group_read(g, &w, &tf))
        return false;
    memcpy(member(base, s->offset), &tf, sizeof(tf));
    mark_given(s, base);
    return true;
}

/* Applies the settings of GROUP, whose path in T is REL ("" for the root); PREFIX names the
 * list element T fills ("" outside lists) in messages. */
static bool walk_group(const struct reader *rd, const config_setting_t *group,
                       const struct config_table *t, void *base, const char *prefix,
                       const char *rel)
{
    struct value val;
    int n = config_setting_length(group);
    for (int i = 0; i < n; i++) {
        const config_setting_t *child = config_setting_get_elem(group, i);
        char path[NAME_MAX_LEN], full[2 * NAME_MAX_LEN];
        join_name(rel, config_setting_name(child), path, sizeof(path));
        join_name(prefix, path, full, sizeof(full));
        const struct config_field *s;
        int sp;
        memset(&val, 0, sizeof(val));
        raw_from_setting(rd, child, &val.one);
        if (!trace_add(rd->trace, full, &val.one.where))
            return false;
        if (find_setting(t, path, &s, &sp)) {
            if (s->type == T_GROUPS) {
                if (!walk_list(rd, child, s, base, full))
                    return false;
                continue;
            }
            if (s->type == T_TRANSFER && config_setting_is_group(child)) {
                if (!walk_transfer(rd, child, s, base, full))
                    return false;
                continue;
            }
            val.is_list = config_setting_is_array(child) || config_setting_is_list(child);
            if (val.is_list) {
                val.count = config_setting_length(child);
                for (int k = 0; k < val.count && k < ELEMS_MAX; k++)
                    raw_from_setting(rd, config_setting_get_elem(child, k), &val.elems[k]);
            }
            if (!apply(t, s, sp, full, &val, base))
                return false;
        } else if (is_group_path(t, path, NULL, 0)) {
            if (!config_setting_is_group(child)) {
                char got[NAME_MAX_LEN + 8];
                describe(&val.one, got, sizeof(got));
                report(&val.one.where, full, "expected a group { ... }, got %s", got);
                return false;
            }
            if (!walk_group(rd, child, t, base, prefix, path))
                return false;
        } else {
            report_unknown(t, &val.one.where, prefix, path);
            return false;
        }
    }
    return true;
}

/* Debian's libconfig 1.5 reads an integer without the L suffix into an int, so 4294967297
 * became 1 (and 0x100000010, 16), and it has no NaN or infinity: "nan" is a bare syntax
 * error.  Before libconfig sees a chunk, its literals are checked here: an integer outside
 * the int range gets the L that makes libconfig read it whole (the table's ranges then judge
 * it), one beyond 64 bits and a NaN or infinity where a value goes are refused with the file
 * and line.  Line breaks are kept, so libconfig's line numbers still map.  Returns the
 * checked text (the caller frees it), or NULL after one log_error. */

static bool name_char(char c, bool first)
{
    return isalpha((unsigned char)c) || c == '*' ||
           (!first && (isdigit((unsigned char)c) || c == '-' || c == '_'));
}

static char *check_literals(const struct source *src, const struct chunk *ch)
{
    const char *t = ch->text ? ch->text : "";
    size_t len = strlen(t), n = 0;
    char *out = malloc(2 * len + 1); /* at most one L per literal */
    if (!out) {
        log_error("%s: out of memory", locate(src, ch, 1).file);
        return NULL;
    }
    int line = 1;
    char last = ';'; /* the last character that was not blank or a comment */
    /* An array's elements must share a type: in an array with one wide integer, every integer
     * gets the L.  Where its integers end in OUT, and whether one is wide. */
    bool in_array = false, array_wide = false;
    size_t *ends = NULL, n_ends = 0, cap_ends = 0;
    for (size_t i = 0; i < len;) {
        char c = t[i];
        if (c == '\n') {
            line++;
            out[n++] = t[i++];
        } else if (c == '"') { /* a string, with its escapes, over lines if it goes on */
            int first = line;
            out[n++] = t[i++];
            while (i < len && t[i] != '"') {
                if (t[i] == '\\' && i + 1 < len)
                    out[n++] = t[i++];
                line += t[i] == '\n';
                out[n++] = t[i++];
            }
            if (i >= len) {
                /* (libconfig 1.5 also leaks its string buffer over this) */
                struct where w = locate(src, ch, first);
                log_error("%s:%d: syntax error: a string without its closing quote", w.file,
                          w.line);
                free(ends);
                free(out);
                return NULL;
            }
            out[n++] = t[i++];
            last = '"';
        } else if (c == '#' || (c == '/' && i + 1 < len && t[i + 1] == '/')) {
            while (i < len && t[i] != '\n')
                out[n++] = t[i++];
        } else if (c == '/' && i + 1 < len && t[i + 1] == '*') {
            out[n++] = t[i++];
            out[n++] = t[i++];
            while (i < len && !(t[i] == '*' && i + 1 < len && t[i + 1] == '/')) {
                line += t[i] == '\n';
                out[n++] = t[i++];
            }
            for (int k = 0; k < 2 && i < len; k++)
                out[n++] = t[i++];
        } else if (name_char(c, true) ||
                   ((c == '-' || c == '+') && i + 1 < len && isalpha((unsigned char)t[i + 1]))) {
            size_t start = i;
            if (c == '-' || c == '+')
                out[n++] = t[i++];
            size_t word = i;
            while (i < len && name_char(t[i], i == word))
                out[n++] = t[i++];
            char token[16];
            size_t wl = i - word;
            snprintf(token, sizeof(token), "%.*s", (int)(wl < 15 ? wl : 15), t + word);
            bool value_place =
                last == '=' || last == ':' || last == ',' || last == '[' || last == '(';
            if (value_place && (strcasecmp(token, "nan") == 0 || strcasecmp(token, "inf") == 0 ||
                                strcasecmp(token, "infinity") == 0)) {
                struct where w = locate(src, ch, line);
                log_error("%s:%d: %.*s: expected a finite number (libconfig has no NaN or "
                          "infinity)",
                          w.file, w.line, (int)(i - start), t + start);
                free(ends);
                free(out);
                return NULL;
            }
            last = 'a';
        } else if (isdigit((unsigned char)c) ||
                   ((c == '-' || c == '+') && i + 1 < len && isdigit((unsigned char)t[i + 1]))) {
            size_t start = i;
            bool negative = c == '-';
            if (c == '-' || c == '+')
                i++;
            bool hex = t[i] == '0' && i + 1 < len && (t[i + 1] == 'x' || t[i + 1] == 'X');
            size_t digits = hex ? i + 2 : i, end = digits;
            while (end < len &&
                   (hex ? isxdigit((unsigned char)t[end]) : isdigit((unsigned char)t[end])))
                end++;
            bool is_float = !hex && end < len && (t[end] == '.' || t[end] == 'e' || t[end] == 'E');
            if (is_float) { /* copied as it is, exponent and all */
                end++;
                while (end < len && (isdigit((unsigned char)t[end]) || t[end] == 'e' ||
                                     t[end] == 'E' || t[end] == '.' ||
                                     ((t[end] == '-' || t[end] == '+') &&
                                      (t[end - 1] == 'e' || t[end - 1] == 'E'))))
                    end++;
            }
            memcpy(out + n, t + start, end - start);
            n += end - start;
            i = end;
            last = '0';
            if (is_float || (i < len && t[i] == 'L'))
                continue;
            /* The magnitude, saturated above 2^64. */
            unsigned long long v = 0;
            bool huge = false;
            for (size_t k = digits; k < end; k++) {
                unsigned d = isdigit((unsigned char)t[k])
                                 ? (unsigned)(t[k] - '0')
                                 : (unsigned)(tolower((unsigned char)t[k]) - 'a' + 10);
                unsigned base = hex ? 16 : 10;
                if (v > (ULLONG_MAX - d) / base)
                    huge = true;
                else
                    v = v * base + d;
            }
            if (huge || (!hex && v > (unsigned long long)LLONG_MAX + (negative ? 1u : 0u)) ||
                (hex && v > (unsigned long long)LLONG_MAX)) {
                struct where w = locate(src, ch, line);
                log_error("%s:%d: %.*s: expected an integer of at most 64 bits", w.file, w.line,
                          (int)(end - start), t + start);
                free(ends);
                free(out);
                return NULL;
            }
            bool fits = hex ? v <= (unsigned long long)INT_MAX
                            : (negative ? v <= (unsigned long long)INT_MAX + 1u
                                        : v <= (unsigned long long)INT_MAX);
            if (in_array) {
                array_wide = array_wide || !fits;
                if (n_ends == cap_ends) {
                    cap_ends = cap_ends ? 2 * cap_ends : 16;
                    size_t *grown = realloc(ends, cap_ends * sizeof(*ends));
                    if (!grown) {
                        log_error("%s: out of memory", locate(src, ch, line).file);
                        free(ends);
                        free(out);
                        return NULL;
                    }
                    ends = grown;
                }
                ends[n_ends++] = n;
            } else if (!fits) {
                out[n++] = 'L';
            }
        } else {
            if (c == '[') {
                in_array = true;
                array_wide = false;
                n_ends = 0;
            } else if (c == ']' && in_array) {
                in_array = false;
                /* Widen every integer of the array: insert the L's from the last one back. */
                if (array_wide) {
                    size_t shift = n_ends, tail = n;
                    for (size_t k = n_ends; k-- > 0;) {
                        memmove(out + ends[k] + shift, out + ends[k], tail - ends[k]);
                        out[ends[k] + shift - 1] = 'L';
                        tail = ends[k];
                        shift--;
                    }
                    n += n_ends;
                }
            }
            if (c != ' ' && c != '\t' && c != '\r')
                last = c;
            out[n++] = t[i++];
        }
    }
    free(ends);
    out[n] = '\0';
    return out;
}

/* Parses one chunk and applies what it sets. */
static bool read_chunk(const struct source *src, const struct chunk *ch,
                       const struct config_table *t, void *base, struct config_trace *trace)
{
    if (ch->line_count > USHRT_MAX) {
        /* config_setting_source_line() is an unsigned short */
        struct where w = locate(src, ch, 1);
        log_error("%s: more than %d lines in one piece with its includes", w.file, USHRT_MAX);
        return false;
    }
    char *checked = check_literals(src, ch);
    if (!checked)
        return false;
    config_t lc;
    config_init(&lc);
    bool ok = false;
    if (!config_read_string(&lc, checked)) {
        struct where w = locate(src, ch, config_error_line(&lc));
        const char *text = config_error_text(&lc);
        if (strcmp(text, "syntax error") == 0)
            log_error("%s:%d: syntax error", w.file, w.line);
        else if (strstr(text, "mismatched element type"))
            log_error("%s:%d: syntax error: %s (write every number of an array alike: 1.0, "
                      "not 1)",
                      w.file, w.line, text);
        else
            log_error("%s:%d: syntax error: %s", w.file, w.line, text);
        goto done;
    }
    struct reader rd = {src, ch, trace};
    ok = walk_group(&rd, config_root_setting(&lc), t, base, "", "");
done:
    config_destroy(&lc);
    free(checked);
    return ok;
}

bool config_table_read(const struct config_table *t, const char *path, void *base,
                       struct config_trace *trace)
{
    struct source src = {0};
    bool ok = new_chunk(&src);
    if (!ok)
        log_error("%s: out of memory", path);
    ok = ok && expand_file(&src, path, 0, NULL);
    for (int i = 0; ok && i < src.chunk_count; i++)
        ok = read_chunk(&src, &src.chunks[i], t, base, trace);
    source_finish(&src);
    return ok;
}

/* ------------------------------------------------------------------------------------------ */
/* Reference                                                                                   */

static void format_value(const struct config_field *s, int sp, const void *base, char *buf,
                         size_t size);

/* A list of groups as a file would write it, each element with the settings that differ from
 * an element's defaults (and the required ones). */
static void format_groups(const struct config_field *s, const void *base, char *buf, size_t size)
{
    const struct config_table *et = s->elems;
    void *blank = calloc(1, et->size);
    assert(blank);
    config_table_defaults(et, blank);
    int n = *(const int *)member((void *)base, s->count_offset);
    snprintf(buf, size, "(");
    for (int i = 0; i < n; i++) {
        const void *elem = (const char *)member((void *)base, s->offset) + (size_t)i * et->size;
        strncat(buf, i ? ", {" : " {", size - strlen(buf) - 1);
        for (int k = 0; k < et->count; k++) {
            const struct config_field *f = &et->fields[k];
            char mine[512], plain[512];
            format_value(f, 0, elem, mine, sizeof(mine));
            format_value(f, 0, blank, plain, sizeof(plain));
            if (!(f->flags & F_REQUIRED) && strcmp(mine, plain) == 0)
                continue;
            size_t len = strlen(buf);
            snprintf(buf + len, size - len, " %s = %s;", f->path, mine);
        }
        strncat(buf, " }", size - strlen(buf) - 1);
    }
    strncat(buf, " )", size - strlen(buf) - 1);
    free(blank);
}

/* The value of S in BASE as a file would write it. */
static void format_value(const struct config_field *s, int sp, const void *base, char *buf,
                         size_t size)
{
    switch (s->type) {
    case T_FILES:
        snprintf(buf, size, "[]");
        return;
    case T_STRING:
    case T_PATH:
        snprintf(buf, size, "\"%s\"", (const char *)member((void *)base, s->offset));
        return;
    case T_GROUPS:
        format_groups(s, base, buf, size);
        return;
    case T_TRANSFER:
        snprintf(buf, size, "\"none\"");
        return;
    default:
        break;
    }
    buf[0] = '\0';
    if (s->n > 1)
        strncat(buf, "[", size - 1);
    int shown = (s->flags & F_UP_TO) ? *(const int *)member((void *)base, s->count_offset) : s->n;
    for (int k = 0; k < shown; k++) {
        char num[64];
        double v = fetch(s, sp, k, base);
        if (s->type == T_DOUBLE)
            format_double(v, num, sizeof(num));
        else if (s->type == T_BOOL)
            snprintf(num, sizeof(num), "%s", v != 0 ? "true" : "false");
        else if (s->type == T_ENUM)
            snprintf(num, sizeof(num), "\"%s\"", s->names[(int)v]);
        else
            snprintf(num, sizeof(num), "%.0f", v);
        if (k)
            strncat(buf, ", ", size - strlen(buf) - 1);
        strncat(buf, num, size - strlen(buf) - 1);
    }
    if (s->n > 1)
        strncat(buf, "]", size - strlen(buf) - 1);
}

static void write_rows(const struct config_table *t, const void *defaults, const char *prefix,
                       FILE *out)
{
    static const char *const type_names[] = {
        [T_BOOL] = "bool",
        [T_INT] = "int",
        [T_UINT] = "int",
        [T_DOUBLE] = "float",
        [T_ENUM] = "string",
        [T_STRING] = "string",
        [T_PATH] = "path",
        [T_FILES] = "list of strings",
        [T_GROUPS] = "list of groups",
        [T_TRANSFER] = "path or group",
    };
    for (int i = 0; i < t->count; i++) {
        const struct config_field *s = &t->fields[i];
        char type[32], range[160], value[1024];
        if (s->flags & F_UP_TO)
            snprintf(type, sizeof(type), "%s[0 to %d]", type_names[s->type], s->n);
        else if (s->n > 1)
            snprintf(type, sizeof(type), "%s[%d]", type_names[s->type], s->n);
        else
            snprintf(type, sizeof(type), "%s", type_names[s->type]);
        if (s->type == T_ENUM)
            format_names(s, range, sizeof(range));
        else if (s->type == T_BOOL)
            snprintf(range, sizeof(range), "true, false");
        else if (s->type == T_FILES)
            snprintf(range, sizeof(range), "up to %d", CONFIG_MAX_FILES);
        else if (s->type == T_STRING)
            snprintf(range, sizeof(range), "1 to %zu characters", s->size - 1);
        else if (s->type == T_PATH)
            snprintf(range, sizeof(range), "up to %zu characters", s->size - 1);
        else if (s->type == T_GROUPS)
            snprintf(range, sizeof(range), "%g to %g %ss", s->min, s->max, s->elems->elem_name);
        else if (s->type == T_TRANSFER)
            snprintf(range, sizeof(range), "a transfer function (docs/menu.md)");
        else
            format_range(s, range, sizeof(range));
        for (int sp = 0; sp < instances(s); sp++) {
            char name[NAME_MAX_LEN], path[2 * NAME_MAX_LEN];
            instance_path(s, sp, name, sizeof(name));
            join_name(prefix, name, path, sizeof(path));
            format_value(s, sp, defaults, value, sizeof(value));
            if (s->shown_default)
                fprintf(out, "| `%s` | %s | %s | %s | %s |\n", path, type, s->shown_default, range,
                        s->help);
            else if (s->flags & F_REQUIRED)
                fprintf(out, "| `%s` | %s | required | %s | %s |\n", path, type, range, s->help);
            else
                fprintf(out, "| `%s` | %s | `%s` | %s | %s |\n", path, type, value, range, s->help);
        }
        if (s->type == T_GROUPS) {
            void *elem = calloc(1, s->elems->size);
            assert(elem);
            config_table_defaults(s->elems, elem);
            char elem_prefix[2 * NAME_MAX_LEN];
            join_name(prefix, s->path, elem_prefix, sizeof(elem_prefix) - 4);
            strcat(elem_prefix, ".[i]");
            write_rows(s->elems, elem, elem_prefix, out);
            free(elem);
        }
    }
}

void config_table_write_reference(const struct config_table *t, const void *defaults, FILE *out)
{
    fprintf(out, "| setting | type | default | range | description |\n");
    fprintf(out, "|---|---|---|---|---|\n");
    write_rows(t, defaults, "", out);
}
