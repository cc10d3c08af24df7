/* The information panel: date and time, the legends of the colour-mapped fields, north. */
#include "menu/overlay.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "menu/font.h"
#include "menu/menu.h"

#define W OVERLAY_WIDTH
#define H OVERLAY_HEIGHT
#define BAR_X0 16
#define BAR_X1 236
#define BAR_Y0 78
#define BAR_Y1 102
#define ARROW_CX 282
#define ARROW_CY 92
#define ARROW_R 26

static const uint8_t background[4] = {12, 24, 34, 220};
static const uint8_t ink[3] = {235, 240, 245};
static const uint8_t dim[3] = {160, 175, 190};

struct overlay {
    struct menu_font *font, *small;
    uint8_t pixels[W * H * 4];
    struct overlay_model drawn;
    bool have_drawn, legend;
    int legends; /* bars drawn */
    unsigned generation;
};

struct overlay *overlay_create(const char *font_path)
{
    struct overlay *o = calloc(1, sizeof(*o));
    if (!o) {
        log_error("overlay: out of memory");
        return NULL;
    }
    const char *path = font_path ? font_path : MENU_FONT_PATH;
    o->font = menu_font_create(path, 20.0f);
    o->small = menu_font_create(path, 15.0f);
    if (!o->font || !o->small) {
        overlay_destroy(o);
        return NULL;
    }
    return o;
}

void overlay_destroy(struct overlay *o)
{
    if (!o)
        return;
    menu_font_destroy(o->font);
    menu_font_destroy(o->small);
    free(o);
}

static void fill(uint8_t *img, int x0, int y0, int x1, int y1, const uint8_t rgb[3])
{
    for (int y = y0 < 0 ? 0 : y0; y < y1 && y < H; y++)
        for (int x = x0 < 0 ? 0 : x0; x < x1 && x < W; x++) {
            uint8_t *p = &img[4 * (y * W + x)];
            p[0] = rgb[0];
            p[1] = rgb[1];
            p[2] = rgb[2];
            p[3] = 255;
        }
}

void overlay_value_text(enum transfer_field field, double v, char *buf, int size)
{
    switch (field) {
    case TRANSFER_FIELD_QVAPOR:
    case TRANSFER_FIELD_CONDENSATE:
        snprintf(buf, (size_t)size, "%.3g g/kg", v * 1000.0);
        break;
    case TRANSFER_FIELD_TEMPERATURE:
        snprintf(buf, (size_t)size, "%.3g C", v - 273.15);
        break;
    case TRANSFER_FIELD_WIND:
        snprintf(buf, (size_t)size, "%.3g m/s", v);
        break;
    case TRANSFER_FIELD_THETA:
        snprintf(buf, (size_t)size, "%.4g K", v);
        break;
    case TRANSFER_FIELD_RH:
        snprintf(buf, (size_t)size, "%.3g %%", v);
        break;
    case TRANSFER_FIELD_W:
        snprintf(buf, (size_t)size, "%.3g m/s", v);
        break;
    case TRANSFER_FIELD_VORTICITY:
        snprintf(buf, (size_t)size, "%.3g e-3/s", v * 1e3);
        break;
    default:
        snprintf(buf, (size_t)size, "%.3g", v);
        break;
    }
}

static const char *field_title(enum transfer_field f)
{
    switch (f) {
    case TRANSFER_FIELD_QVAPOR:
        return "water vapour";
    case TRANSFER_FIELD_CONDENSATE:
        return "condensate";
    case TRANSFER_FIELD_TEMPERATURE:
        return "temperature";
    case TRANSFER_FIELD_WIND:
        return "wind speed";
    case TRANSFER_FIELD_THETA:
        return "potential temperature";
    case TRANSFER_FIELD_RH:
        return "relative humidity";
    case TRANSFER_FIELD_W:
        return "vertical velocity";
    case TRANSFER_FIELD_VORTICITY:
        return "vertical vorticity";
    default:
        return "field";
    }
}

/* The colour of the transfer function at X, 0-255 (what the legend shows). */
static void legend_color(const struct transfer_function *tf, float x, uint8_t out[3])
{
    for (int c = 0; c < 3; c++) {
        float v = transfer_eval(tf, (enum transfer_channel)c, x);
        v = v < 0.0f ? 0.0f : v > 1.0f ? 1.0f : v;
        out[c] = (uint8_t)(v * 255.0f + 0.5f);
    }
}

static void draw_legend(struct overlay *o, const struct transfer_function *tf)
{
    menu_font_draw(o->small, o->pixels, W, H, BAR_X0, BAR_Y0 - 22, field_title(tf->field), dim);
    for (int x = BAR_X0; x < BAR_X1; x++) {
        uint8_t rgb[3];
        legend_color(tf, (float)(x - BAR_X0) / (float)(BAR_X1 - 1 - BAR_X0), rgb);
        fill(o->pixels, x, BAR_Y0, x + 1, BAR_Y1, rgb);
    }
    char lo[32], hi[32];
    overlay_value_text(tf->field, tf->lo, lo, sizeof(lo));
    overlay_value_text(tf->field, tf->hi, hi, sizeof(hi));
    menu_font_draw(o->small, o->pixels, W, H, BAR_X0, BAR_Y1 + 4, lo, ink);
    menu_font_draw(o->small, o->pixels, W, H, BAR_X1 - menu_font_width(o->small, hi), BAR_Y1 + 4,
                   hi, ink);
}

/* Several legends, one row each below the date: the field's name and its range's ends on
 * one line, the bar under it. */
static void legend_row(int i, int n, int *y0, int *y1)
{
    int top = 40, h = (H - top - 4) / n;
    *y0 = top + i * h + 18;
    *y1 = top + (i + 1) * h - 2;
}

static void draw_legend_row(struct overlay *o, const struct transfer_function *tf, int i, int n)
{
    int y0, y1;
    legend_row(i, n, &y0, &y1);
    char lo[32], hi[32], title[96];
    overlay_value_text(tf->field, tf->lo, lo, sizeof(lo));
    overlay_value_text(tf->field, tf->hi, hi, sizeof(hi));
    snprintf(title, sizeof(title), "%s  %s", field_title(tf->field), lo);
    menu_font_draw(o->small, o->pixels, W, H, BAR_X0, y0 - 17, title, dim);
    menu_font_draw(o->small, o->pixels, W, H, BAR_X1 - menu_font_width(o->small, hi), y0 - 17,
                   hi, ink);
    for (int x = BAR_X0; x < BAR_X1; x++) {
        uint8_t rgb[3];
        legend_color(tf, (float)(x - BAR_X0) / (float)(BAR_X1 - 1 - BAR_X0), rgb);
        fill(o->pixels, x, y0, x + 1, y1, rgb);
    }
}

/* A filled arrow through the centre, its tip toward ANGLE (clockwise from up), and an N. */
static void draw_north(struct overlay *o, float angle_deg)
{
    float a = angle_deg * (float)M_PI / 180.0f;
    float ux = sinf(a), uy = -cosf(a); /* up on the image is -y */
    float tip[2] = {ARROW_CX + ux * ARROW_R, ARROW_CY + uy * ARROW_R};
    float tail[2] = {ARROW_CX - ux * ARROW_R * 0.6f, ARROW_CY - uy * ARROW_R * 0.6f};
    float side[2] = {-uy * ARROW_R * 0.45f, ux * ARROW_R * 0.45f};
    float v[3][2] = {{tip[0], tip[1]}, {tail[0] + side[0], tail[1] + side[1]},
                     {tail[0] - side[0], tail[1] - side[1]}};
    for (int y = ARROW_CY - ARROW_R - 1; y <= ARROW_CY + ARROW_R + 1; y++)
        for (int x = ARROW_CX - ARROW_R - 1; x <= ARROW_CX + ARROW_R + 1; x++) {
            float px = x + 0.5f, py = y + 0.5f;
            bool in = true;
            for (int e = 0; e < 3 && in; e++) {
                const float *p0 = v[e], *p1 = v[(e + 1) % 3];
                float cross = (p1[0] - p0[0]) * (py - p0[1]) - (p1[1] - p0[1]) * (px - p0[0]);
                in = cross * ((v[1][0] - v[0][0]) * (v[2][1] - v[0][1]) -
                              (v[1][1] - v[0][1]) * (v[2][0] - v[0][0])) >= 0.0f;
            }
            if (in)
                fill(o->pixels, x, y, x + 1, y + 1, ink);
        }
    int nx = (int)(tip[0] + ux * 12.0f) - menu_font_width(o->small, "N") / 2;
    int ny = (int)(tip[1] + uy * 12.0f) - menu_font_ascent(o->small) / 2 - 2;
    menu_font_draw(o->small, o->pixels, W, H, nx, ny, "N", ink);
}

const uint8_t *overlay_pixels(struct overlay *o, const struct overlay_model *m,
                              unsigned *generation)
{
    if (!o->have_drawn || memcmp(&o->drawn, m, sizeof(*m)) != 0) {
        for (int i = 0; i < W * H; i++)
            memcpy(&o->pixels[4 * i], background, 4);
        if (m->date)
            menu_font_draw(o->font, o->pixels, W, H, 16, 14, m->date_text, ink);
        o->legend = m->legend;
        o->legends = m->legend ? (m->legend_count > 1 ? m->legend_count : 1) : 0;
        if (o->legends > OVERLAY_LEGENDS)
            o->legends = OVERLAY_LEGENDS;
        if (o->legends == 1)
            draw_legend(o, &m->transfer);
        for (int i = 0; o->legends > 1 && i < o->legends; i++)
            draw_legend_row(o, &m->legends[i], i, o->legends);
        if (m->north)
            draw_north(o, m->north_deg);
        o->drawn = *m;
        o->have_drawn = true;
        o->generation++;
    }
    if (generation)
        *generation = o->generation;
    return o->pixels;
}

bool overlay_legend_pixel_at(const struct overlay *o, int i, float x, int *px, int *py)
{
    if (i < 0 || i >= o->legends)
        return false;
    if (o->legends == 1)
        return overlay_legend_pixel(o, x, px, py);
    int y0, y1;
    legend_row(i, o->legends, &y0, &y1);
    *px = BAR_X0 + (int)lroundf(x * (float)(BAR_X1 - 1 - BAR_X0));
    *py = (y0 + y1) / 2;
    return true;
}

bool overlay_legend_pixel(const struct overlay *o, float x, int *px, int *py)
{
    if (!o->legend)
        return false;
    *px = BAR_X0 + (int)lroundf(x * (float)(BAR_X1 - 1 - BAR_X0));
    *py = (BAR_Y0 + BAR_Y1) / 2;
    return true;
}
