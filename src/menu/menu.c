/*
 * The menu's state machine: pages laid out as widgets in panel pixels, the pointer (the wand's
 * ray hitting the panel's plane), the trigger (press, drag, release), and the drawing of the
 * panel image.
 */
#include "menu/menu.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "menu/font.h"

#define WIDGETS_MAX 64
#define NAME_LEN 32
#define PICK_RADIUS 10 /* pixels: a click this close to a control point grabs it */

enum kind { W_BUTTON, W_TOGGLE, W_SLIDER, W_CANVAS, W_LABEL };

/* What a widget edits. */
enum id {
    ID_NONE,
    ID_TAB,
    ID_RESET,
    ID_PLAY,
    ID_BACK,
    ID_FORWARD,
    ID_FIRST,
    ID_SPEED,
    ID_STEP,
    ID_LOOP,
    ID_SPECIES_ON,
    ID_SUB,
    ID_PICK,
    ID_SCALE,
    ID_TINT,
    ID_TF_MODE,
    ID_TF_FIELD,
    ID_CHANNEL,
    ID_CANVAS,
    ID_DELETE,
    ID_SLOT,
    ID_SAVE,
    ID_LOAD,
    ID_AZIMUTH,
    ID_ELEVATION,
    ID_RAY_STEP,
    ID_LOD,
    ID_RESOLUTION,
    ID_EPSILON,
    ID_DIFFUSE,
    ID_SAVE_VIEW,
    ID_FRAME,
    ID_PROBE_ON,
    ID_PROBE_MODE,
    ID_PROBE_THRESHOLD,
    ID_PROBE_DISTANCE,
    ID_LAYER_ADD,
    ID_LAYER_ON,
    ID_LAYER_FIELD,
    ID_LAYER_MODE,
    ID_LAYER_EDIT,
    ID_LAYER_REMOVE,
    ID_LAYER_OPACITY,
    ID_SLICE_ADD,
    ID_SLICE_ON,
    ID_SLICE_FIELD,
    ID_SLICE_AXIS,
    ID_SLICE_SELECT,
    ID_SLICE_REMOVE,
    ID_SLICE_POSITION,
    ID_SLICE_TILT,
    ID_SLICE_OPACITY,
    ID_SLICE_CONTOURS,
};

struct widget {
    char name[NAME_LEN];
    enum kind kind;
    enum id id;
    int index;
    int rect[4]; /* x, y, w, h in panel pixels, y down */
    char label[64];
    bool disabled, selected;
    bool small; /* its label in the small font */
    double lo, hi; /* sliders */
};

struct menu {
    struct menu_desc desc;
    struct menu_font *font, *small;
    struct menu_model model;
    int w, h;
    uint8_t *pixels;
    unsigned generation;
    bool dirty;
    bool visible;
    enum menu_page page;
    int sub;       /* Transfer page: 0 species, 1 function */
    int species;   /* Transfer page: the species being tinted */
    int channel;   /* transfer function channel being edited */
    int point;     /* selected control point of that channel, or -1 */
    char status[96];
    struct widget widgets[WIDGETS_MAX];
    int n_widgets;
    /* pose */
    float center[3], right[3], up[3], normal[3], width;
    /* pointer */
    float ray_o[3], ray_d[3];
    bool have_ray;
    float hit_t;
    float px, py; /* pointer on the panel, pixels (valid when hit_t >= 0) */
    /* trigger */
    bool down;
    int pressed;   /* widget index the trigger went down on, or -1 */
    double drag;   /* slider value while dragging */
    bool dragging, moved;
    unsigned changes;
};

static const char *const page_names[MENU_PAGE_COUNT] = {
    "time", "fields", "layers", "slices", "transfer", "light", "quality", "probe"};
static const char *const page_titles[MENU_PAGE_COUNT] = {
    "Time", "Fields", "Layers", "Slices", "Transfer", "Light", "Quality", "Probe"};

void menu_slice_plane(struct menu_slice *sl, const double box_centre[3])
{
    double t = sl->tilt_deg * M_PI / 180.0;
    double n[3] = {0.0, 0.0, 0.0};
    int a = sl->axis, b = a == 0 ? 1 : a == 1 ? 2 : 1; /* B: the axis the normal leans to */
    n[a] = cos(t);
    n[b] = sin(t);
    for (int k = 0; k < 3; k++) {
        sl->slice.normal[k] = n[k];
        sl->slice.point[k] = k == a ? sl->position_m : box_centre[k];
    }
}

void menu_slice_from_plane(struct menu_slice *sl)
{
    const double *n = sl->slice.normal;
    int a = 0;
    for (int k = 1; k < 3; k++)
        if (fabs(n[k]) > fabs(n[a]))
            a = k;
    int b = a == 0 ? 1 : a == 1 ? 2 : 1;
    double sign = n[a] < 0.0 ? -1.0 : 1.0;
    sl->axis = a;
    sl->tilt_deg = atan2(sign * n[b], fabs(n[a])) * 180.0 / M_PI;
    sl->position_m = sl->slice.point[a];
}

const char *menu_page_name(enum menu_page p)
{
    return p >= 0 && p < MENU_PAGE_COUNT ? page_names[p] : "?";
}

/* ---- layout ---------------------------------------------------------------------------- */

static struct widget *add(struct menu *m, enum kind kind, enum id id, int index, const char *name,
                          int x, int y, int w, int h, const char *label)
{
    if (m->n_widgets >= WIDGETS_MAX)
        return NULL;
    struct widget *wd = &m->widgets[m->n_widgets++];
    memset(wd, 0, sizeof(*wd));
    snprintf(wd->name, sizeof(wd->name), "%s", name);
    wd->kind = kind;
    wd->id = id;
    wd->index = index;
    wd->rect[0] = x;
    wd->rect[1] = y;
    wd->rect[2] = w;
    wd->rect[3] = h;
    snprintf(wd->label, sizeof(wd->label), "%s", label ? label : "");
    return wd;
}

static struct widget *slider(struct menu *m, enum id id, int index, const char *name, int y,
                             double lo, double hi, const char *label)
{
    struct widget *wd = add(m, W_SLIDER, id, index, name, 16, y, m->w - 32, 40, label);
    if (wd) {
        wd->lo = lo;
        wd->hi = hi;
    }
    return wd;
}

static const char *step_date(const struct menu *m, int step)
{
    const char *d = m->desc.step_date ? m->desc.step_date(m->desc.user, step) : NULL;
    return d ? d : "";
}

/* The value a slider shows: the drag value while it is being dragged. */
static double slider_value(const struct menu *m, const struct widget *wd)
{
    if (m->dragging && m->pressed >= 0 && &m->widgets[m->pressed] == wd)
        return m->drag;
    const struct menu_model *md = &m->model;
    switch (wd->id) {
    case ID_SPEED:
        return md->speed;
    case ID_STEP:
        return md->step;
    case ID_SCALE:
        return md->species_scale[m->species];
    case ID_TINT:
        return md->species_tint[m->species][wd->index];
    case ID_AZIMUTH:
        return md->sun_azimuth;
    case ID_ELEVATION:
        return md->sun_elevation;
    case ID_RAY_STEP:
        return md->step_m;
    case ID_LOD:
        return md->lod_pixels;
    case ID_RESOLUTION:
        return md->light_resolution;
    case ID_EPSILON:
        return md->epsilon;
    case ID_PROBE_THRESHOLD: /* a decade scale */
        return log10(md->probe_threshold > 0.0 ? md->probe_threshold : 1e-4);
    case ID_PROBE_DISTANCE:
        return md->probe_distance_m / 1000.0;
    case ID_LAYER_OPACITY:
        return md->layer_count > 0 ? md->layers[md->layer_edited].opacity : 0.0;
    case ID_SLICE_POSITION:
        return md->slice_count > 0 ? md->slices[md->slice_selected].position_m / 1000.0 : 0.0;
    case ID_SLICE_TILT:
        return md->slice_count > 0 ? md->slices[md->slice_selected].tilt_deg : 0.0;
    case ID_SLICE_OPACITY:
        return md->slice_count > 0 ? md->slices[md->slice_selected].slice.opacity : 0.0;
    case ID_SLICE_CONTOURS: {
        /* Contour lines across the colour map's range: its span over the spacing. */
        if (md->slice_count == 0)
            return 0.0;
        const struct transfer_slice *sl = &md->slices[md->slice_selected].slice;
        return sl->contour_every > 0.0 ? (sl->tf.hi - sl->tf.lo) / sl->contour_every : 0.0;
    }
    default:
        return 0.0;
    }
}

/* Slider values snap where they are integers. */
static double snap(const struct widget *wd, double v)
{
    if (v < wd->lo)
        v = wd->lo;
    if (v > wd->hi)
        v = wd->hi;
    if (wd->id == ID_STEP)
        return floor(v + 0.5);
    if (wd->id == ID_RESOLUTION)
        return 16.0 * floor(v / 16.0 + 0.5);
    if (wd->id == ID_LOD) /* half pixels; under a half: off */
        return 0.5 * floor(2.0 * v + 0.5);
    return v;
}

static void slider_label(const struct menu *m, const struct widget *wd, char *buf, size_t n)
{
    double v = slider_value(m, wd);
    switch (wd->id) {
    case ID_SPEED:
        snprintf(buf, n, "Speed: %.2g steps/s", v);
        break;
    case ID_STEP:
        snprintf(buf, n, "Step %d of %d   %s", (int)v + 1, m->model.step_count,
                 step_date(m, (int)v));
        break;
    case ID_SCALE:
        snprintf(buf, n, "%s extinction x %.2f", species_name((enum species)m->species), v);
        break;
    case ID_TINT:
        snprintf(buf, n, "Tint %s: %.2f", (const char *[]){"red", "green", "blue"}[wd->index], v);
        break;
    case ID_AZIMUTH:
        snprintf(buf, n, "Sun azimuth: %.0f deg", v);
        break;
    case ID_ELEVATION:
        snprintf(buf, n, "Sun elevation: %.0f deg", v);
        break;
    case ID_RAY_STEP:
        if (v <= 0.0)
            snprintf(buf, n, "Ray step: automatic");
        else
            snprintf(buf, n, "Ray step: %.0f m", v);
        break;
    case ID_LOD:
        if (v <= 0.0)
            snprintf(buf, n, "Level of detail: off (every step)");
        else
            snprintf(buf, n, "Level of detail: steps %.1f pixels wide", v);
        break;
    case ID_RESOLUTION:
        snprintf(buf, n, "Light map: %d cells per axis", (int)v);
        break;
    case ID_EPSILON:
        snprintf(buf, n, "Light map error bound: %.3f", v);
        break;
    case ID_PROBE_THRESHOLD:
        snprintf(buf, n, "Visible where extinction > %.2g /km", pow(10.0, v) * 1000.0);
        break;
    case ID_PROBE_DISTANCE:
        snprintf(buf, n, "Distance along the ray: %.0f km", v);
        break;
    case ID_LAYER_OPACITY:
        snprintf(buf, n, "Layer %d opacity: %.2f", m->model.layer_edited + 1, v);
        break;
    case ID_SLICE_POSITION:
        snprintf(buf, n, "Slice %d at %c = %.1f km", m->model.slice_selected + 1,
                 "xyz"[m->model.slice_count ? m->model.slices[m->model.slice_selected].axis : 2],
                 v);
        break;
    case ID_SLICE_TILT:
        snprintf(buf, n, "Tilt: %.0f deg", v);
        break;
    case ID_SLICE_OPACITY:
        snprintf(buf, n, "Slice opacity: %.2f", v);
        break;
    case ID_SLICE_CONTOURS:
        if ((int)lround(v) == 0)
            snprintf(buf, n, "Contours: none");
        else
            snprintf(buf, n, "Contours: %d across the colour map", (int)lround(v));
        break;
    default:
        snprintf(buf, n, "%s", wd->label);
        break;
    }
}

static void layout(struct menu *m)
{
    struct menu_model *md = &m->model;
    m->n_widgets = 0;
    /* Each tab as wide as its title and the same margin (the row's spare width shared out),
     * all titles in the menu's font where they fit the row, else all in the small one, so the
     * row reads as one ("Transfer" never runs into "Light"). */
    int avail = m->w - 8 - 70, title_w[MENU_PAGE_COUNT], titles = 0;
    bool small_tabs = false;
    for (int pass = 0; pass < 2; pass++) {
        const struct menu_font *f = pass == 0 ? m->font : m->small;
        if (!f)
            break;
        titles = 0;
        for (int p = 0; p < MENU_PAGE_COUNT; p++) {
            title_w[p] = menu_font_width(f, page_titles[p]) + 12;
            titles += title_w[p];
        }
        small_tabs = pass == 1;
        if (titles <= avail)
            break;
    }
    int spare = titles <= avail ? (avail - titles) / MENU_PAGE_COUNT : -1, tab_x = 4;
    for (int p = 0; p < MENU_PAGE_COUNT; p++) {
        char name[NAME_LEN];
        snprintf(name, sizeof(name), "tab.%s", page_names[p]);
        int tab_w = spare >= 0 ? title_w[p] + spare : avail / MENU_PAGE_COUNT;
        struct widget *wd = add(m, W_BUTTON, ID_TAB, p, name, tab_x, 4, tab_w - 4, 32,
                                page_titles[p]);
        if (wd) {
            wd->selected = (int)m->page == p;
            wd->small = small_tabs;
        }
        tab_x += tab_w;
    }
    add(m, W_BUTTON, ID_RESET, 0, "reset", m->w - 70, 4, 66, 32, "Reset");
    int y = 48;
    char label[64];
    switch (m->page) {
    case MENU_PAGE_TIME: {
        int bw = (m->w - 32 - 24) / 4;
        add(m, W_BUTTON, ID_FIRST, 0, "time.first", 16, y, bw, 40, "|<");
        add(m, W_BUTTON, ID_BACK, 0, "time.back", 16 + (bw + 8), y, bw, 40, "<");
        add(m, W_BUTTON, ID_PLAY, 0, "time.play", 16 + 2 * (bw + 8), y, bw, 40,
            md->playing ? "Pause" : "Play");
        add(m, W_BUTTON, ID_FORWARD, 0, "time.forward", 16 + 3 * (bw + 8), y, bw, 40, ">");
        y += 56;
        slider(m, ID_STEP, 0, "time.slider", y, 0, md->step_count > 1 ? md->step_count - 1 : 1,
               "");
        y += 56;
        slider(m, ID_SPEED, 0, "time.speed", y, 0.25, 10.0, "");
        y += 56;
        struct widget *wd = add(m, W_TOGGLE, ID_LOOP, 0, "time.loop", 16, y, 200, 36, "Loop");
        if (wd)
            wd->selected = md->loop;
        /* The whole domain in view again (the Shift+F key). */
        add(m, W_BUTTON, ID_FRAME, 0, "time.frame", 16 + 200 + 12, y, 140, 36, "Frame");
        /* The view, the time and the look as a scene file (the C key's bookmark). */
        add(m, W_BUTTON, ID_SAVE_VIEW, 0, "time.save", m->w - 16 - 180, y, 180, 36, "Save view");
        break;
    }
    case MENU_PAGE_FIELDS:
        for (int f = 0; f < SPECIES_COUNT; f++) {
            char name[NAME_LEN];
            snprintf(name, sizeof(name), "fields.%s", species_name((enum species)f));
            snprintf(label, sizeof(label), "%s%s", species_name((enum species)f),
                     md->species_present[f] ? "" : " (not in the data)");
            struct widget *wd = add(m, W_TOGGLE, ID_SPECIES_ON, f, name, 16, y, m->w - 32, 36,
                                    label);
            if (wd) {
                wd->selected = md->species_on[f];
                wd->disabled = !md->species_present[f];
            }
            y += 44;
        }
        break;
    case MENU_PAGE_TRANSFER: {
        int hw = (m->w - 40) / 2;
        struct widget *a = add(m, W_BUTTON, ID_SUB, 0, "transfer.species", 16, y, hw, 30,
                               "Species");
        struct widget *b = add(m, W_BUTTON, ID_SUB, 1, "transfer.function", 24 + hw, y, hw, 30,
                               "Transfer function");
        if (a && b) {
            a->selected = m->sub == 0;
            b->selected = m->sub == 1;
        }
        y += 40;
        if (m->sub == 0) {
            int bw = (m->w - 32 - 4 * 6) / SPECIES_COUNT;
            for (int f = 0; f < SPECIES_COUNT; f++) {
                char name[NAME_LEN];
                snprintf(name, sizeof(name), "transfer.pick.%s", species_name((enum species)f));
                struct widget *wd = add(m, W_BUTTON, ID_PICK, f, name, 16 + f * (bw + 6), y, bw,
                                        30, species_name((enum species)f));
                if (wd)
                    wd->selected = m->species == f;
            }
            y += 42;
            slider(m, ID_SCALE, 0, "transfer.scale", y, 0.0, 4.0, "");
            y += 52;
            const char *tints[3] = {"transfer.tint.red", "transfer.tint.green",
                                    "transfer.tint.blue"};
            for (int c = 0; c < 3; c++, y += 52)
                slider(m, ID_TINT, c, tints[c], y, 0.0, 1.0, "");
        } else {
            struct widget *wd = add(m, W_TOGGLE, ID_TF_MODE, 0, "transfer.mode", 16, y, hw, 30,
                                    "Show function");
            if (wd)
                wd->selected = md->transfer_on;
            snprintf(label, sizeof(label), "Field: %s",
                     transfer_field_label(md->transfer.field));
            add(m, W_BUTTON, ID_TF_FIELD, 0, "transfer.field", 24 + hw, y, hw, 30, label);
            y += 38;
            int cw = (m->w - 32 - 3 * 6 - 100) / 4;
            for (int c = 0; c < TRANSFER_CHANNELS; c++) {
                char name[NAME_LEN];
                snprintf(name, sizeof(name), "transfer.channel.%s",
                         transfer_channel_name((enum transfer_channel)c));
                wd = add(m, W_BUTTON, ID_CHANNEL, c, name, 16 + c * (cw + 6), y, cw, 30,
                         transfer_channel_name((enum transfer_channel)c));
                if (wd)
                    wd->selected = m->channel == c;
            }
            wd = add(m, W_BUTTON, ID_DELETE, 0, "transfer.delete", m->w - 16 - 94, y, 94, 30,
                     "Delete");
            if (wd)
                wd->disabled = m->point < 0 || md->transfer.count[m->channel] <= 1;
            y += 38;
            add(m, W_CANVAS, ID_CANVAS, 0, "transfer.canvas", 16, y, m->w - 32, 170, "");
            y += 194; /* the axis' labels below it */
            int sw = 40;
            for (int s = 0; s < MENU_SLOTS; s++) {
                char name[NAME_LEN], text[8];
                snprintf(name, sizeof(name), "transfer.slot.%d", s + 1);
                snprintf(text, sizeof(text), "%d", s + 1);
                wd = add(m, W_BUTTON, ID_SLOT, s, name, 16 + s * (sw + 6), y, sw, 30, text);
                if (wd)
                    wd->selected = md->slot == s;
            }
            int x = 16 + MENU_SLOTS * (sw + 6) + 8;
            int bw2 = (m->w - 16 - x - 8) / 2;
            add(m, W_BUTTON, ID_SAVE, 0, "transfer.save", x, y, bw2, 30, "Save");
            add(m, W_BUTTON, ID_LOAD, 0, "transfer.load", x + bw2 + 8, y, bw2, 30, "Load");
        }
        break;
    }
    case MENU_PAGE_LAYERS: {
        /* A row per layer: on/off with its field's name, the field, emit or tint, edit (the
         * Transfer page's function), remove; the edited layer's opacity below. */
        struct widget *wd = add(m, W_BUTTON, ID_LAYER_ADD, 0, "layers.add", 16, y, 180, 32,
                                "Add layer");
        if (wd)
            wd->disabled = md->layer_count >= TRANSFER_LAYER_MAX;
        y += 42;
        for (int i = 0; i < md->layer_count; i++, y += 40) {
            const struct transfer_layer *l = &md->layers[i];
            char name[NAME_LEN];
            snprintf(name, sizeof(name), "layers.%d.on", i + 1);
            snprintf(label, sizeof(label), "%d on", i + 1);
            wd = add(m, W_TOGGLE, ID_LAYER_ON, i, name, 16, y, 86, 32, label);
            if (wd)
                wd->selected = l->enabled;
            snprintf(name, sizeof(name), "layers.%d.field", i + 1);
            wd = add(m, W_BUTTON, ID_LAYER_FIELD, i, name, 108, y, 200, 32,
                     transfer_field_label(l->tf.field));
            snprintf(name, sizeof(name), "layers.%d.mode", i + 1);
            add(m, W_BUTTON, ID_LAYER_MODE, i, name, 314, y, 76, 32,
                l->mode == TRANSFER_LAYER_TINT ? "tint" : "emit");
            snprintf(name, sizeof(name), "layers.%d.edit", i + 1);
            wd = add(m, W_BUTTON, ID_LAYER_EDIT, i, name, 396, y, 76, 32, "Edit");
            if (wd)
                wd->selected = md->layer_edited == i;
            snprintf(name, sizeof(name), "layers.%d.remove", i + 1);
            add(m, W_BUTTON, ID_LAYER_REMOVE, i, name, 478, y, m->w - 16 - 478, 32, "Remove");
        }
        if (md->layer_count > 0)
            slider(m, ID_LAYER_OPACITY, 0, "layers.opacity", y + 8, 0.0, 2.0, "");
        break;
    }
    case MENU_PAGE_SLICES: {
        /* A row per slice: on/off, the field, the axis, select (the sliders move it), remove;
         * the selected slice's position, tilt, opacity and contours below. */
        struct widget *wd = add(m, W_BUTTON, ID_SLICE_ADD, 0, "slices.add", 16, y, 180, 32,
                                "Add slice");
        if (wd)
            wd->disabled = md->slice_count >= TRANSFER_SLICE_MAX;
        y += 40;
        for (int i = 0; i < md->slice_count; i++, y += 38) {
            const struct menu_slice *sl = &md->slices[i];
            char name[NAME_LEN];
            snprintf(name, sizeof(name), "slices.%d.on", i + 1);
            snprintf(label, sizeof(label), "%d on", i + 1);
            wd = add(m, W_TOGGLE, ID_SLICE_ON, i, name, 16, y, 86, 30, label);
            if (wd)
                wd->selected = sl->slice.enabled;
            snprintf(name, sizeof(name), "slices.%d.field", i + 1);
            add(m, W_BUTTON, ID_SLICE_FIELD, i, name, 108, y, 200, 30,
                transfer_field_label(sl->slice.tf.field));
            snprintf(name, sizeof(name), "slices.%d.axis", i + 1);
            snprintf(label, sizeof(label), "across %c", "xyz"[sl->axis]);
            add(m, W_BUTTON, ID_SLICE_AXIS, i, name, 314, y, 86, 30, label);
            snprintf(name, sizeof(name), "slices.%d.select", i + 1);
            wd = add(m, W_BUTTON, ID_SLICE_SELECT, i, name, 406, y, 70, 30, "Move");
            if (wd)
                wd->selected = md->slice_selected == i;
            snprintf(name, sizeof(name), "slices.%d.remove", i + 1);
            add(m, W_BUTTON, ID_SLICE_REMOVE, i, name, 482, y, m->w - 16 - 482, 30, "Remove");
        }
        if (md->slice_count > 0) {
            int a = md->slices[md->slice_selected].axis;
            y += 4;
            slider(m, ID_SLICE_POSITION, 0, "slices.position", y, md->box_min_m[a] / 1000.0,
                   md->box_max_m[a] / 1000.0, "");
            y += 46;
            slider(m, ID_SLICE_TILT, 0, "slices.tilt", y, -60.0, 60.0, "");
            y += 46;
            slider(m, ID_SLICE_OPACITY, 0, "slices.opacity", y, 0.0, 1.0, "");
            y += 46;
            slider(m, ID_SLICE_CONTOURS, 0, "slices.contours", y, 0.0, 20.0, "");
        }
        break;
    }
    case MENU_PAGE_LIGHT:
        slider(m, ID_AZIMUTH, 0, "light.azimuth", y, 0.0, 360.0, "");
        y += 56;
        slider(m, ID_ELEVATION, 0, "light.elevation", y, -10.0, 90.0, "");
        break;
    case MENU_PAGE_QUALITY:
        slider(m, ID_RAY_STEP, 0, "quality.step", y, 0.0,
               md->step_max_m > 0.0 ? md->step_max_m : 2000.0, "");
        y += 56;
        slider(m, ID_LOD, 0, "quality.lod", y, 0.0, 8.0, "");
        y += 56;
        slider(m, ID_RESOLUTION, 0, "quality.resolution", y, 16.0, 256.0, "");
        y += 56;
        slider(m, ID_EPSILON, 0, "quality.epsilon", y, 0.001, 0.1, "");
        y += 56;
        {
            struct widget *wd = add(m, W_TOGGLE, ID_DIFFUSE, 0, "quality.diffuse", 16, y,
                                    m->w - 32, 36, "Diffuse light (multiple scattering)");
            if (wd) {
                wd->selected = md->diffuse_on;
                wd->disabled = !md->diffuse_possible;
            }
        }
        break;
    case MENU_PAGE_PROBE: {
        struct widget *wd = add(m, W_TOGGLE, ID_PROBE_ON, 0, "probe.on", 16, y, m->w - 32, 36,
                                "Probe: the values at the wand (key V)");
        if (wd)
            wd->selected = md->probe_on;
        y += 44;
        snprintf(label, sizeof(label), "Reads: %s",
                 md->probe_mode == MENU_PROBE_AT_DISTANCE ? "a set distance along the ray"
                                                          : "the first visible point");
        add(m, W_BUTTON, ID_PROBE_MODE, 0, "probe.mode", 16, y, m->w - 32, 36, label);
        y += 52;
        wd = slider(m, ID_PROBE_THRESHOLD, 0, "probe.threshold", y, -6.0, -1.0, "");
        if (wd)
            wd->disabled = md->probe_mode != MENU_PROBE_FIRST_VISIBLE;
        y += 56;
        wd = slider(m, ID_PROBE_DISTANCE, 0, "probe.distance", y, 0.0,
                    md->probe_distance_max_m > 0.0 ? md->probe_distance_max_m / 1000.0 : 500.0,
                    "");
        if (wd)
            wd->disabled = md->probe_mode != MENU_PROBE_AT_DISTANCE;
        break;
    }
    case MENU_PAGE_COUNT:
        break;
    }
}

/* ---- drawing --------------------------------------------------------------------------- */

static const uint8_t c_panel[3] = {22, 28, 40}, c_widget[3] = {48, 60, 82},
                     c_hover[3] = {70, 90, 124}, c_selected[3] = {40, 110, 170},
                     c_text[3] = {235, 238, 245}, c_dim[3] = {120, 126, 140},
                     c_border[3] = {150, 170, 200}, c_canvas[3] = {12, 14, 20};

static void fill(struct menu *m, int x, int y, int w, int h, const uint8_t rgb[3])
{
    for (int j = y < 0 ? 0 : y; j < y + h && j < m->h; j++)
        for (int i = x < 0 ? 0 : x; i < x + w && i < m->w; i++) {
            uint8_t *p = &m->pixels[4 * ((size_t)j * (size_t)m->w + (size_t)i)];
            p[0] = rgb[0];
            p[1] = rgb[1];
            p[2] = rgb[2];
            p[3] = 255;
        }
}

static void frame(struct menu *m, const int r[4], const uint8_t rgb[3])
{
    fill(m, r[0], r[1], r[2], 1, rgb);
    fill(m, r[0], r[1] + r[3] - 1, r[2], 1, rgb);
    fill(m, r[0], r[1], 1, r[3], rgb);
    fill(m, r[0] + r[2] - 1, r[1], 1, r[3], rgb);
}

static void line(struct menu *m, float x0, float y0, float x1, float y1, const uint8_t rgb[3])
{
    int n = (int)(fmaxf(fabsf(x1 - x0), fabsf(y1 - y0))) + 1;
    for (int i = 0; i <= n; i++) {
        float t = (float)i / (float)n;
        int x = (int)(x0 + t * (x1 - x0)), y = (int)(y0 + t * (y1 - y0));
        fill(m, x, y, 2, 2, rgb);
    }
}

static void text(struct menu *m, int x, int y, const char *s, const uint8_t rgb[3])
{
    menu_font_draw(m->font, m->pixels, m->w, m->h, x, y, s, rgb);
}

/* A label wider than its widget is drawn in the small font, so that it does not run into its
 * neighbour. */
static void text_centered(struct menu *m, const int r[4], const char *s, const uint8_t rgb[3],
                          bool small)
{
    const struct menu_font *f = small && m->small ? m->small : m->font;
    int tw = menu_font_width(f, s);
    if (tw > r[2] - 6 && m->small) {
        f = m->small;
        tw = menu_font_width(f, s);
    }
    int x = r[0] + (r[2] - tw) / 2;
    int y = r[1] + (r[3] - menu_font_ascent(f)) / 2 - 2;
    menu_font_draw(f, m->pixels, m->w, m->h, x, y, s, rgb);
}

static int hovered(const struct menu *m);

static void canvas_xy(const int r[4], float x, float v, float *px, float *py)
{
    *px = (float)r[0] + 6.0f + x * (float)(r[2] - 12);
    *py = (float)(r[1] + r[3]) - 6.0f - v * (float)(r[3] - 12);
}

/* A value of FIELD in the unit the editor labels it with (g/kg, C, m/s). */
static double shown_value(enum transfer_field f, double v)
{
    if (f == TRANSFER_FIELD_TEMPERATURE)
        return v - 273.15;
    if (f == TRANSFER_FIELD_WIND || f == TRANSFER_FIELD_THETA || f == TRANSFER_FIELD_RH ||
        f == TRANSFER_FIELD_W)
        return v;
    return v * 1e3; /* g/kg; vorticity in 1e-3/s */
}

static const char *shown_unit(enum transfer_field f)
{
    switch (f) {
    case TRANSFER_FIELD_TEMPERATURE:
        return "C";
    case TRANSFER_FIELD_WIND:
        return "m/s";
    case TRANSFER_FIELD_THETA:
        return "K";
    case TRANSFER_FIELD_RH:
        return "%";
    case TRANSFER_FIELD_W:
        return "m/s";
    case TRANSFER_FIELD_VORTICITY:
        return "1e-3/s";
    default:
        return "g/kg";
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
    case TRANSFER_FIELD_THETA:
        return "potential temperature";
    case TRANSFER_FIELD_RH:
        return "relative humidity";
    case TRANSFER_FIELD_W:
        return "vertical velocity";
    case TRANSFER_FIELD_VORTICITY:
        return "vertical vorticity";
    default:
        return "wind speed";
    }
}

/* 1, 2 or 5 times a power of ten: about SPAN / 5. */
static double tick_step(double span)
{
    double raw = span / 5.0, p = pow(10.0, floor(log10(raw))), f = raw / p;
    return (f < 1.5 ? 1.0 : f < 3.5 ? 2.0 : f < 7.5 ? 5.0 : 10.0) * p;
}

/* The bars of the field's histogram over the canvas' width, their heights the square root of
 * the count (a sparse bin still shows beside a full one). */
static void draw_histogram(struct menu *m, const int r[4], const struct transfer_histogram *h)
{
    static const uint8_t bar[3] = {44, 56, 74};
    double top = sqrt((double)transfer_histogram_max(h));
    if (!(top > 0.0))
        return;
    float x0 = (float)r[0] + 6.0f, w = (float)(r[2] - 12), base = (float)(r[1] + r[3]) - 12.0f;
    float full = base - ((float)r[1] + 6.0f);
    for (int b = 0; b < TRANSFER_HISTOGRAM_BINS; b++) {
        if (!h->count[b])
            continue;
        int a = (int)(x0 + w * (float)b / TRANSFER_HISTOGRAM_BINS);
        int e = (int)(x0 + w * (float)(b + 1) / TRANSFER_HISTOGRAM_BINS);
        int hgt = (int)ceilf(full * (float)(sqrt((double)h->count[b]) / top));
        fill(m, a, (int)base - hgt, e - a > 1 ? e - a - 1 : 1, hgt, bar);
    }
}

static void draw_canvas(struct menu *m, const struct widget *wd)
{
    const int *r = wd->rect;
    fill(m, r[0], r[1], r[2], r[3], c_canvas);
    frame(m, r, c_border);
    const struct menu_model *md = &m->model;
    const struct transfer_function *tf = &md->transfer;
    const struct transfer_histogram *h = &md->histogram;
    bool bars = md->histogram_valid && h->field == tf->field && h->lo == tf->lo && h->hi == tf->hi;
    if (bars)
        draw_histogram(m, r, h);
    /* The colour map along the bottom: what the function gives, over an opaque strip. */
    for (int i = 0; i < r[2] - 2; i++) {
        float x = (float)i / (float)(r[2] - 3);
        uint8_t rgb[3];
        float a = transfer_eval(tf, TRANSFER_ALPHA, x);
        for (int c = 0; c < 3; c++) {
            float v = transfer_eval(tf, (enum transfer_channel)c, x);
            rgb[c] = (uint8_t)(255.0f * (v * (0.3f + 0.7f * a)));
        }
        fill(m, r[0] + 1 + i, r[1] + r[3] - 10, 1, 9, rgb);
    }
    static const uint8_t channel_rgb[TRANSFER_CHANNELS][3] = {
        {230, 70, 70}, {80, 210, 90}, {90, 130, 240}, {230, 230, 230}};
    for (int c = 0; c < TRANSFER_CHANNELS; c++) {
        const uint8_t *col = c == m->channel ? channel_rgb[c] : c_dim;
        float prev_x = 0, prev_y = 0;
        for (int i = 0; i <= 64; i++) {
            float x = (float)i / 64.0f, px, py;
            canvas_xy(r, x, transfer_eval(tf, (enum transfer_channel)c, x), &px, &py);
            if (i)
                line(m, prev_x, prev_y, px, py, col);
            prev_x = px;
            prev_y = py;
        }
    }
    for (int i = 0; i < tf->count[m->channel]; i++) {
        const struct transfer_point *p = &tf->points[m->channel][i];
        float px, py;
        canvas_xy(r, p->x, p->v, &px, &py);
        bool sel = i == m->point;
        fill(m, (int)px - 5, (int)py - 5, 11, 11, sel ? c_text : channel_rgb[m->channel]);
        if (sel)
            fill(m, (int)px - 3, (int)py - 3, 7, 7, channel_rgb[m->channel]);
    }
    /* What the axes are: the field and its unit, the channel's value; the point chosen.  Each
     * label on a box of the canvas' own colour, over the curves. */
    char text[96];
    snprintf(text, sizeof(text), "%s, %s%s", field_title(tf->field), shown_unit(tf->field),
             bars ? " (bars: voxels)" : "");
    int th = menu_font_ascent(m->small) + 6;
    fill(m, r[0] + 2, r[1] + 2, menu_font_width(m->small, text) + 12, th, c_canvas);
    menu_font_draw(m->small, m->pixels, m->w, m->h, r[0] + 8, r[1] + 4, text, c_text);
    if (m->point >= 0 && m->point < tf->count[m->channel]) {
        const struct transfer_point *p = &tf->points[m->channel][m->point];
        double v = shown_value(tf->field, tf->lo + p->x * (tf->hi - tf->lo));
        snprintf(text, sizeof(text), "%s %.2f at %.3g %s",
                 transfer_channel_name((enum transfer_channel)m->channel), p->v, v,
                 shown_unit(tf->field));
    } else {
        snprintf(text, sizeof(text), "%s: 0 to 1",
                 transfer_channel_name((enum transfer_channel)m->channel));
    }
    int tw = menu_font_width(m->small, text);
    fill(m, r[0] + r[2] - 14 - tw, r[1] + 2, tw + 12, th, c_canvas);
    menu_font_draw(m->small, m->pixels, m->w, m->h, r[0] + r[2] - 8 - tw, r[1] + 4, text, c_text);
    /* Ticks with values under the canvas, in the field's unit. */
    double lo = shown_value(tf->field, tf->lo), hi = shown_value(tf->field, tf->hi);
    double step = tick_step(hi - lo);
    for (double t = ceil(lo / step - 1e-9) * step; t <= hi + 1e-9 * step; t += step) {
        float x = (float)((t - lo) / (hi - lo)), px, py;
        canvas_xy(r, x, 0.0f, &px, &py);
        fill(m, (int)px, r[1] + r[3], 1, 4, c_border);
        char label[32];
        snprintf(label, sizeof(label), "%g", fabs(t) < 1e-9 * step ? 0.0 : t);
        int lw = menu_font_width(m->small, label);
        int lx = (int)px - lw / 2;
        lx = lx < r[0] ? r[0] : lx + lw > r[0] + r[2] ? r[0] + r[2] - lw : lx;
        menu_font_draw(m->small, m->pixels, m->w, m->h, lx, r[1] + r[3] + 4, label, c_text);
    }
}

static void redraw(struct menu *m)
{
    layout(m);
    fill(m, 0, 0, m->w, m->h, c_panel);
    int hover = hovered(m);
    for (int i = 0; i < m->n_widgets; i++) {
        struct widget *wd = &m->widgets[i];
        const int *r = wd->rect;
        const uint8_t *bg = wd->selected ? c_selected : (i == hover ? c_hover : c_widget);
        const uint8_t *fg = wd->disabled ? c_dim : c_text;
        char label[96];
        switch (wd->kind) {
        case W_BUTTON:
            fill(m, r[0], r[1], r[2], r[3], bg);
            text_centered(m, r, wd->label, fg, wd->small);
            break;
        case W_TOGGLE: {
            fill(m, r[0], r[1], r[2], r[3], i == hover ? c_hover : c_widget);
            int box[4] = {r[0] + 8, r[1] + (r[3] - 18) / 2, 18, 18};
            fill(m, box[0], box[1], box[2], box[3], wd->selected ? c_selected : c_canvas);
            frame(m, box, c_border);
            text(m, r[0] + 36, r[1] + (r[3] - menu_font_ascent(m->font)) / 2 - 2, wd->label,
                 fg);
            break;
        }
        case W_SLIDER: {
            slider_label(m, wd, label, sizeof(label));
            text(m, r[0], r[1], label, fg);
            int ty = r[1] + r[3] - 12;
            fill(m, r[0], ty, r[2], 6, c_widget);
            double v = slider_value(m, wd);
            double t = wd->hi > wd->lo ? (v - wd->lo) / (wd->hi - wd->lo) : 0.0;
            t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
            int kx = r[0] + (int)(t * (r[2] - 12));
            fill(m, r[0], ty, kx - r[0] + 6, 6, c_selected);
            fill(m, kx, ty - 7, 12, 20, i == hover || (m->dragging && m->pressed == i) ? c_text
                                                                                    : c_border);
            break;
        }
        case W_CANVAS:
            draw_canvas(m, wd);
            break;
        case W_LABEL:
            text(m, r[0], r[1], wd->label, fg);
            break;
        }
    }
    if (m->status[0])
        text(m, 16, m->h - 30, m->status, c_dim);
    frame(m, (const int[]){0, 0, m->w, m->h}, c_border);
    m->generation++;
    m->dirty = false;
}

/* ---- life ------------------------------------------------------------------------------ */

struct menu *menu_create(const struct menu_desc *desc, const struct menu_model *model)
{
    struct menu *m = calloc(1, sizeof(*m));
    if (!m) {
        log_error("menu: out of memory");
        return NULL;
    }
    if (desc)
        m->desc = *desc;
    m->w = m->desc.width > 0 ? m->desc.width : 576;
    m->h = m->desc.height > 0 ? m->desc.height : 440;
    const char *font = m->desc.font_path ? m->desc.font_path : MENU_FONT_PATH;
    m->font = menu_font_create(font, 20.0f);
    m->small = m->font ? menu_font_create(font, 15.0f) : NULL;
    m->pixels = calloc((size_t)m->w * (size_t)m->h, 4);
    if (!m->font || !m->small || !m->pixels) {
        if (!m->pixels)
            log_error("menu: out of memory");
        menu_destroy(m);
        return NULL;
    }
    m->model = *model;
    m->visible = true;
    m->pressed = -1;
    m->point = -1;
    m->channel = TRANSFER_ALPHA;
    m->hit_t = -1.0f;
    m->dirty = true;
    const float c[3] = {0, 0, 0}, r[3] = {1, 0, 0}, u[3] = {0, 1, 0};
    menu_set_pose(m, c, r, u, 1.0f);
    layout(m);
    return m;
}

void menu_destroy(struct menu *m)
{
    if (!m)
        return;
    menu_font_destroy(m->font);
    menu_font_destroy(m->small);
    free(m->pixels);
    free(m);
}

struct menu_model *menu_model(struct menu *m)
{
    return &m->model;
}

void menu_model_changed(struct menu *m)
{
    if (m->point >= m->model.transfer.count[m->channel])
        m->point = -1;
    m->dirty = true;
}

void menu_set_visible(struct menu *m, bool visible)
{
    if (m->visible != visible)
        m->changes |= MENU_CHANGE_VISIBLE;
    m->visible = visible;
    if (!visible) {
        m->dragging = false;
        m->pressed = -1;
    }
}

bool menu_visible(const struct menu *m)
{
    return m->visible;
}

void menu_set_page(struct menu *m, enum menu_page page)
{
    if (page < 0 || page >= MENU_PAGE_COUNT)
        return;
    m->page = page;
    m->dragging = false;
    m->pressed = -1;
    m->dirty = true;
    layout(m);
}

enum menu_page menu_page(const struct menu *m)
{
    return m->page;
}

void menu_set_status(struct menu *m, const char *s)
{
    snprintf(m->status, sizeof(m->status), "%s", s ? s : "");
    m->dirty = true;
}

const uint8_t *menu_pixels(struct menu *m, int *w, int *h, unsigned *generation)
{
    if (m->dirty)
        redraw(m);
    *w = m->w;
    *h = m->h;
    if (generation)
        *generation = m->generation;
    return m->pixels;
}

/* ---- pose and pointer ------------------------------------------------------------------ */

static void cross(const float a[3], const float b[3], float out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static float dot(const float a[3], const float b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

void menu_set_pose(struct menu *m, const float center[3], const float right[3],
                   const float up[3], float width)
{
    memcpy(m->center, center, sizeof(m->center));
    memcpy(m->right, right, sizeof(m->right));
    memcpy(m->up, up, sizeof(m->up));
    m->width = width;
    cross(right, up, m->normal);
}

float menu_aspect(const struct menu *m)
{
    return (float)m->h / (float)m->w;
}

void menu_corners(const struct menu *m, float out[4][3])
{
    float hw = 0.5f * m->width, hh = 0.5f * m->width * menu_aspect(m);
    const float sx[4] = {-1, 1, 1, -1}, sy[4] = {-1, -1, 1, 1};
    for (int k = 0; k < 4; k++)
        for (int i = 0; i < 3; i++)
            out[k][i] = m->center[i] + sx[k] * hw * m->right[i] + sy[k] * hh * m->up[i];
}

/* Panel pixel (PX, PY) -> menu space. */
static void panel_point(const struct menu *m, float px, float py, float out[3])
{
    float x = (px / (float)m->w - 0.5f) * m->width;
    float y = (0.5f - py / (float)m->h) * m->width * menu_aspect(m);
    for (int i = 0; i < 3; i++)
        out[i] = m->center[i] + x * m->right[i] + y * m->up[i];
}

/* Intersects the ray with the panel: hit_t (< 0: missed) and the pointer in pixels. */
static void update_hit(struct menu *m)
{
    m->hit_t = -1.0f;
    if (!m->have_ray || !m->visible)
        return;
    float denom = dot(m->ray_d, m->normal);
    if (fabsf(denom) < 1e-6f)
        return;
    float d[3];
    for (int i = 0; i < 3; i++)
        d[i] = m->center[i] - m->ray_o[i];
    float t = dot(d, m->normal) / denom;
    if (t < 0.0f)
        return;
    float p[3];
    for (int i = 0; i < 3; i++)
        p[i] = m->ray_o[i] + t * m->ray_d[i] - m->center[i];
    float x = dot(p, m->right) / m->width + 0.5f;
    float y = 0.5f - dot(p, m->up) / (m->width * menu_aspect(m));
    m->px = x * (float)m->w;
    m->py = y * (float)m->h;
    /* While dragging, the pointer may leave the panel: keep following its plane. */
    if ((x >= 0.0f && x <= 1.0f && y >= 0.0f && y <= 1.0f) || m->dragging)
        m->hit_t = t;
}

static int widget_at(const struct menu *m, float px, float py)
{
    for (int i = 0; i < m->n_widgets; i++) {
        const int *r = m->widgets[i].rect;
        if (px >= r[0] && px < r[0] + r[2] && py >= r[1] && py < r[1] + r[3])
            return i;
    }
    return -1;
}

static int hovered(const struct menu *m)
{
    return m->hit_t >= 0.0f ? widget_at(m, m->px, m->py) : -1;
}

bool menu_ray(const struct menu *m, float origin[3], float direction[3], float *hit)
{
    if (!m->have_ray)
        return false;
    memcpy(origin, m->ray_o, sizeof(m->ray_o));
    memcpy(direction, m->ray_d, sizeof(m->ray_d));
    *hit = m->hit_t;
    return true;
}

bool menu_captures(const struct menu *m)
{
    return m->visible && (m->hit_t >= 0.0f || m->dragging || m->pressed >= 0);
}

static const struct widget *find_widget(struct menu *m, const char *name)
{
    if (m->dirty)
        layout(m);
    for (int i = 0; i < m->n_widgets; i++)
        if (strcmp(m->widgets[i].name, name) == 0)
            return &m->widgets[i];
    return NULL;
}

bool menu_widget_rect(struct menu *m, const char *name, int rect[4])
{
    const struct widget *wd = find_widget(m, name);
    if (!wd)
        return false;
    memcpy(rect, wd->rect, sizeof(wd->rect));
    return true;
}

bool menu_widget_known(struct menu *m, const char *name)
{
    /* Each page, and the transfer page's two halves, laid out in turn; then the menu as it
     * was. */
    enum menu_page page = m->page;
    int sub = m->sub;
    bool found = false;
    /* The Layers and Slices pages with every row they can have (a script may add the layers
     * and slices it aims at). */
    int layers = m->model.layer_count, slices = m->model.slice_count;
    for (int p = 0; p < MENU_PAGE_COUNT && !found; p++) {
        for (int s = 0; s < 2 && !found; s++) {
            m->page = (enum menu_page)p;
            m->sub = s;
            m->model.layer_count = p == MENU_PAGE_LAYERS ? TRANSFER_LAYER_MAX : layers;
            m->model.slice_count = p == MENU_PAGE_SLICES ? TRANSFER_SLICE_MAX : slices;
            layout(m);
            for (int i = 0; i < m->n_widgets && !found; i++)
                found = strcmp(m->widgets[i].name, name) == 0;
        }
    }
    m->model.layer_count = layers;
    m->model.slice_count = slices;
    m->page = page;
    m->sub = sub;
    layout(m);
    return found;
}

bool menu_widget_point(struct menu *m, const char *name, float u, float v, float out[3])
{
    const struct widget *wd = find_widget(m, name);
    if (!wd)
        return false;
    panel_point(m, (float)wd->rect[0] + u * (float)wd->rect[2],
                (float)wd->rect[1] + v * (float)wd->rect[3], out);
    return true;
}

/* ---- the trigger ----------------------------------------------------------------------- */

static double slider_at(const struct widget *wd, float px)
{
    double t = (px - wd->rect[0] - 6.0) / (double)(wd->rect[2] - 12);
    t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
    return snap(wd, wd->lo + t * (wd->hi - wd->lo));
}

static void canvas_value(const struct widget *wd, float px, float py, float *x, float *v)
{
    const int *r = wd->rect;
    *x = (px - (float)r[0] - 6.0f) / (float)(r[2] - 12);
    *v = ((float)(r[1] + r[3]) - 6.0f - py) / (float)(r[3] - 12);
    *x = *x < 0.0f ? 0.0f : *x > 1.0f ? 1.0f : *x;
    *v = *v < 0.0f ? 0.0f : *v > 1.0f ? 1.0f : *v;
}

/* SL's plane from its axis, position and tilt, through the centre of MD's box. */
static void slice_plane_in_box(const struct menu_model *md, struct menu_slice *sl)
{
    double c[3];
    for (int k = 0; k < 3; k++)
        c[k] = 0.5 * (md->box_min_m[k] + md->box_max_m[k]);
    menu_slice_plane(sl, c);
}

static void commit_slider(struct menu *m, const struct widget *wd, double v)
{
    struct menu_model *md = &m->model;
    switch (wd->id) {
    case ID_SPEED:
        md->speed = v;
        m->changes |= MENU_CHANGE_PLAYBACK;
        break;
    case ID_STEP:
        md->step = (int)v;
        m->changes |= MENU_CHANGE_STEP;
        break;
    case ID_SCALE:
        md->species_scale[m->species] = v;
        m->changes |= MENU_CHANGE_SPECIES;
        break;
    case ID_TINT:
        md->species_tint[m->species][wd->index] = (float)v;
        m->changes |= MENU_CHANGE_SPECIES;
        break;
    case ID_AZIMUTH:
        md->sun_azimuth = v;
        m->changes |= MENU_CHANGE_SUN;
        break;
    case ID_ELEVATION:
        md->sun_elevation = v;
        m->changes |= MENU_CHANGE_SUN;
        break;
    case ID_RAY_STEP:
        md->step_m = v;
        m->changes |= MENU_CHANGE_QUALITY;
        break;
    case ID_LOD:
        md->lod_pixels = v;
        m->changes |= MENU_CHANGE_QUALITY;
        break;
    case ID_RESOLUTION:
        md->light_resolution = (int)v;
        m->changes |= MENU_CHANGE_QUALITY;
        break;
    case ID_EPSILON:
        md->epsilon = v;
        m->changes |= MENU_CHANGE_QUALITY;
        break;
    case ID_PROBE_THRESHOLD:
        md->probe_threshold = pow(10.0, v);
        m->changes |= MENU_CHANGE_PROBE;
        break;
    case ID_PROBE_DISTANCE:
        md->probe_distance_m = v * 1000.0;
        m->changes |= MENU_CHANGE_PROBE;
        break;
    case ID_LAYER_OPACITY:
        if (md->layer_count > 0) {
            md->layers[md->layer_edited].opacity = v;
            m->changes |= MENU_CHANGE_TRANSFER;
        }
        break;
    case ID_SLICE_POSITION:
    case ID_SLICE_TILT:
    case ID_SLICE_OPACITY:
    case ID_SLICE_CONTOURS: {
        if (md->slice_count == 0)
            break;
        struct menu_slice *sl = &md->slices[md->slice_selected];
        if (wd->id == ID_SLICE_POSITION)
            sl->position_m = v * 1000.0;
        else if (wd->id == ID_SLICE_TILT)
            sl->tilt_deg = v;
        else if (wd->id == ID_SLICE_OPACITY)
            sl->slice.opacity = v;
        else {
            int count = (int)lround(v);
            sl->slice.contour_every = count > 0 ? (sl->slice.tf.hi - sl->slice.tf.lo) / count : 0.0;
        }
        slice_plane_in_box(md, sl);
        m->changes |= MENU_CHANGE_SLICES;
        break;
    }
    default:
        break;
    }
}

static void step_by(struct menu *m, int delta)
{
    struct menu_model *md = &m->model;
    if (md->step_count < 1)
        return;
    int s = md->step + delta;
    if (md->loop)
        s = ((s % md->step_count) + md->step_count) % md->step_count;
    s = s < 0 ? 0 : s >= md->step_count ? md->step_count - 1 : s;
    if (s != md->step) {
        md->step = s;
        m->changes |= MENU_CHANGE_STEP;
    }
}

#define MENU_LAYER_OPACITY 0.02 /* of a layer the Layers page adds */

/* Layer I becomes the one the Transfer page edits. */
static void select_layer(struct menu *m, int i)
{
    struct menu_model *md = &m->model;
    md->layer_edited = i;
    md->transfer = md->layers[i].tf;
    md->transfer_on = md->layers[i].enabled;
    m->point = -1;
}

/* A button released over itself. */
static void activate(struct menu *m, const struct widget *wd)
{
    struct menu_model *md = &m->model;
    if (wd->disabled)
        return;
    switch (wd->id) {
    case ID_TAB:
        m->page = (enum menu_page)wd->index;
        break;
    case ID_RESET:
        m->changes |= MENU_ACTION_RESET_VIEW;
        break;
    case ID_PLAY:
        md->playing = !md->playing;
        m->changes |= MENU_CHANGE_PLAYBACK;
        break;
    case ID_FIRST:
        step_by(m, -md->step);
        break;
    case ID_BACK:
        step_by(m, -1);
        break;
    case ID_FORWARD:
        step_by(m, 1);
        break;
    case ID_LOOP:
        md->loop = !md->loop;
        m->changes |= MENU_CHANGE_PLAYBACK;
        break;
    case ID_DIFFUSE:
        md->diffuse_on = !md->diffuse_on;
        m->changes |= MENU_CHANGE_QUALITY;
        break;
    case ID_SPECIES_ON:
        md->species_on[wd->index] = !md->species_on[wd->index];
        m->changes |= MENU_CHANGE_SPECIES;
        break;
    case ID_SUB:
        m->sub = wd->index;
        break;
    case ID_PICK:
        m->species = wd->index;
        break;
    case ID_TF_MODE:
        md->transfer_on = !md->transfer_on;
        m->changes |= MENU_CHANGE_TRANSFER;
        break;
    case ID_TF_FIELD: {
        enum transfer_field f = (enum transfer_field)((md->transfer.field + 1) %
                                                      TRANSFER_FIELD_COUNT);
        char name[TRANSFER_NAME_MAX];
        memcpy(name, md->transfer.name, sizeof(name));
        transfer_defaults(&md->transfer, f);
        memcpy(md->transfer.name, name, sizeof(name));
        m->point = -1;
        md->transfer_on = true; /* an edit shows the function at once */
        m->changes |= MENU_CHANGE_TRANSFER;
        break;
    }
    case ID_CHANNEL:
        m->channel = wd->index;
        m->point = -1;
        break;
    case ID_DELETE:
        if (transfer_delete_point(&md->transfer, (enum transfer_channel)m->channel, m->point)) {
            m->point = -1;
            md->transfer_on = true;
            m->changes |= MENU_CHANGE_TRANSFER;
        }
        break;
    case ID_SLOT:
        md->slot = wd->index;
        break;
    case ID_SAVE:
        m->changes |= MENU_ACTION_SAVE;
        break;
    case ID_LOAD:
        m->changes |= MENU_ACTION_LOAD;
        m->point = -1;
        break;
    case ID_SAVE_VIEW:
        m->changes |= MENU_ACTION_SAVE_VIEW;
        break;
    case ID_FRAME:
        m->changes |= MENU_ACTION_FRAME;
        break;
    case ID_PROBE_ON:
        md->probe_on = !md->probe_on;
        m->changes |= MENU_CHANGE_PROBE;
        break;
    case ID_SLICE_ADD:
        if (md->slice_count < TRANSFER_SLICE_MAX) {
            /* Temperature across z, half way up the box, opaque. */
            struct menu_slice *sl = &md->slices[md->slice_count];
            memset(sl, 0, sizeof(*sl));
            sl->slice.enabled = true;
            sl->slice.opacity = 1.0;
            transfer_defaults(&sl->slice.tf, TRANSFER_FIELD_TEMPERATURE);
            sl->axis = 2;
            sl->position_m = 0.5 * (md->box_min_m[2] + md->box_max_m[2]);
            slice_plane_in_box(md, sl);
            md->slice_selected = md->slice_count++;
            m->changes |= MENU_CHANGE_SLICES;
        }
        break;
    case ID_SLICE_ON:
        md->slices[wd->index].slice.enabled = !md->slices[wd->index].slice.enabled;
        m->changes |= MENU_CHANGE_SLICES;
        break;
    case ID_SLICE_FIELD: {
        struct transfer_slice *sl = &md->slices[wd->index].slice;
        int count = sl->contour_every > 0.0 ? (int)lround((sl->tf.hi - sl->tf.lo) /
                                                          sl->contour_every)
                                            : 0;
        transfer_defaults(&sl->tf, (enum transfer_field)((sl->tf.field + 1) % TRANSFER_FIELD_COUNT));
        sl->contour_every = count > 0 ? (sl->tf.hi - sl->tf.lo) / count : 0.0;
        m->changes |= MENU_CHANGE_SLICES;
        break;
    }
    case ID_SLICE_AXIS: {
        struct menu_slice *sl = &md->slices[wd->index];
        sl->axis = (sl->axis + 1) % 3;
        sl->tilt_deg = 0.0;
        sl->position_m = 0.5 * (md->box_min_m[sl->axis] + md->box_max_m[sl->axis]);
        slice_plane_in_box(md, sl);
        m->changes |= MENU_CHANGE_SLICES;
        break;
    }
    case ID_SLICE_SELECT:
        md->slice_selected = wd->index;
        break;
    case ID_SLICE_REMOVE:
        for (int i = wd->index; i + 1 < md->slice_count; i++)
            md->slices[i] = md->slices[i + 1];
        md->slice_count--;
        if (md->slice_selected >= md->slice_count)
            md->slice_selected = md->slice_count > 0 ? md->slice_count - 1 : 0;
        m->changes |= MENU_CHANGE_SLICES;
        break;
    case ID_LAYER_ADD:
        if (md->layer_count < TRANSFER_LAYER_MAX) {
            /* A temperature layer, shown: the first thing a forecaster adds.  Faint: the
             * default function's density is made for a column of a few km, and a layer fills
             * the whole domain, hundreds of km along a slanting ray. */
            struct transfer_layer *l = &md->layers[md->layer_count];
            *l = (struct transfer_layer){.enabled = true, .opacity = MENU_LAYER_OPACITY,
                                         .mode = TRANSFER_LAYER_EMIT};
            transfer_defaults(&l->tf, TRANSFER_FIELD_TEMPERATURE);
            md->layer_edited = md->layer_count++;
            select_layer(m, md->layer_edited);
            m->changes |= MENU_CHANGE_TRANSFER;
        }
        break;
    case ID_LAYER_ON:
        md->layers[wd->index].enabled = !md->layers[wd->index].enabled;
        if (wd->index == md->layer_edited)
            md->transfer_on = md->layers[wd->index].enabled;
        m->changes |= MENU_CHANGE_TRANSFER;
        break;
    case ID_LAYER_FIELD: {
        struct transfer_layer *l = &md->layers[wd->index];
        transfer_defaults(&l->tf, (enum transfer_field)((l->tf.field + 1) % TRANSFER_FIELD_COUNT));
        if (wd->index == md->layer_edited)
            select_layer(m, wd->index);
        m->changes |= MENU_CHANGE_TRANSFER;
        break;
    }
    case ID_LAYER_MODE:
        md->layers[wd->index].mode = md->layers[wd->index].mode == TRANSFER_LAYER_TINT
                                         ? TRANSFER_LAYER_EMIT
                                         : TRANSFER_LAYER_TINT;
        m->changes |= MENU_CHANGE_TRANSFER;
        break;
    case ID_LAYER_EDIT:
        /* Its function in the Transfer page's editor, at once. */
        select_layer(m, wd->index);
        m->page = MENU_PAGE_TRANSFER;
        m->sub = 1;
        break;
    case ID_LAYER_REMOVE:
        for (int i = wd->index; i + 1 < md->layer_count; i++)
            md->layers[i] = md->layers[i + 1];
        md->layer_count--;
        if (md->layer_edited >= md->layer_count)
            md->layer_edited = md->layer_count > 0 ? md->layer_count - 1 : 0;
        if (md->layer_count > 0) {
            select_layer(m, md->layer_edited);
        } else {
            transfer_defaults(&md->transfer, TRANSFER_FIELD_QVAPOR);
            md->transfer_on = false;
        }
        m->changes |= MENU_CHANGE_TRANSFER;
        break;
    case ID_PROBE_MODE:
        md->probe_mode = md->probe_mode == MENU_PROBE_AT_DISTANCE ? MENU_PROBE_FIRST_VISIBLE
                                                                  : MENU_PROBE_AT_DISTANCE;
        m->changes |= MENU_CHANGE_PROBE;
        break;
    default:
        break;
    }
}

static void trigger_down(struct menu *m)
{
    m->down = true;
    int i = hovered(m);
    m->pressed = i;
    m->dragging = false;
    m->moved = false;
    if (i < 0)
        return;
    struct widget *wd = &m->widgets[i];
    if (wd->disabled)
        return;
    if (wd->kind == W_SLIDER) {
        m->dragging = true;
        m->drag = slider_at(wd, m->px);
    } else if (wd->kind == W_CANVAS) {
        struct transfer_function *tf = &m->model.transfer;
        enum transfer_channel c = (enum transfer_channel)m->channel;
        int best = -1;
        float best_d = PICK_RADIUS;
        for (int k = 0; k < tf->count[c]; k++) {
            float px, py;
            canvas_xy(wd->rect, tf->points[c][k].x, tf->points[c][k].v, &px, &py);
            float d = hypotf(px - m->px, py - m->py);
            if (d <= best_d) {
                best_d = d;
                best = k;
            }
        }
        if (best < 0) {
            float x, v;
            canvas_value(wd, m->px, m->py, &x, &v);
            best = transfer_add_point(tf, c, x, v);
            if (best >= 0) {
                m->model.transfer_on = true; /* an edit shows the function at once */
                m->changes |= MENU_CHANGE_TRANSFER;
            }
        }
        m->point = best;
        m->dragging = best >= 0;
    }
    m->dirty = true;
}

static void pointer_moved(struct menu *m)
{
    if (!m->dragging || m->pressed < 0)
        return;
    struct widget *wd = &m->widgets[m->pressed];
    if (wd->kind == W_SLIDER) {
        double v = slider_at(wd, m->px);
        if (v != m->drag) {
            m->drag = v;
            m->dirty = true;
        }
    } else if (wd->kind == W_CANVAS && m->point >= 0) {
        float x, v;
        canvas_value(wd, m->px, m->py, &x, &v);
        /* The point follows the pointer on the panel; the change is reported on release. */
        m->point = transfer_move_point(&m->model.transfer, (enum transfer_channel)m->channel,
                                       m->point, x, v);
        m->moved = true;
        m->dirty = true;
    }
}

static void trigger_up(struct menu *m)
{
    m->down = false;
    int i = m->pressed;
    m->pressed = -1;
    if (i < 0)
        return;
    struct widget *wd = &m->widgets[i];
    if (m->dragging) {
        m->dragging = false;
        if (wd->kind == W_SLIDER && m->drag != slider_value(m, wd))
            commit_slider(m, wd, m->drag);
        else if (wd->kind == W_CANVAS && m->moved) {
            m->model.transfer_on = true;
            m->changes |= MENU_CHANGE_TRANSFER;
        }
    } else if (hovered(m) == i && (wd->kind == W_BUTTON || wd->kind == W_TOGGLE)) {
        activate(m, wd);
    }
    m->dirty = true;
}

static void key(struct menu *m, enum input_key k)
{
    switch (k) {
    case INPUT_KEY_PLAY:
        m->model.playing = !m->model.playing;
        m->changes |= MENU_CHANGE_PLAYBACK;
        break;
    case INPUT_KEY_STEP_BACK:
        step_by(m, -1);
        break;
    case INPUT_KEY_STEP_FORWARD:
        step_by(m, 1);
        break;
    case INPUT_KEY_MENU:
        menu_set_visible(m, !m->visible);
        break;
    case INPUT_KEY_PAGE_NEXT:
        menu_set_page(m, (enum menu_page)((m->page + 1) % MENU_PAGE_COUNT));
        break;
    case INPUT_KEY_PAGE_PREV:
        menu_set_page(m, (enum menu_page)((m->page + MENU_PAGE_COUNT - 1) % MENU_PAGE_COUNT));
        break;
    case INPUT_KEY_PROBE:
        m->model.probe_on = !m->model.probe_on;
        m->changes |= MENU_CHANGE_PROBE;
        break;
    default: /* navigation, the sun, quitting: not the menu's */
        return;
    }
    m->dirty = true;
}

void menu_handle(struct menu *m, const struct input_event *e)
{
    if (m->dirty)
        layout(m);
    int before = hovered(m);
    switch (e->type) {
    case INPUT_POSE:
        memcpy(m->ray_o, e->position, sizeof(m->ray_o));
        memcpy(m->ray_d, e->direction, sizeof(m->ray_d));
        m->have_ray = true;
        update_hit(m);
        pointer_moved(m);
        break;
    case INPUT_AIM: {
        float p[3];
        if (!menu_widget_point(m, e->target, e->u, e->v, p)) {
            log_warn("menu: no widget \"%s\" on the %s page", e->target, page_names[m->page]);
            break;
        }
        for (int i = 0; i < 3; i++) {
            m->ray_o[i] = p[i] + 0.5f * m->width * m->normal[i];
            m->ray_d[i] = -m->normal[i];
        }
        m->have_ray = true;
        update_hit(m);
        pointer_moved(m);
        break;
    }
    case INPUT_BUTTON:
        if (e->button == INPUT_BUTTON_MENU && e->down)
            menu_set_visible(m, !m->visible);
        else if (e->button == INPUT_BUTTON_RESET && e->down)
            m->changes |= MENU_ACTION_RESET_VIEW;
        else if (e->button == INPUT_BUTTON_TRIGGER && m->visible) {
            if (e->down)
                trigger_down(m);
            else
                trigger_up(m);
        }
        break;
    case INPUT_KEY:
        key(m, e->key);
        break;
    case INPUT_AXIS:
    case INPUT_DRAG:
    case INPUT_SCROLL:
        break;
    }
    if (hovered(m) != before)
        m->dirty = true;
}

unsigned menu_take_changes(struct menu *m)
{
    unsigned c = m->changes;
    m->changes = 0;
    if (c)
        m->dirty = true;
    return c;
}
