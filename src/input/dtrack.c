/*
 * The DTrack2/DTrack3 ASCII output, one datagram at a time (ART's "Technical Appendix",
 * output format):
 *
 *   fr 21753
 *   ts 39596.024831                       (or: ts2 SECONDS MICROSECONDS [LATENCY_US])
 *   6dcal 2
 *   6d 1 [0 1.000][326.848 -187.216 109.503][b0 b1 b2 b3 b4 b5 b6 b7 b8]
 *   6df2 1 1 [0 1.000 6 2][x y z][b0 ... b8][BUTTON_WORD J0 J1]
 *
 * 6d: the count, then per body [id quality][x y z] (mm; DTrack 1 added three Euler angles,
 * which are read and ignored) and the rotation matrix column by column.  6df2: the Flysticks
 * defined, the count that follows, then per Flystick [id quality buttons joysticks][x y z]
 * [matrix][button words (32 buttons each) then the joystick values].  A quality below zero
 * means not tracked.  Every other record type is skipped.
 */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "input/tracker.h"

#define POSITION_MAX_MM 1e7 /* 10 km: anything farther is not a room's */

struct cursor {
    const char *p, *end;
    int line;
    char *why;
    size_t why_size;
};

static bool fail(struct cursor *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static bool fail(struct cursor *c, const char *fmt, ...)
{
    if (c->why_size == 0)
        return false;
    int n = snprintf(c->why, c->why_size, "line %d: ", c->line);
    if (n < 0 || (size_t)n >= c->why_size)
        return false;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(c->why + n, c->why_size - (size_t)n, fmt, ap);
    va_end(ap);
    return false;
}

static void skip_spaces(struct cursor *c)
{
    while (c->p < c->end && (*c->p == ' ' || *c->p == '\t'))
        c->p++;
}

static bool at(struct cursor *c, char ch)
{
    skip_spaces(c);
    if (c->p < c->end && *c->p == ch) {
        c->p++;
        return true;
    }
    return false;
}

/* Copies the next number's characters into TOK; false when there is none. */
static bool number_token(struct cursor *c, char *tok, size_t size)
{
    skip_spaces(c);
    size_t n = 0;
    while (c->p < c->end && n + 1 < size &&
           ((*c->p >= '0' && *c->p <= '9') || *c->p == '-' || *c->p == '+' || *c->p == '.' ||
            *c->p == 'e' || *c->p == 'E'))
        tok[n++] = *c->p++;
    tok[n] = '\0';
    /* A token too long to be a number is not one. */
    if (n + 1 >= size && c->p < c->end && *c->p != ' ' && *c->p != ']' && *c->p != '\t')
        return false;
    return n > 0;
}

static bool read_double(struct cursor *c, const char *what, double *out)
{
    char tok[64];
    if (!number_token(c, tok, sizeof(tok)))
        return fail(c, "expected a number (%s)", what);
    char *end;
    errno = 0;
    double v = strtod(tok, &end);
    if (*end || errno || !isfinite(v))
        return fail(c, "expected a finite number (%s), got \"%s\"", what, tok);
    *out = v;
    return true;
}

static bool read_long(struct cursor *c, const char *what, long long lo, long long hi,
                      long long *out)
{
    char tok[64];
    if (!number_token(c, tok, sizeof(tok)))
        return fail(c, "expected an integer (%s)", what);
    char *end;
    errno = 0;
    long long v = strtoll(tok, &end, 10);
    if (*end || errno || v < lo || v > hi)
        return fail(c, "expected an integer in [%lld, %lld] (%s), got \"%s\"", lo, hi, what, tok);
    *out = v;
    return true;
}

static bool read_int(struct cursor *c, const char *what, int lo, int hi, int *out)
{
    long long v;
    if (!read_long(c, what, lo, hi, &v))
        return false;
    *out = (int)v;
    return true;
}

static bool open_block(struct cursor *c, const char *what)
{
    return at(c, '[') || fail(c, "expected '[' (%s)", what);
}

static bool close_block(struct cursor *c, const char *what)
{
    return at(c, ']') || fail(c, "expected ']' after %s", what);
}

/* [x y z] in mm, or DTrack 1's [x y z eta theta phi]. */
static bool read_location(struct cursor *c, struct dtrack_item *it)
{
    if (!open_block(c, "position"))
        return false;
    for (int i = 0; i < 3; i++) {
        if (!read_double(c, "position", &it->position[i]))
            return false;
        if (fabs(it->position[i]) > POSITION_MAX_MM)
            return fail(c, "expected a position within 10 km, got %g mm", it->position[i]);
    }
    skip_spaces(c);
    if (c->p < c->end && *c->p != ']') {
        double angles[3];
        for (int i = 0; i < 3; i++) {
            if (!read_double(c, "angle", &angles[i]))
                return false;
        }
    }
    return close_block(c, "the position");
}

/* The columns of a rotation: unit length, perpendicular, right-handed (to 1e-3, the matrix
 * comes with six decimals). */
static bool is_rotation(const double m[9])
{
    const double *a = m, *b = m + 3, *k = m + 6;
    double dots[6] = {
        a[0] * a[0] + a[1] * a[1] + a[2] * a[2], b[0] * b[0] + b[1] * b[1] + b[2] * b[2],
        k[0] * k[0] + k[1] * k[1] + k[2] * k[2], a[0] * b[0] + a[1] * b[1] + a[2] * b[2],
        a[0] * k[0] + a[1] * k[1] + a[2] * k[2], b[0] * k[0] + b[1] * k[1] + b[2] * k[2],
    };
    for (int i = 0; i < 3; i++) {
        if (fabs(dots[i] - 1.0) > 1e-3 || fabs(dots[3 + i]) > 1e-3)
            return false;
    }
    double det = a[0] * (b[1] * k[2] - b[2] * k[1]) - b[0] * (a[1] * k[2] - a[2] * k[1]) +
                 k[0] * (a[1] * b[2] - a[2] * b[1]);
    return det > 0.99;
}

static bool read_rotation(struct cursor *c, struct dtrack_item *it)
{
    if (!open_block(c, "rotation matrix"))
        return false;
    for (int i = 0; i < 9; i++) {
        if (!read_double(c, "rotation matrix", &it->rotation[i]))
            return false;
    }
    if (!close_block(c, "the rotation matrix (9 numbers)"))
        return false;
    if (it->quality >= 0.0 && !is_rotation(it->rotation))
        return fail(c,
                    "expected a rotation matrix for id %d (orthonormal columns, "
                    "determinant 1)",
                    it->id);
    return true;
}

static bool unique_id(struct cursor *c, const struct dtrack_item *items, int n, int id)
{
    for (int i = 0; i < n; i++) {
        if (items[i].id == id)
            return fail(c, "id %d comes twice", id);
    }
    return true;
}

static bool parse_6d(struct cursor *c, struct dtrack_frame *f)
{
    int n;
    if (!read_int(c, "body count", 0, DTRACK_ITEMS_MAX, &n))
        return false;
    f->have_bodies = true;
    for (int i = 0; i < n; i++) {
        struct dtrack_item *it = &f->bodies[i];
        memset(it, 0, sizeof(*it));
        if (!open_block(c, "body id and quality") || !read_int(c, "body id", 0, 9999, &it->id) ||
            !read_double(c, "quality", &it->quality) || !close_block(c, "the body's quality"))
            return false;
        if (!unique_id(c, f->bodies, i, it->id) || !read_location(c, it) || !read_rotation(c, it))
            return false;
    }
    f->body_count = n;
    return true;
}

static bool parse_6df2(struct cursor *c, struct dtrack_frame *f)
{
    int defined, n;
    if (!read_int(c, "Flysticks defined", 0, 9999, &defined) ||
        !read_int(c, "Flystick count", 0, DTRACK_ITEMS_MAX, &n))
        return false;
    f->have_flysticks = true;
    for (int i = 0; i < n; i++) {
        struct dtrack_item *it = &f->flysticks[i];
        memset(it, 0, sizeof(*it));
        if (!open_block(c, "Flystick id, quality, buttons, joysticks") ||
            !read_int(c, "Flystick id", 0, 9999, &it->id) ||
            !read_double(c, "quality", &it->quality) ||
            !read_int(c, "button count", 0, TRACKER_BUTTONS_MAX, &it->button_count) ||
            !read_int(c, "joystick count", 0, TRACKER_AXES_MAX, &it->axis_count) ||
            !close_block(c, "the Flystick's counts"))
            return false;
        if (!unique_id(c, f->flysticks, i, it->id) || !read_location(c, it) ||
            !read_rotation(c, it) || !open_block(c, "buttons and joysticks"))
            return false;
        for (int w = 0; w * 32 < it->button_count; w++) {
            long long word;
            if (!read_long(c, "button word", 0, 0xffffffffLL, &word))
                return false;
            for (int b = 0; b < 32 && w * 32 + b < it->button_count; b++)
                it->buttons[w * 32 + b] = (word >> b) & 1;
        }
        for (int j = 0; j < it->axis_count; j++) {
            if (!read_double(c, "joystick value", &it->axes[j]))
                return false;
            if (it->axes[j] < -1.0 - 1e-6 || it->axes[j] > 1.0 + 1e-6)
                return fail(c, "expected a joystick value in [-1, 1], got %g", it->axes[j]);
        }
        if (!close_block(c, "the button words and joystick values"))
            return false;
    }
    f->flystick_count = n;
    return true;
}

bool dtrack_parse(const char *data, size_t len, struct dtrack_frame *out, char *why,
                  size_t why_size)
{
    memset(out, 0, sizeof(*out));
    out->calibrated = -1;
    if (why_size)
        why[0] = '\0';
    struct cursor c = {.p = data, .end = data + len, .why = why, .why_size = why_size};
    if (len > DTRACK_DATAGRAM_MAX) {
        c.line = 1;
        return fail(&c, "expected a datagram of at most %d bytes, got %zu", DTRACK_DATAGRAM_MAX,
                    len);
    }
    while (c.end > c.p && c.end[-1] == '\0') /* a sender's C string terminator */
        c.end--;
    bool any = false;
    bool seen_fr = false, seen_ts = false, seen_cal = false;
    while (c.p < c.end) {
        c.line++;
        const char *eol = memchr(c.p, '\n', (size_t)(c.end - c.p));
        const char *line_end = eol ? eol : c.end;
        if (line_end > c.p && line_end[-1] == '\r')
            line_end--;
        struct cursor l = c;
        l.end = line_end;
        skip_spaces(&l);
        char kind[16];
        size_t k = 0;
        while (l.p < l.end && *l.p != ' ' && *l.p != '\t' && k + 1 < sizeof(kind))
            kind[k++] = *l.p++;
        kind[k] = '\0';
        bool word = k > 0 && (l.p == l.end || *l.p == ' ' || *l.p == '\t');
        for (size_t i = 0; i < k; i++)
            word =
                word && ((kind[i] >= '0' && kind[i] <= '9') || (kind[i] >= 'a' && kind[i] <= 'z'));
        bool ok = true, known = true;
        if (k == 0 && l.p == l.end) {
            known = false; /* an empty line */
        } else if (!word) {
            ok = fail(&l, "expected a record type (fr, ts, 6d, ...) at the start of the line");
        } else if (strcmp(kind, "fr") == 0) {
            long long v = 0;
            ok = seen_fr ? fail(&l, "a second \"fr\" line")
                         : read_long(&l, "frame counter", 0, 0xffffffffLL, &v);
            out->counter = (uint32_t)v;
            out->have_counter = seen_fr = true;
        } else if (strcmp(kind, "ts") == 0 || strcmp(kind, "ts2") == 0) {
            if (seen_ts) {
                ok = fail(&l, "a second time stamp line");
            } else if (kind[2] == '\0') {
                ok = read_double(&l, "time stamp", &out->time_s);
            } else {
                long long sec = 0, usec = 0, latency = 0;
                ok = read_long(&l, "time stamp seconds", 0, 0xffffffffLL, &sec) &&
                     read_long(&l, "time stamp microseconds", 0, 999999, &usec);
                skip_spaces(&l);
                if (ok && l.p < l.end)
                    ok = read_long(&l, "latency", 0, 0xffffffffLL, &latency);
                out->time_s = (double)sec + 1e-6 * (double)usec;
            }
            out->have_time = seen_ts = true;
        } else if (strcmp(kind, "6dcal") == 0) {
            ok = !seen_cal ? read_int(&l, "calibrated bodies", 0, 9999, &out->calibrated)
                           : fail(&l, "a second \"6dcal\" line");
            seen_cal = true;
        } else if (strcmp(kind, "6d") == 0) {
            ok = !out->have_bodies ? parse_6d(&l, out) : fail(&l, "a second \"6d\" line");
        } else if (strcmp(kind, "6df2") == 0) {
            ok = !out->have_flysticks ? parse_6df2(&l, out) : fail(&l, "a second \"6df2\" line");
        } else {
            known = false;
            out->skipped_lines++;
        }
        if (ok && known) {
            skip_spaces(&l);
            if (l.p < l.end)
                ok = fail(&l, "expected the end of the \"%s\" line, got \"%.*s\"", kind,
                          (int)(l.end - l.p > 24 ? 24 : l.end - l.p), l.p);
        }
        if (!ok)
            return false;
        any = any || known || word;
        c.p = eol ? eol + 1 : c.end;
    }
    if (!any) {
        c.line = 1;
        return fail(&c, "expected DTrack output (fr, ts, 6d, 6df2 lines), got an empty datagram");
    }
    return true;
}
