/* A panel of labelled values: a title, then label and value columns. */
#include "menu/readout.h"

#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "menu/font.h"
#include "menu/menu.h"

#define W READOUT_WIDTH
#define H READOUT_HEIGHT
#define MARGIN 14
#define VALUE_X 118
#define ROW_H 17

static const uint8_t background[4] = {12, 24, 34, 220};
static const uint8_t ink[3] = {235, 240, 245};
static const uint8_t dim[3] = {140, 155, 170};
static const uint8_t label_ink[3] = {170, 190, 210};

struct readout {
    struct menu_font *font, *small;
    uint8_t pixels[W * H * 4];
    struct readout_model drawn;
    bool have_drawn;
    unsigned generation;
};

struct readout *readout_create(const char *font_path)
{
    struct readout *r = calloc(1, sizeof(*r));
    if (!r) {
        log_error("readout: out of memory");
        return NULL;
    }
    const char *path = font_path ? font_path : MENU_FONT_PATH;
    r->font = menu_font_create(path, 19.0f);
    r->small = menu_font_create(path, 15.0f);
    if (!r->font || !r->small) {
        readout_destroy(r);
        return NULL;
    }
    return r;
}

void readout_destroy(struct readout *r)
{
    if (!r)
        return;
    menu_font_destroy(r->font);
    menu_font_destroy(r->small);
    free(r);
}

const uint8_t *readout_pixels(struct readout *r, const struct readout_model *m,
                              unsigned *generation)
{
    if (!r->have_drawn || memcmp(&r->drawn, m, sizeof(*m)) != 0) {
        for (int i = 0; i < W * H; i++)
            memcpy(&r->pixels[4 * i], background, 4);
        menu_font_draw(r->font, r->pixels, W, H, MARGIN, 10, m->title, ink);
        int y = 40;
        for (int i = 0; i < m->count && i < READOUT_ROWS && y + ROW_H <= H; i++, y += ROW_H) {
            const struct readout_row *row = &m->rows[i];
            /* A row without a label is a line of text across the panel. */
            menu_font_draw(r->small, r->pixels, W, H, MARGIN, y, row->label, label_ink);
            menu_font_draw(r->small, r->pixels, W, H, row->label[0] ? VALUE_X : MARGIN, y,
                           row->value, row->dim ? dim : ink);
        }
        r->drawn = *m;
        r->have_drawn = true;
        r->generation++;
    }
    if (generation)
        *generation = r->generation;
    return r->pixels;
}
