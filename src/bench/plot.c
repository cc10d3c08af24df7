/* The accuracy-vs-time plot: RMSE against milliseconds on log-log axes, one panel per scene,
 * drawn into an 8-bit canvas with stb_easy_font's glyph quads and written with image.h. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wmissing-braces"
#include <stb_easy_font.h>
#pragma GCC diagnostic pop

#include "bench/bench.h"
#include "common/log.h"

#define PANEL_W 460
#define PANEL_H 380
#define TITLE_H 28
#define MARGIN_L 64
#define MARGIN_R 16
#define MARGIN_T 30
#define MARGIN_B 46

struct canvas {
    int w, h;
    uint8_t *rgb; /* row 0 at the top */
};

static const uint8_t BLACK[3] = {0, 0, 0}, GREY[3] = {150, 150, 150}, LIGHT[3] = {225, 225, 225},
                     RED[3] = {200, 30, 30}, BLUE[3] = {30, 70, 200};

const uint8_t bench_plot_volume_rgb[3] = {20, 150, 60};
#define GREEN bench_plot_volume_rgb

static void put(struct canvas *c, int x, int y, const uint8_t col[3])
{
    if (x < 0 || y < 0 || x >= c->w || y >= c->h)
        return;
    memcpy(&c->rgb[3 * ((size_t)y * c->w + x)], col, 3);
}

static void rect(struct canvas *c, int x0, int y0, int x1, int y1, const uint8_t col[3])
{
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++)
            put(c, x, y, col);
}

static void line(struct canvas *c, int x0, int y0, int x1, int y1, const uint8_t col[3])
{
    int dx = abs(x1 - x0), dy = -abs(y1 - y0);
    int sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1, err = dx + dy;
    for (;;) {
        put(c, x0, y0, col);
        put(c, x0 + 1, y0, col);
        if (x0 == x1 && y0 == y1)
            break;
        int e2 = 2 * err;
        if (e2 >= dy) {
            err += dy;
            x0 += sx;
        }
        if (e2 <= dx) {
            err += dx;
            y0 += sy;
        }
    }
}

static void disc(struct canvas *c, int cx, int cy, int r, const uint8_t col[3])
{
    for (int y = -r; y <= r; y++)
        for (int x = -r; x <= r; x++)
            if (x * x + y * y <= r * r)
                put(c, cx + x, cy + y, col);
}

static void ring(struct canvas *c, int cx, int cy, int r, const uint8_t col[3])
{
    for (int y = -r - 1; y <= r + 1; y++)
        for (int x = -r - 1; x <= r + 1; x++) {
            int d = x * x + y * y;
            if (d <= (r + 1) * (r + 1) && d >= (r - 1) * (r - 1))
                put(c, cx + x, cy + y, col);
        }
}

static void square(struct canvas *c, int cx, int cy, int r, const uint8_t col[3])
{
    for (int k = -r; k <= r; k++) {
        for (int w = 0; w < 2; w++) {
            put(c, cx + k, cy - r + w, col);
            put(c, cx + k, cy + r - w, col);
            put(c, cx - r + w, cy + k, col);
            put(c, cx + r - w, cy + k, col);
        }
    }
}

/* Text with its top-left corner at (X, Y), glyphs scaled by SCALE. */
static void text(struct canvas *c, int x, int y, int scale, const char *s, const uint8_t col[3])
{
    static char buf[60000];
    unsigned char colour[4] = {0, 0, 0, 255};
    int quads = stb_easy_font_print(0, 0, (char *)s, colour, buf, sizeof(buf));
    for (int q = 0; q < quads; q++) {
        const float *v = (const float *)(buf + q * 4 * 16);
        /* four vertices of 16 bytes: x, y, z, colour */
        float x0 = v[0], y0 = v[1], x1 = v[8], y1 = v[9];
        rect(c, x + (int)(x0 * scale), y + (int)(y0 * scale), x + (int)(x1 * scale),
             y + (int)(y1 * scale), col);
    }
}

static int text_width(const char *s, int scale)
{
    return stb_easy_font_width((char *)s) * scale;
}

struct axis {
    double lo, hi; /* log10 range */
    int p0, p1;    /* pixel range */
};

static int to_pixel(const struct axis *a, double v)
{
    double t = (log10(v) - a->lo) / (a->hi - a->lo);
    return (int)lrint(a->p0 + t * (a->p1 - a->p0));
}

static void range(double lo, double hi, struct axis *a)
{
    if (!(lo > 0))
        lo = hi > 0 ? hi / 10 : 1e-3;
    if (!(hi > lo))
        hi = lo * 10;
    a->lo = log10(lo) - 0.12;
    a->hi = log10(hi) + 0.12;
}

static void ticks(struct canvas *c, const struct axis *a, bool x_axis, int other0, int other1)
{
    bool dense = a->hi - a->lo < 1.6;
    for (int k = (int)floor(a->lo); k <= (int)ceil(a->hi); k++) {
        static const int mult[] = {1, 2, 5};
        for (int m = 0; m < 3; m++) {
            double v = mult[m] * pow(10.0, k);
            double l = log10(v);
            if (l < a->lo || l > a->hi)
                continue;
            int p = to_pixel(a, v);
            bool label = m == 0 || dense;
            if (x_axis) {
                line(c, p, other0, p, other1, LIGHT);
                line(c, p, other1, p, other1 + (label ? 5 : 3), BLACK);
            } else {
                line(c, other0, p, other1, p, LIGHT);
                line(c, other0 - (label ? 5 : 3), p, other0, p, BLACK);
            }
            if (!label)
                continue;
            char s[32];
            snprintf(s, sizeof(s), "%g", v);
            if (x_axis)
                text(c, p - text_width(s, 1) / 2, other1 + 8, 1, s, BLACK);
            else
                text(c, other0 - 8 - text_width(s, 1), p - 4, 1, s, BLACK);
        }
    }
}

static int by_time(const void *a, const void *b)
{
    const struct bench_result *x = *(const struct bench_result *const *)a;
    const struct bench_result *y = *(const struct bench_result *const *)b;
    double tx = x->build_ms + x->view_ms, ty = y->build_ms + y->view_ms;
    return tx < ty ? -1 : tx > ty;
}

static double error_of(const struct bench_result *r, bool self)
{
    return bench_error(r, self);
}

/* The markers' key in the corner of the plot area (AX, AY) that holds fewest of RES's N
 * points, the top right on a tie: what grey, red, the blue ring and (when VOLUME) the green
 * square stand for. */
static void legend(struct canvas *c, const struct axis *ax, const struct axis *ay,
                   const struct bench_result *res, int n, bool self, bool volume)
{
    static const char *const what[] = {"a setting", "Pareto front", "default (multiple: columns)",
                                       "multiple: volume (3-D)"};
    int rows = volume ? 4 : 3, wmax = 0;
    for (int i = 0; i < rows; i++)
        wmax = text_width(what[i], 1) > wmax ? text_width(what[i], 1) : wmax;
    int w = wmax + 24, h = 13 * rows + 4, best = -1, best_count = 0;
    int corners[4][2] = {{ax->p1 - w, ay->p1},
                         {ax->p0 + 4, ay->p1},
                         {ax->p1 - w, ay->p0 - h - 4},
                         {ax->p0 + 4, ay->p0 - h - 4}};
    for (int k = 0; k < 4; k++) {
        int count = 0;
        for (int i = 0; i < n; i++) {
            double t = res[i].build_ms + res[i].view_ms, e = error_of(&res[i], self);
            if (!(t > 0) || !(e > 0) || !isfinite(e))
                continue;
            int px = to_pixel(ax, t), py = to_pixel(ay, e);
            count += px >= corners[k][0] - 10 && px <= corners[k][0] + w + 10 &&
                     py >= corners[k][1] - 10 && py <= corners[k][1] + h + 10;
        }
        if (best < 0 || count < best_count) {
            best = k;
            best_count = count;
        }
    }
    int mx = corners[best][0] + 8, tx = mx + 12;
    for (int i = 0; i < rows; i++) {
        int y = corners[best][1] + 8 + 13 * i;
        if (i == 0)
            disc(c, mx, y, 3, GREY);
        else if (i == 1)
            disc(c, mx, y, 4, RED);
        else if (i == 2)
            ring(c, mx, y, 5, BLUE);
        else
            square(c, mx, y, 5, GREEN);
        text(c, tx, y - 4, 1, what[i], i == 3 ? GREEN : i == 2 ? BLUE : i == 1 ? RED : BLACK);
    }
}

static void panel(struct canvas *c, int x0, const char *name, const struct bench_result *res,
                  int n, bool self)
{
    struct axis ax = {.p0 = x0 + MARGIN_L, .p1 = x0 + PANEL_W - MARGIN_R};
    struct axis ay = {.p0 = TITLE_H + PANEL_H - MARGIN_B, .p1 = TITLE_H + MARGIN_T};
    double tmin = INFINITY, tmax = 0, emin = INFINITY, emax = 0;
    for (int i = 0; i < n; i++) {
        double t = res[i].build_ms + res[i].view_ms;
        if (t > 0) {
            tmin = fmin(tmin, t);
            tmax = fmax(tmax, t);
        }
        if (error_of(&res[i], self) > 0 && isfinite(error_of(&res[i], self))) {
            emin = fmin(emin, error_of(&res[i], self));
            emax = fmax(emax, error_of(&res[i], self));
        }
    }
    range(tmin, tmax, &ax);
    range(emin, emax, &ay);
    ticks(c, &ax, true, ay.p1, ay.p0);
    ticks(c, &ay, false, ax.p0, ax.p1);
    line(c, ax.p0, ay.p0, ax.p1, ay.p0, BLACK);
    line(c, ax.p0, ay.p0, ax.p0, ay.p1, BLACK);
    text(c, x0 + (PANEL_W - text_width(name, 2)) / 2, TITLE_H + 6, 2, name, BLACK);
    const char *xl = "ms: light build + one view (log)";
    text(c, (ax.p0 + ax.p1 - text_width(xl, 1)) / 2, ay.p0 + 26, 1, xl, BLACK);
    text(c, x0 + 6, TITLE_H + 10, 1,
         self ? "RMSE vs converged renderer (log)" : "RMSE vs Monte Carlo (log)", BLACK);

    const struct bench_result *front[64];
    int nf = 0;
    for (int i = 0; i < n; i++) {
        double t = res[i].build_ms + res[i].view_ms;
        if (!(t > 0) || !(error_of(&res[i], self) > 0) || !isfinite(error_of(&res[i], self)))
            continue;
        disc(c, to_pixel(&ax, t), to_pixel(&ay, error_of(&res[i], self)), 3, GREY);
        if ((self ? res[i].pareto_self : res[i].pareto) && nf < 64)
            front[nf++] = &res[i];
    }
    qsort(front, (size_t)nf, sizeof(front[0]), by_time);
    for (int i = 0; i + 1 < nf; i++)
        line(c, to_pixel(&ax, front[i]->build_ms + front[i]->view_ms),
             to_pixel(&ay, error_of(front[i], self)),
             to_pixel(&ax, front[i + 1]->build_ms + front[i + 1]->view_ms),
             to_pixel(&ay, error_of(front[i + 1], self)), RED);
    int boxes[64][4], nb = 0; /* labels drawn so far: x0, y0, x1, y1 */
    for (int i = 0; i < nf; i++) {
        int px = to_pixel(&ax, front[i]->build_ms + front[i]->view_ms);
        int py = to_pixel(&ay, error_of(front[i], self));
        disc(c, px, py, 4, RED);
        char s[96];
        snprintf(s, sizeof(s), "%s %s", front[i]->v.knob, front[i]->v.value);
        if (front[i]->v.is_default)
            snprintf(s, sizeof(s), "default");
        int tx = px + 7, tw = text_width(s, 1);
        if (tx + tw > ax.p1)
            tx = px - 7 - tw;
        bool clear = true; /* leave a label out rather than overprint another */
        for (int b = 0; b < nb; b++)
            clear &= tx + tw < boxes[b][0] || tx > boxes[b][2] || py + 6 < boxes[b][1] ||
                     py - 5 > boxes[b][3];
        if (!clear)
            continue;
        text(c, tx, py - 4, 1, s, RED);
        boxes[nb][0] = tx, boxes[nb][1] = py - 5, boxes[nb][2] = tx + tw, boxes[nb][3] = py + 6;
        nb++;
    }
    /* The 3-D diffusion tier of multiple scattering: a square around its point, so that both
     * tiers (the columns are the default's) can be told apart whatever their place. */
    bool volume_shown = false;
    for (int i = 0; i < n; i++) {
        double e = error_of(&res[i], self), t = res[i].build_ms + res[i].view_ms;
        if (bench_is_volume_tier(&res[i].v) && t > 0 && e > 0 && isfinite(e)) {
            square(c, to_pixel(&ax, t), to_pixel(&ay, e), 7, GREEN);
            volume_shown = true;
        }
    }
    legend(c, &ax, &ay, res, n, self, volume_shown);
    for (int i = 0; i < n; i++) {
        double e = error_of(&res[i], self);
        if (res[i].v.is_default && e > 0 && isfinite(e)) {
            int px = to_pixel(&ax, res[i].build_ms + res[i].view_ms);
            int py = to_pixel(&ay, error_of(&res[i], self));
            ring(c, px, py, 8, BLUE);
            if (!(self ? res[i].pareto_self : res[i].pareto)) {
                int tw = text_width("default", 1);
                int tx = px + 10 + tw > ax.p1 ? px - 10 - tw : px + 10;
                text(c, tx, py + 6, 1, "default", BLUE);
            }
        }
    }
}

/* Linear radiance that image_tonemap maps to V at exposure 1 (bisection: it is monotone). */
static float linear_for(int v)
{
    if (v <= 0)
        return 0.0f;
    if (v >= 255)
        return 100.0f;
    float lo = 0.0f, hi = 100.0f;
    for (int i = 0; i < 60; i++) {
        float mid = 0.5f * (lo + hi);
        if (image_tonemap(mid, 1.0f) < v)
            lo = mid;
        else
            hi = mid;
    }
    return hi;
}

uint8_t *bench_plot_rgb(const char *title, int n_scenes, const char *const *names,
                        const struct bench_result *const *res, const int *n, bool self, int *w,
                        int *h)
{
    struct canvas c = {.w = PANEL_W * (n_scenes > 0 ? n_scenes : 1), .h = TITLE_H + PANEL_H};
    c.rgb = malloc((size_t)c.w * c.h * 3);
    if (!c.rgb) {
        log_error("out of memory for the plot");
        return NULL;
    }
    memset(c.rgb, 255, (size_t)c.w * c.h * 3);
    text(&c, 8, 8, 2, title, BLACK);
    for (int s = 0; s < n_scenes; s++)
        panel(&c, s * PANEL_W, names[s], res[s], n[s], self);
    *w = c.w;
    *h = c.h;
    return c.rgb;
}

bool bench_plot_png(const char *path, const char *title, int n_scenes, const char *const *names,
                    const struct bench_result *const *res, const int *n, bool self)
{
    int w = 0, h = 0;
    uint8_t *rgb = bench_plot_rgb(title, n_scenes, names, res, n, self, &w, &h);
    struct image img = {0};
    if (!rgb || !image_init(&img, w, h)) {
        free(rgb);
        log_error("%s: out of memory for the plot", path);
        return false;
    }
    float lut[256];
    for (int v = 0; v < 256; v++)
        lut[v] = linear_for(v);
    for (int y = 0; y < h; y++) {
        for (int x = 0; x < w; x++) {
            const uint8_t *p = &rgb[3 * ((size_t)y * w + x)];
            float *q = &img.rgba[4 * ((size_t)(h - 1 - y) * w + x)]; /* rows bottom up */
            for (int k = 0; k < 3; k++)
                q[k] = lut[p[k]];
            q[3] = 1.0f;
        }
    }
    bool ok = image_write_png(&img, path, 1.0f);
    image_finish(&img);
    free(rgb);
    return ok;
}
